"""The solve-time coarse-mesh warning (``Problem.check_element``) on every solve path: a scenario
run (``scenario.run``, the ``core-se3 run`` command) drives the solvers itself, not through
``Problem.solve`` (review finding; the test fails on the code before)."""
import warnings

import pytest

from core_se3 import scenario
from core_se3.catalogue import shell_course as sc
from core_se3.errors import ElementWarning

pytestmark = pytest.mark.core


@pytest.mark.parametrize("control", ["load", "linear", "arclength"])
def test_a_scenario_run_of_the_coarse_thin_roof_warns_like_problem_solve(control, tmp_path):
    # the roof 2x2 at R/h 1e4 is 10.9 times its converged deflection: Problem.solve warns, and
    # scenario.run (core-se3 run) was silent for every control
    doc = sc.scenario_doc("scordelis-lo", 2, 25.0 / 1e4)
    doc.setdefault("solver", {})["control"] = control
    if control != "linear":
        doc["solver"]["lam_end"] = 1e-3
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scenario.run(scenario.from_dict(doc), str(tmp_path / control))
    assert sum(issubclass(w.category, ElementWarning) for w in caught) == 1


def test_a_warm_started_sweep_point_warns_too(tmp_path):
    # a sweep over the thickness of the roof 2x2: R/h 1e2 (no warning) then 1e4 (10.9 times its
    # deflection), the thin point warm started by a Newton solve that skips Problem.solve: it
    # was silent
    doc = sc.scenario_doc("scordelis-lo", 2, 25.0 / 1e2)
    doc.setdefault("solver", {}).update(lam_end=1e-3, steps=1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = scenario.sweep(scenario.from_dict(doc), {"material.h": [0.25, 0.0025]}, out=str(tmp_path),
                             plot=False)
    assert [r["warm"] for r in res.rows] == [False, True]
    assert sum(issubclass(w.category, ElementWarning) for w in caught) == 1
