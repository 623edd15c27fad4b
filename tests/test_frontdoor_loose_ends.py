"""The front door's loose ends of the sixth review (what reaches a user through a scenario file or
the Python API and was said late, wrongly or not at all); each test fails on the code before its
fix.  (Series files: tests/test_io.py; result documents: tests/test_result_outputs.py; a Problem's
linear solver: tests/test_solver.py.)
"""
import copy
import warnings

import pytest

from core_se3 import scenario
from core_se3.errors import ScenarioError

QUIET = {"vtu": False, "plots": False, "picture": False}
STRIP = {"name": "strip", "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
         "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
         "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}],
         "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": 1}, "output": dict(QUIET)}


def doc(**sections):
    d = copy.deepcopy(STRIP)
    d.update(copy.deepcopy(sections))
    return d


def load(d):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return scenario.from_dict(d, file="s.toml")


def test_a_linear_solver_this_machine_lacks_is_named_at_its_key(monkeypatch):
    """[solver] linear_solver = "mumps" where petsc4py is missing (the NumPy 2 environment) was
    refused only when the solve began ('solver 'mumps' needs petsc4py'), after the set-up; the
    Problem now refuses it when made, and the scenario names [solver.linear_solver] (not
    [material], where the Problem's other refusals go) and the choices on this machine."""
    from core_se3.model.solving import LINEAR_SOLVERS
    monkeypatch.setitem(LINEAR_SOLVERS, "mumps", lambda: "needs petsc4py, not installed here")
    with pytest.raises(ScenarioError, match=r"\[solver.linear_solver\]: linear_solver 'mumps' needs petsc4py, not "
                                            r"installed here; the choices on this machine: auto, banded, superlu"):
        load(doc(solver={"steps": 1, "linear_solver": "mumps"}))
