"""The scenario front door's leftovers of the last review: ``run --check`` of a [sweep], ``sweep
--resume`` where there is nothing to resume, and the findings of an adversarial pass over the
TOML front door; each test fails on the code before its fix.  (A magnet in a zero applied field:
tests/test_magnetics.py; the residual's force and moment parts: tests/test_result_outputs.py.)
"""
import copy
import csv
import json
import os
import warnings

import pytest

from core_se3 import cli, scenario
from core_se3.errors import CheckpointError, ScenarioError

QUIET = {"vtu": False, "plots": False, "picture": False}
STRIP = {"name": "strip", "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
         "edges": {"mid": {"box": {"x": [5.0, 5.0]}}},
         "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
         "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}],
         "probes": [{"name": "mid", "edge": "mid"}], "solver": {"steps": 1}, "output": dict(QUIET)}


def doc(**sections):
    d = copy.deepcopy(STRIP)
    d.update(copy.deepcopy(sections))
    return d


def write(tmp_path, d, name="s.toml"):
    p = tmp_path / name
    p.write_text(scenario.dumps(d))
    return str(p)


def load(d):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return scenario.from_dict(d, file="s.toml")


# ================================================================== (a) run --check of a [sweep]
def test_run_check_validates_every_sweep_value(tmp_path, capsys):
    """``run --check`` passed (exit 0, 'valid') a [sweep] whose second value of material.nu is 0.7,
    which ``core-se3 sweep`` then refused; now --check refuses it with the sweep's message."""
    path = write(tmp_path, doc(sweep={"material.nu": [0.3, 0.7]}))
    assert cli.main(["run", path, "--check", "-q"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == (f"error: {path}: [sweep.material.nu]: the swept value 0.7 of material.nu: expected a "
                           "number < 0.5, got 0.7")
    assert cli.main(["sweep", path, "--out", str(tmp_path / "sw"), "-q"]) == 2      # the sweep's own verdict
    assert capsys.readouterr().err == err and not os.path.exists(tmp_path / "sw")


def test_run_check_and_sweep_validate_every_point_of_the_grid(tmp_path, capsys):
    """Values valid one by one may not be together: nx = 2 has no node at x = 2.5.  --check passed
    it, and the sweep ran three of its four points, then stopped with '[edges.mid]: selects no
    nodes' (no point named), sweep.json left 'running' with 'rows': 0 beside a CSV of 3 rows.
    Now both refuse the point before anything runs, naming it."""
    path = write(tmp_path, doc(sweep={"mesh.nx": [4, 2], "edges.mid.box.x": [[5.0, 5.0], [2.5, 2.5]]}))
    msg = (f"error: {path}: [sweep]: the swept point mesh.nx = 2, edges.mid.box.x = [2.5, 2.5]: [edges.mid]: "
           "selects no nodes")
    assert cli.main(["run", path, "--check", "-q"]) == 2
    assert capsys.readouterr().err.strip() == msg
    assert cli.main(["sweep", path, "--out", str(tmp_path / "sw"), "-q"]) == 2
    assert capsys.readouterr().err.strip() == msg and not os.path.exists(tmp_path / "sw")
    with pytest.raises(ScenarioError, match=r"\[--set\]: the swept point mesh.nx = 2, edges.mid.box.x"):
        scenario.check_sweep(load(doc()), {"mesh.nx": [4, 2], "edges.mid.box.x": [[5.0, 5.0], [2.5, 2.5]]})


def test_run_check_of_a_valid_sweep_says_its_points(tmp_path, capsys):
    path = write(tmp_path, doc(sweep={"mesh.nx": [4, 8], "material.E": [1e6, 2e6, 3e6]}))
    assert cli.main(["run", path, "--check"]) == 0
    assert "sweep: 6 point(s) of mesh.nx, material.E valid" in capsys.readouterr().out
    grid, points = scenario.check_sweep(load(doc(sweep={"mesh.nx": [4, 8], "material.E": [1e6, 2e6, 3e6]})))
    assert list(grid) == ["mesh.nx", "material.E"] and len(points) == 6 and points[1] == (4, 2e6)


# ================================================================== (b) --resume with nothing to resume
def test_sweep_resume_where_there_is_no_sweep_is_refused(tmp_path, capsys):
    """``sweep --resume`` into a directory that does not exist, or holds no sweep, started a fresh
    sweep silently (exit 0: a misspelt --out ran the whole grid again, elsewhere); ``run --resume``
    refused, but created the directory.  Now both refuse, naming the directory, and create nothing."""
    path = write(tmp_path, doc())
    for cmd, extra in (("run", []), ("sweep", ["--set", "material.E=1e6,2e6"])):
        new = tmp_path / f"new-{cmd}"
        assert cli.main([cmd, path, "--resume", "--out", str(new), "-q", *extra]) == 2
        err = capsys.readouterr().err
        assert f"nothing to resume: --out '{new}' does not exist (no earlier {cmd} there)" in err, err
        assert not os.path.exists(new)
    empty = tmp_path / "empty"
    empty.mkdir()
    assert cli.main(["sweep", path, "--resume", "--out", str(empty), "-q", "--set", "material.E=1e6,2e6"]) == 2
    assert f"nothing to resume: {empty} holds no sweep" in capsys.readouterr().err
    assert not os.path.exists(empty / "sweep.csv")
    with pytest.raises(CheckpointError, match="nothing to resume"):
        scenario.sweep(load(doc()), {"material.E": [1e6]}, out=str(tmp_path / "py"), plot=False, resume=True)


def test_sweep_resume_of_a_sweep_stopped_before_its_first_row_starts_over(tmp_path):
    """As a run stopped before its first checkpoint: the earlier sweep's files are there, no
    sweep.npz yet; the resume runs the grid from its first point."""
    from core_se3.io.rundir import RunDirectory
    from core_se3.scenario.sweep_files import SWEEP_FILES
    out = str(tmp_path / "sw")
    with RunDirectory(out, "sweep", SWEEP_FILES).claim() as rd:      # what a sweep killed in its first run left
        with open(rd.file("sweep.json"), "w") as fh:
            json.dump({"status": "running", "rows": 0}, fh)
    res = scenario.sweep(load(doc()), {"material.E": [1e6, 2e6]}, out=out, plot=False, resume=True)
    assert [r["status"] for r in res.rows] == ["complete", "complete"]
    assert len(list(csv.DictReader(open(os.path.join(out, "sweep.csv"))))) == 2
