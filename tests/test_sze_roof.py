"""Sze, Liu & Lo (2004) s3.8, the hinged cylindrical roof under a central point load
(issue 6, P0 and the 6.35 roof of P2), traced by arc length.

Reference: core_se3/data/literature.json ``sze3.8a_hinged_roof`` (h = 12.7, P_max = 3000 from
two sources) and ``sze3.8d_hinged_roof`` (h = 6.35, P_max marked unverified).  Model: the
quarter roof (symmetry supports, load P/4 at the corner), cases sze-hinged-roof and
sze-hinged-roof-6.35 in core_se3/cases_sze.py.  Measure: the largest distance of a computed
point to the table polyline in (P/P_max, -W_C/max(-W_C)).

Full meshes (16x16 quarter = 32x32 roof, benchmarks/sze.py) give 0.97 %; the 8x8 quarter used
here 2.44 %, 12x12 1.44 %, 24x24 0.52 % (the error falls with the mesh, ~h^1.3): on 8x8 the
worst point is the end of the stiff far branch, where P/P_max rises steeply with W_C.
The 6.35 roof's full mesh is the quarter 32x32 (1.72 % on the stated, unverified scale
P_max = 3000 of s3.8a; 3.38 % on 16x16, 7.35 % on 8x8; benchmarks/results/sze.md, 2026-12-05).
"""
import numpy as np
import pytest

from core_se3 import catalogue
from core_se3.catalogue.family_sze import curve_deviation, table_curves
from core_se3.catalogue.measures import point_curve_distances
from core_se3.catalogue import get_case
from core_se3.catalogue.references import literature_entry


@pytest.fixture(scope="module")
def roof127():
    doc, res, prob = catalogue.run_case("sze-hinged-roof", mesh=(8, 8))
    return doc, res, prob


def test_point_curve_distance():
    """Distances to a polyline: inside a segment, past a vertex, beyond the ends, on it."""
    curve = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    pts = np.array([[0.5, 0.1], [1.2, 0.5], [2.0, 2.0], [-1.0, 0.0], [1.0, 0.25]])
    assert np.allclose(point_curve_distances(pts, curve), [0.1, 0.2, np.sqrt(2.0), 1.0, 0.0])
    assert np.isclose(point_curve_distances([[3.0, 4.0]], [[0.0, 0.0]])[0], 5.0)


def test_table_points_have_zero_deviation():
    """The table itself, fed through the measure, deviates by 0 (scaling and sign wiring)."""
    case = get_case("sze-hinged-roof")
    (col, lam, u), = table_curves(case)
    probes = [{"C": np.array([0.0, 0.0, -w])} for w in u]
    dev, per, info = curve_deviation(case, lam, probes)
    assert dev < 1e-15 and info[0]["u_max"] == 29.374


def test_hinged_roof_12p7_curve_within_3_percent(roof127):
    """h = 12.7 on the 8x8 quarter: the path snaps through (lam rises to the upper limit point,
    falls to the lower one, rises again) and ends at the table's last deflection 29.374.
    Deviation bar 3 % (the acceptance bar; measured 2.44 % on this coarse mesh, 0.97 % at the
    full 16x16 mesh, see the module docstring)."""
    doc, res, prob = roof127
    ref = doc["reference"]
    assert ref["entry"] == "sze3.8a_hinged_roof" and ref["P_max"] == 3000.0
    assert ref["deviation"] <= 0.03, ref["deviation"]
    w = np.array([-s["probes"]["C"]["u"][2] for s in doc["steps"]])
    assert abs(w[-1] - 29.374) < 1e-8
    assert max(s["balance_error"] for s in doc["steps"]) < 1e-8


def test_hinged_roof_12p7_limit_points(roof127):
    """Both limit points are found (negative eigenvalues 0 -> 1 -> 0) at P/P_max = 0.7436
    and 0.1705 (8x8, parabolic estimate inside a bracket of one arc-length step), against the table's largest and smallest tabulated values 0.7421 and
    0.1729 (sampled every ~1 in W_C, so they are within ~0.5 % of the true extremes).
    Bars 1 % (upper) and 3 % (lower: the coarse mesh's post-buckling branch is the least
    accurate part, as for the curve)."""
    doc, res, prob = roof127
    cps = res.critical_points
    assert [c.kind for c in cps] == ["limit", "limit"]
    assert [c.negative_eigenvalues for c in cps] == [(0, 1), (1, 0)]
    e = literature_entry("sze3.8a_hinged_roof")
    lam = np.array(e["P_over_Pmax"])
    upper, lower = lam[:15].max(), lam[5:30].min()
    assert abs(cps[0].lam - upper) < 0.01 * upper, cps[0].lam
    assert abs(cps[1].lam - lower) < 0.03 * lower, cps[1].lam
    # the stability flags of the recorded steps: unstable exactly between the two
    neg = [s["stability"]["negative_eigenvalues"] for s in doc["steps"]]
    assert neg[cps[0].step - 1] == 0 and neg[cps[0].step] == 1
    assert neg[cps[1].step - 1] == 1 and neg[cps[1].step] == 0


def test_quarter_model_equals_full_roof():
    """Symmetry supports: the 4x4 quarter and the 8x8 full roof (same nodes on the quarter)
    give the same central deflection at P = 0.6 P_max (load control, 3 steps, before the limit
    point) to 1e-8 relative: the symmetry planes' body-frame fixes are exact."""
    case = get_case("sze-hinged-roof")
    w = []
    for full, mesh in ((0.0, (4, 4)), (1.0, (8, 8))):
        p = catalogue.case_params(case, {"full": full})
        prob = catalogue.build_problem(case, p, mesh)
        res = prob.solve(steps=3, lam_end=0.6)
        w.append(-res.final.probes["C"]["u"][2])
    assert w[0] > 5.0                                   # well into the nonlinear range
    assert abs(w[0] - w[1]) < 1e-8 * w[0], w


def test_hinged_roof_6p35_snap_back():
    """h = 6.35 (8x8 quarter): arc length follows the snap-through AND the snap-back (the load
    turns negative and the deflection W_C decreases along the path before it grows again).
    P_max of this table is unverified (no second source found), so the load axis has no bar.
    The deflection-only features do not depend on P_max: the table's W_C reverses at 17.008
    and turns forward again at 14.451 (bars 3 %: measured 16.94 and 14.53 at the step points);
    the ratio of the two limit loads, -0.1288/0.1953 = -0.660 in the table, is also free of
    P_max (measured -0.651, bar 3 %)."""
    doc, res, prob = catalogue.run_case("sze-hinged-roof-6.35", mesh=(8, 8))
    w = np.array([-s["probes"]["C"]["u"][2] for s in doc["steps"]])
    lam = np.array([s["load_factor"] for s in doc["steps"]])
    assert abs(w[-1] - 38.45) < 1e-8
    back = np.nonzero(np.diff(w) < 0)[0]
    assert len(back) >= 2                                # W_C decreases over several steps
    w_rev, w_fwd = w[back[0]], w[back[-1] + 1]
    assert abs(w_rev - 17.008) < 0.03 * 17.008, w_rev
    assert abs(w_fwd - 14.451) < 0.03 * 14.451, w_fwd
    assert lam.min() < 0
    cps = [c for c in res.critical_points if c.kind == "limit"]
    assert len(cps) == 2
    ratio = cps[1].lam / cps[0].lam
    assert abs(ratio - (-0.1288 / 0.1953)) < 0.03 * 0.660, ratio
    assert doc["reference"]["unverified"]               # reported, flagged


@pytest.mark.parametrize("s", [1e-3, 1e3])
def test_roof_in_other_units_stops_at_the_same_point(roof127, s):
    """The 12.7 roof with every length times s (mm -> m: s = 1e-3, E x 1e6; m -> km: s = 1e3)
    is the same problem: the path stops at the table's end displacement times s
    (``stop_length_ratio``: the rise's ratio), in as many steps and iterations, with the
    displacements times s (observed 1.5e-14, load factors to 3e-12).  Before, the stop stayed
    29.374 in any unit: mm -> m ran to max_steps (401 steps, 18.6 times the displacement), m -> km
    stopped after 2 steps."""
    doc0, res0, prob0 = roof127
    p = catalogue.case_params(get_case("sze-hinged-roof"), None)
    ov = dict(E=p["E"] / s ** 2, h=p["h"] * s, R=p["R"] * s, L=p["L"] * s)
    doc, res, prob = catalogue.run_case("sze-hinged-roof", mesh=(8, 8), overrides=ov)
    assert len(res.steps) == len(res0.steps)
    assert [st.iterations for st in res.steps] == [st.iterations for st in res0.steps]
    u0 = res0.final.g[:, :3, 3] - prob0.mesh.g0[:, :3, 3]
    u = res.final.g[:, :3, 3] - prob.mesh.g0[:, :3, 3]
    assert np.abs(u / s - u0).max() <= 1e-10 * np.abs(u0).max()
    lam0, lam = [st.load_factor for st in res0.steps], [st.load_factor for st in res.steps]
    assert np.abs(np.subtract(lam, lam0)).max() <= 1e-9
