"""DOLFINx side of the comparison harness (issue 5): the fenicsx_ref adapter and its tangent check.

The roll-up to k = 1/4 (tip rotation pi/2) has the exact answer of a circle of curvature M/EI
(core_se3/data/elastica.json, 2_pure_bending_rollup_out_of_plane); fenicsx_ref's Naghdi strain
couples bending to stretch at O((h kappa)^2), so 4x1 Q2 elements are within 1 % of it.
"""
from math import pi

import numpy as np

from comparison.metrics import circle_tip, path_distance
from comparison.models import fenicsx_available, run_core, run_fenicsx


def test_adapter_matches_circle_and_core_at_the_same_load_factors():
    assert fenicsx_available()[0]
    rf = run_fenicsx("rollup", (4, 1), dict(k=0.25), 2, tangent_check=True)
    rc = run_core("rollup", (8, 2), dict(k=0.25), 2)
    assert rf["status"] == rc["status"] == "ok"
    assert rf["lams"] == rc["lams"] == [0.5, 1.0]
    u, v, _ = circle_tip(10.0, np.array([0.5, 1.0]) * 0.25 * 2 * pi / 10.0)
    ref = np.column_stack([u, v])
    scale = np.linalg.norm(ref, axis=1).max()
    assert path_distance(np.array(rf["u"])[:, [0, 2]], ref, scale)[0] < 0.01
    assert path_distance(rc["u"], rf["u"])[0] < 0.01
    # the assembled UFL Jacobian against central differences of the residual
    assert rf["tangent_check"] < 1e-5
    assert rf["timings"]["jit"] >= 0.0 and rf["n_dofs"] > 0
