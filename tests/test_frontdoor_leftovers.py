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
