"""The tutorial (examples/tutorial.py) is a literate script whose asserts are its checks:
elastica agreement of the cantilever, identical Python/scenario results, error messages that
name the key, interrupted-and-resumed run, resultants against statics, a magnetic strip."""
import os
import runpy
import sys

TUTORIAL = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "examples", "tutorial.py")


def test_tutorial_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", [TUTORIAL, str(tmp_path)])
    runpy.run_path(TUTORIAL, run_name="__main__")
    out = capsys.readouterr().out
    assert "difference 0.064 %" in out                       # README: cantilever-shear 16x1, 0.064 %
    assert "[material.nu]: expected a number < 0.5, got 0.5" in out
    for f in ("python-vtu/series.pvd", "python-shell.png", "cantilever/results.json",
              "cantilever/vtu/series.pvd", "cantilever/shell.png"):
        assert os.path.exists(tmp_path / f), f
