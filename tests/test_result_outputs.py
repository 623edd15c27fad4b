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
