"""The solve-time coarse-mesh warning (``Problem.check_element``) on every solve path: a scenario
run (``scenario.run``, the ``core-se3 run`` command) drives the solvers itself, not through
``Problem.solve`` (review finding; the test fails on the code before), and a design's equilibria
(``design.follow``, ``Design.optimise``), which follow the path in the variables as a material
variable thins the shell: checked once per new design point, said once per design run."""
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


# ---------------------------------------------------------------- design runs -------------
# the roof 2x2 (R 25): phi^3 L / h = 1.78 along its free edge at h = 0.25, 0.444 / h in general,
# so the mesh turns coarse below h = 0.222 (the roof 2x2 at R/h 1e4: 10.9 times its deflection)
COARSE_BELOW = 0.4442227355845404 / 2.0


def _roof_design(h0, h_target, lower):
    """A design of the roof 2x2's thickness (one value, all elements) that puts the free edge's
    middle (the node deflecting most) where the roof of thickness h_target has it (lam 0.1)."""
    import numpy as np
    from core_se3.design import Design, MaterialVariable, NodePosition, Pose, Target
    q, _ = sc.scordelis_lo(2, h=h_target)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        z = q.solve(steps=2, lam_end=0.1).final.g[:, 2, 3]
    p, _ = sc.scordelis_lo(2, h=h0)
    a = int(np.argmin(z - p.mesh.g0[:, 2, 3]))
    h = MaterialVariable(p, [np.arange(p.mesh.n_elements)], "h", lower=lower, upper=0.3)
    target = Target(NodePosition(p, [a]), components=[2], value=[z[a]])
    return Design(p, [h], [Pose("roof", [target], lam=0.1)])


def _element_warnings(run):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = run()
    return out, [str(w.message) for w in caught if issubclass(w.category, ElementWarning)]


def test_a_design_that_thins_the_roof_past_the_coarse_limit_warns_once():
    # the optimiser takes the thickness from 0.25 (fine) to 0.15 (phi^3 L / h = 3.0): the
    # design's equilibria follow the path from the last one without Problem.solve, so the
    # element was never checked again and the run was silent; now the first coarse point is
    # named, and the later coarse points of the run (four here) say nothing more
    d = _roof_design(0.25, 0.15, lower=0.12)
    r, said = _element_warnings(lambda: d.optimise(tolerance=1e-6, max_iter=30))
    assert abs(r.x[0] - 0.15) < 1e-4
    coarse = [e["x"][0] for e in r.history if e["x"][0] < COARSE_BELOW]
    assert len(coarse) >= 2
    assert len(said) == 1
    assert "phi^3 L / h" in said[0] and "design point h[0] = " in said[0]
    first = float(said[0].split("design point h[0] = ")[1].split()[0])
    assert first < COARSE_BELOW


def test_a_design_that_stays_fine_is_silent():
    d = _roof_design(0.28, 0.24, lower=COARSE_BELOW * 1.02)
    r, said = _element_warnings(lambda: d.optimise(tolerance=1e-6, max_iter=30))
    assert abs(r.x[0] - 0.24) < 1e-4
    assert said == []


def _thin_roof_follow():
    import numpy as np
    from core_se3.design import MaterialVariable, solve_flat
    p, _ = sc.scordelis_lo(2, h=0.25)
    h = MaterialVariable(p, [np.arange(p.mesh.n_elements)], "h")
    st, said = _element_warnings(lambda: solve_flat(p, [h], [np.array([0.25])], lam=0.01))
    assert said == []
    return p, h, st


def test_follow_checks_the_point_it_reaches():
    # follow (the design's warm-started equilibrium) from h = 0.25 (1.78) to 0.1 (4.4): silent before
    import numpy as np
    from core_se3.design import follow
    p, h, st = _thin_roof_follow()
    _, said = _element_warnings(lambda: follow(p, [h], [np.array([0.1])], st))
    assert len(said) == 1 and "design point h[0] = 0.1 " in said[0]


def test_a_shared_element_check_says_it_once_along_a_path():
    import numpy as np
    from core_se3.design import ElementCheck, follow
    p, h, st = _thin_roof_follow()
    check = ElementCheck()

    def path():
        s = st
        for x in (0.23, 0.1, 0.05, 0.3, 0.04):          # 1.93, then 4.4, 8.9, 1.48, 11
            s, _ = follow(p, [h], [np.array([x])], s, check=check)
    _, said = _element_warnings(path)
    assert len(said) == 1 and "design point h[0] = 0.1 " in said[0]
    assert check.said == {ElementCheck.CAUSE: "h[0] = 0.1"}
