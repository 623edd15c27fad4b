"""The end check in scenario runs (``core-se3 run``): load control whose step crosses an even
number of eigenvalues says so, as ``Problem.solve`` does (issue 29).

Found by reading scenario/runner.py: it drove ``newton_steps`` and never called the end check,
so a scenario's ``end_check = true`` (the default) did nothing.  The compressed cantilever strip
(10 x 1 x 0.1, E 1.2e6, nu 0; Euler's loads (2n - 1)^2 pi^2 EI / (4 L^2) = 2.47, 22.2, 61.7) loaded
to 30 in one step passes the first two: det K's sign is unchanged, and the run ended "complete" on
the straight, twice unstable state.
"""
import json
import os

import pytest

from core_se3 import scenario
from core_se3.errors import ConvergenceError

COLUMN = {"name": "column", "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 10, "ny": 1},
          "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
          "loads": [{"type": "edge_force", "edge": "x1", "force": [-30.0, 0.0, 0.0]}],
          "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": 1},
          "output": {"vtu": False, "plots": False, "picture": False}}


def _run(tmp_path, **solver):
    doc = dict(COLUMN, solver=dict(COLUMN["solver"], **solver))
    path = tmp_path / "column.toml"
    path.write_text(scenario.dumps(doc))
    out = tmp_path / "out"
    try:
        scenario.run(scenario.load(path), out=str(out))
        err = None
    except ConvergenceError as exc:
        err = str(exc)
    with open(out / "results.json") as f:
        return err, json.load(f), sorted(os.listdir(out))


def test_a_scenario_step_over_two_buckling_loads_stops_naming_it(tmp_path):
    err, doc, files = _run(tmp_path)
    assert err is not None and "rose from 0 to 2" in err and "between load factors 0 and 1" in err
    assert "inertia_check" in err and "step 1" in err
    assert doc["status"] == "failed" and "rose from 0 to 2" in doc["error"]
    assert len(doc["steps"]) == 2 and "checkpoint.npz" in files        # what was computed is kept


def test_without_the_end_check_the_old_answer_completes(tmp_path):
    """Negative control: the state the run reached is a converged equilibrium (the straight strip)."""
    err, doc, _ = _run(tmp_path, end_check=False)
    assert err is None and doc["status"] == "complete"


@pytest.mark.parametrize("steps", [2, 10])
def test_smaller_steps_stop_at_the_located_bifurcation(tmp_path, steps):
    err, doc, _ = _run(tmp_path, steps=steps)
    assert "det K changed sign" in err and "at 0.08239746" in err      # Euler: 2.467 / 30 = 0.0822 and doc["status"] == "failed"
