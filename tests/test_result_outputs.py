"""The numbers a run publishes, checked against exact solutions and against each other: sweep
rows (warm and cold), ..."""
import numpy as np
import pytest

from core_se3 import scenario

pytestmark = pytest.mark.core

E, H, L, W = 1.2e6, 0.1, 10.0, 1.0
M_PI = np.pi * E * W * H ** 3 / 12 / L          # the end moment that rolls the strip's tip by pi


def _strip(moment, steps):
    return scenario.from_dict({"mesh": {"generator": "rectangle", "L": L, "width": W, "nx": 8, "ny": 1},
                               "material": {"E": E, "nu": 0.0, "h": H},
                               "supports": [{"type": "clamp", "edge": "x0"}],
                               "loads": [{"type": "edge_moment", "edge": "x1", "moment": [0.0, -moment, 0.0]}],
                               "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": steps}})


def test_a_warm_sweep_row_keeps_the_turns_of_a_roll_up(tmp_path):
    """Pure bending, nu = 0: the tip turns by M L / (E I) exactly, 1.2 pi and 1.3 pi.  The warm
    row (one Newton solve from the 1.2 pi state) read 0.7 pi = 2 pi - 1.3 pi before: its probe
    rotation was unwrapped from zero, the cold row's along its load steps."""
    grid = {"loads[0].moment[1]": [-1.2 * M_PI, -1.3 * M_PI]}
    scn = _strip(1.2 * M_PI, 12)
    warm = scenario.sweep(scn, grid, out=str(tmp_path / "warm"), plot=False).rows
    cold = scenario.sweep(scn, grid, out=str(tmp_path / "cold"), plot=False, warm=False).rows
    assert [r["warm"] for r in warm] == [False, True] and not any(r["warm"] for r in cold)
    for rows in (warm, cold):
        assert [r["tip.rotation"] for r in rows] == [pytest.approx(1.2 * np.pi, rel=1e-9),
                                                      pytest.approx(1.3 * np.pi, rel=1e-9)]
        np.testing.assert_allclose(rows[1]["tip.rotation_vector"], [0.0, -1.3 * np.pi, 0.0], atol=1e-9)


def test_a_solve_continued_from_a_step_keeps_its_probes_turns():
    """Pure bending (exact): rolled to 1.2 pi, then continued to 1.3 pi from the stored step
    (``g_init=StepResult``): 1.2 pi and 1.3 pi, as one solve to 1.3 pi reads; bare frames still
    start from the angle modulo 2 pi (0.8 pi and 0.7 pi, said in the docstring).  Before, a
    StepResult was refused with a bare TypeError (float() of a StepResult)."""
    from core_se3 import Material, Problem, mesh
    p = Problem(mesh.rectangle(L, W, 8, 1), Material(E, 0.0, H))
    p.clamp("x0")
    p.add_edge_moment("x1", (0.0, -M_PI, 0.0))
    p.add_probe("tip")
    first = p.solve(steps=12, lam_end=1.2).final
    on = p.solve(steps=1, lam_start=1.2, lam_end=1.3, g_init=first)
    assert [s.probes["tip"]["rotation_angle"] / np.pi for s in on.steps] == [pytest.approx(1.2, rel=1e-9),
                                                                             pytest.approx(1.3, rel=1e-9)]
    np.testing.assert_allclose(on.final.probes["tip"]["rotation_vector"], [0.0, -1.3 * np.pi, 0.0], atol=1e-9)
