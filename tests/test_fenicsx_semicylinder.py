"""fenicsx_ref: Sze et al. (2004) s3.7, the clamped semi-cylinder pinched at the crown of its free
edge (isotropic), and the curve-distance measure it is judged by.

Case: ``core_se3.cases['sze-semicylinder']`` (R = 1.016, L = 3.048, h = 0.03, E = 2.0685e7,
nu = 0.3; edge y0 clamped; longitudinal edges u_z = 0 and rotation about the axis fixed; dead
point load P along -z at (0, L, R), P to P_max = 2000).  Reference: core_se3/data/literature.json,
``sze3.7_clamped_semicylinder_point_load``, columns ``P_over_Pmax`` and
``minus_W_A_x100_isotropic`` (x 0.01 = -u_z at the crown; Abaqus S4R, 40x40).

Measure (issue acceptance, at most 2 %): the largest distance from each computed point
(P_k/P_max, u_k/u_max) to the piecewise-linear tabulated curve, u_max = the table's largest
displacement (1.71505).

Measured (Q2, PSRI, k_s = 1, the case's 40 uniform load steps; table-loads-only in brackets):

    mesh    8x8      12x12    16x16           24x24    32x32    40x40
    error   2.63e-2  9.8e-3   5.0e-3 (3.2e-3) 6.0e-3   6.2e-3   6.3e-3 (3.6e-3)
    -u_z(P_max)  1.6741  1.7064  1.7094  1.7147  1.7162  1.7168     (table: 1.71505)

The converged ~6e-3 is reached between table entries (P = 750: the table's linear interpolation
across the steep stretch 0.35..0.4 P_max); at the table loads themselves it is 3.6e-3.
k_s = 5/6 on 16x16: 5.2e-3.
"""
from math import sqrt

import numpy as np

import dolfinx  # noqa: F401  -- must fail (not skip) without DOLFINx

from fenicsx_ref import run_case
from core_se3.catalogue.measures import point_curve_distances

CASE = "sze-semicylinder"
ENTRY = "sze3.7_clamped_semicylinder_point_load"


def test_curve_distance():
    """Distances to a polyline: interior of a segment, past a vertex, beyond the ends, on it."""
    curve = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    pts = np.array([[0.5, 0.1], [1.2, 0.5], [2.0, 2.0], [-1.0, 0.0], [1.0, 0.25], [0.9, 0.05]])
    d = point_curve_distances(pts, curve)
    assert np.allclose(d, [0.1, 0.2, sqrt(2.0), 1.0, 0.0, 0.05], atol=1e-15)
    # repeated vertex (zero-length segment) and a one-point curve
    assert np.isclose(point_curve_distances([[0.5, -0.3]], [[0, 0], [0, 0], [1, 0]]).max(), 0.3)
    assert np.isclose(point_curve_distances([[3.0, 4.0]], [[0.0, 0.0]]).max(), 5.0)
    # a point exactly on the polyline between vertices of different slopes
    assert point_curve_distances([[0.25, 0.5]], [[0, 0], [0.5, 1.0], [1.0, 1.0]]).max() < 1e-15


def test_sze_semicylinder_16x16(record_property):
    """Acceptance: the curve distance is at most 2 % (measured 5.0e-3 on 16x16, the case's 40 load
    steps; the bar 1e-2 keeps a 2x margin and stays half the acceptance).  The end point
    -u_z(P_max) = 1.7094 is 0.33 % below the table's 1.71505 (bar 1 %), and the response stays
    symmetric about the plane x = 0 through the load (u_x at the crown ~ 1e-16)."""
    r = run_case(CASE, mesh=(16, 16))
    assert r["status"] == "ok"
    ref = r["reference"]
    assert ref["entry"] == ENTRY and ref["n_points"] == 40
    assert abs(ref["u_max"] - 1.71505) < 1e-12 and ref["P_max"] == 2000.0
    record_property("curve_distance_16x16", ref["error"])
    print(f"sze-semicylinder 16x16: curve distance {ref['error']:.3e} at P = {ref['error_at_load']}, "
          f"timings {r['timings']}")
    assert ref["error"] <= 0.02
    assert ref["error"] <= 1e-2
    last = r["steps"][-1]
    assert abs(last["load"]["value"] - 2000.0) < 1e-9
    crown = last["probes"]["crown"]["u"]
    assert abs(-crown[2] / 1.71505 - 1) < 1e-2
    assert max(abs(s["probes"]["crown"]["u"][0]) for s in r["steps"]) < 1e-10
