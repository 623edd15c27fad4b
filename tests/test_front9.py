"""front9: small front-door loose ends (the figure writer, design's output error, the annulus
mesh's minimum, overflowing meshes, a meant multi-turn angle in a scenario file)."""
import numpy as np
import pytest

pytestmark = pytest.mark.core


def test_sweep_and_design_plots_go_through_the_one_figure_writer(tmp_path, monkeypatch):
    """sweep_files.write_plot and design_runner's plots save through io.plots.save_figure (one
    copy of the atomic save; before, each kept its own atomic_path around savefig)."""
    pytest.importorskip("matplotlib")
    from core_se3.io import plots
    from core_se3.scenario import design_runner, sweep_files
    from core_se3.scenario.sweep import SweepResult
    saved = []
    real = plots.save_figure
    monkeypatch.setattr(plots, "save_figure", lambda fig, path, **kw: saved.append(path) or real(fig, path, **kw))
    monkeypatch.setattr(design_runner, "save_figure", plots.save_figure, raising=False)
    rows = [{"material.E": e, "status": "complete", "tip.uz": 1.0 / e} for e in (1.0, 2.0)]
    sweep_files.write_plot(str(tmp_path / "sweep.png"), SweepResult(["material.E"], rows), "t")
    history = [{"iteration": k, "objective": 1.0 / (k + 1), "gradient_norm": 0.1} for k in range(3)]
    design_runner._convergence_plot(str(tmp_path / "convergence.png"), history, "t")
    assert saved == [str(tmp_path / "sweep.png"), str(tmp_path / "convergence.png")]
    assert all(open(p, "rb").read(4)[1:] == b"PNG" for p in saved)


def test_design_output_error_says_which_files_were_written(tmp_path, monkeypatch, capsys):
    """A design whose convergence plot cannot be written (a full disk) said "the design's result
    is not written" though optimised.toml, the target plot and the VTU series were written: now
    the error line names those written and the ones not (the failed file, design.json)."""
    from test_design_scenario import BASE
    from core_se3.cli import main
    from core_se3.scenario import design_runner

    def full(path, *a):
        raise OSError(28, "No space left on device", str(path))
    monkeypatch.setattr(design_runner, "_convergence_plot", full)
    path = tmp_path / "strip.toml"
    path.write_text(BASE)
    out = tmp_path / "out"
    assert main(["design", str(path), "--out", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: cannot write the outputs") and "the design's result is not written" not in err
    written, not_written = err.split("; written: ")[1].split("; not written: ")
    assert str(out / "optimised.toml") in written and (out / "optimised.toml").exists()
    assert str(out / "convergence.png") in not_written and "design.json" in not_written
    assert not (out / "design.json").exists()


def test_an_annulus_of_too_few_elements_around_names_the_cause_and_the_minimum():
    """``bench run sze-slit-annular --mesh 4x2``: two elements around the slit ring span half a
    turn each, their corners on one line; the error said only 'quads ... degenerate'.  Now it
    names the count around and the minimum (3 for a full turn, 2 for half a turn)."""
    from core_se3 import mesh as M
    from core_se3.cli import main
    from core_se3.errors import MeshError
    with pytest.raises(MeshError, match=r"nt = 2 element\(s\) around 6.28319 rad span 180 degrees.*at least nt = 3"):
        M.annulus(6.0, 10.0, 2 * np.pi, 4, 2)
    with pytest.raises(MeshError, match=r"at least nt = 2"):
        M.annulus(6.0, 10.0, np.pi, 4, 1)
    m = M.annulus(6.0, 10.0, 2 * np.pi, 4, 3)                   # the minimum: 120 degrees each
    assert m.n_elements == 12
    assert main(["bench", "run", "sze-slit-annular", "--mesh", "4x2", "-q"]) == 2


@pytest.mark.parametrize("L", [1e300, 1e155])
def test_a_mesh_whose_lengths_overflow_says_so(L, tmp_path, capsys):
    """A strip of L = 1e300 (and 1e155: edge lengths sqrt(e.e) overflow from 1.3e154) was refused
    as 'quads ... degenerate ... nodes at one point (an edge of length 1)'; now as an overflow,
    in Python and from a scenario file (its key).  A mesh far from the origin keeps its round-off
    message (tests/test_mesh.py), and one of span 1e150 is accepted."""
    import warnings
    from core_se3 import mesh as M
    from core_se3.cli import main
    from core_se3.errors import MeshError
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(MeshError, match=r"the mesh spans 1e\+(300|155) \[length\], beyond 1e\+150: .*overflow"):
            M.rectangle(L, 1.0, 2, 1)
        assert M.rectangle(1e150, 1.0, 2, 1).n_elements == 2
    f = tmp_path / "big.toml"
    f.write_text(f'[mesh]\ngenerator = "rectangle"\nL = {L!r}\nwidth = 1.0\nnx = 2\nny = 1\n[material]\n'
                 'E = 1.0\nnu = 0.0\nh = 0.1\n[[supports]]\ntype = "clamp"\nedge = "x0"\n')
    assert main(["run", str(f), "--out", str(tmp_path / "o"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "[mesh]" in err and "overflow" in err and "degenerate" not in err


TURNING = """
units = "SI"
{meant}
[mesh]
generator = "rectangle"
L = 1.0
width = 0.2
nx = 2
ny = 1
[material]
E = 1e6
nu = 0.0
h = 0.01
[[supports]]
type = "clamp"
edge = "x0"
[fields.coil]
type = "uniform"
B = [0.0, 0.0, 0.01]
rotate = {{ axis = [0.0, 1.0, 0.0], angle = 62.8 }}
[[magnets]]
Br = [0.1, 0.0, 0.0]
"""


def test_a_meant_multi_turn_angle_is_said_once_and_can_be_said_meant():
    """A field turning 10 times (62.8 rad) warned as a ScenarioWarning at its key, plus twice as a
    bare AngleWarning whose hint (warnings.catch_warnings around the call) a file cannot follow,
    and nothing said it was meant.  Now: one ScenarioWarning naming the top-level key
    ``many_turns``; listed there, nothing is said (nor with --strict); a listed key that is no
    angle of the file is refused with the closest one."""
    import warnings
    from core_se3 import scenario
    from core_se3.errors import ScenarioError
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        scenario.loads(TURNING.format(meant=""))
    assert [type(w.message).__name__ for w in said] == ["ScenarioWarning"]
    assert 'many_turns = ["fields.coil.rotate.angle"]' in str(said[0].message)
    meant = TURNING.format(meant='many_turns = ["fields.coil.rotate.angle"]')
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        scn = scenario.loads(meant, strict=True)
        scn.load_numbers()
    assert said == [] and scn.warnings == []
    with pytest.warns(UserWarning, match="many_turns"):
        assert scn.fingerprint == scenario.loads(TURNING.format(meant="")).fingerprint      # no mechanics
    with pytest.raises(ScenarioError, match=r"\[many_turns\[0\]\]: 'fields.coil.rotate.angel' is not an angle.*"
                                            r"did you mean 'fields.coil.rotate.angle'"):
        scenario.loads(TURNING.format(meant='many_turns = ["fields.coil.rotate.angel"]'))
