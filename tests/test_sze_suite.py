"""Sze, Liu & Lo (2004) s3.3 (slit annular plate) and s3.7 (clamped semi-cylinder, isotropic)
with core_se3 (issue 6, P1), on coarse meshes.

References: core_se3/data/literature.json ``sze3.3_slit_annular_plate`` (Abaqus S4R, 10x80,
columns W_A at r = 6 and W_B at r = 10 of the lifted edge) and
``sze3.7_clamped_semicylinder_point_load`` (column minus_W_A_x100_isotropic, x 0.01).
Measure: the largest distance of a computed point to the table polyline in
(P/P_max, u/u_max), u_max per column (core_se3.bench_sze.curve_deviation).

Measured deviations (core-se3 bench run NAME --mesh ..., default element):

    sze-semicylinder   12x12 3.87 %   16x16 2.09 %   24x24 1.11 %   (table mesh 40x40: benchmarks)
    sze-slit-annular   6x30  2.01 %   8x40  1.31 %   10x80 0.77 %   (the table's mesh)

The semi-cylinder's error falls as ~h^1.6..2 (stiffer coarse meshes: the end deflection is
2.1 % low on 16x16), so its coarse bar is 2.5 % on 16x16; the annulus meets the 2 %
acceptance bar on 8x40, its test mesh (6x30 met it, 1.53 %, before the least-turn gauge of the
nodal frames removed the radial frames' defect, which had made the coarse mesh more flexible).
"""

import numpy as np
import pytest

from core_se3 import catalogue


def test_slit_annular_plate_8x40_within_2_percent():
    """Slit annulus, 8x40 (radial x around), arc length to P_max = 0.8: both curves within 2 %
    (measured W_A 1.31 %, W_B 1.04 %); end deflections within 2.5 % of the table's 13.891 and
    17.528 (measured 13.69 and 17.33, the coarse mesh is stiffer); equilibrium with reactions
    balancing the load to 1e-6 (the residual floor of this very flexible plate is ~1e-8).
    The 6x30 mesh this test took gives 2.01 % / 1.60 % since the element builds its frames in the
    least-turn gauge (docs/ELEMENTS.md, "Nodal frames"): before, the generator's radial frames,
    turning 0.21 rad per element, had made it more flexible (1.53 % / 1.24 %)."""
    doc, res, prob = catalogue.run_case("sze-slit-annular", mesh=(8, 40))
    ref = doc["reference"]
    assert ref["entry"] == "sze3.3_slit_annular_plate"
    assert ref["deviation"] <= 0.02, ref["curves"]
    assert abs(doc["steps"][-1]["load_factor"] - 1.0) < 1e-12
    wa, wb = doc["steps"][-1]["probes"]["A"]["u"][2], doc["steps"][-1]["probes"]["B"]["u"][2]
    assert abs(wa - 13.891) < 0.025 * 13.891 and abs(wb - 17.528) < 0.025 * 17.528, (wa, wb)
    assert max(s["balance_error"] for s in doc["steps"]) < 1e-6
    assert not res.critical_points                       # a monotone, stable path


def test_semicylinder_16x16_within_2p5_percent():
    """Clamped semi-cylinder, 16x16, the case's 40 load steps: deviation <= 2.5 % (measured
    2.09 %; 24x24 gives 1.11 %, see the module docstring); -u_z(P_max) within 3 % of the
    table's 1.71505 (measured 1.679); the response is symmetric about the plane x = 0 through
    the load (|u_x| at the crown < 1e-10)."""
    doc, res, prob = catalogue.run_case("sze-semicylinder", mesh=(16, 16))
    ref = doc["reference"]
    assert ref["entry"] == "sze3.7_clamped_semicylinder_point_load"
    assert ref["deviation"] <= 0.025, ref["curves"]
    u = doc["steps"][-1]["probes"]["crown"]["u"]
    assert abs(-u[2] - 1.71505) < 0.03 * 1.71505, u
    assert abs(u[0]) < 1e-10
    assert len(doc["steps"]) == 41


def test_limit_points_of_a_curve_whose_reference_has_none_are_reported_as_snaps_of_the_mesh():
    """The pinched cylinder's 16x16 octant (measured: 8 limit points in 4 pairs, P/P_max 0.1473 ->
    0.1449, 0.1659 -> 0.1448, 0.205 -> 0.1832, 0.319 -> 0.3157, each with one negative eigenvalue
    between; none on 24x24 and 48x48) while Sze's curve rises monotonically: the run's report says
    the reference has no limit point and gives each snap's drop, so 'limit point at P/P_max ~
    0.166' is not read as the benchmark's.  Before, the limit points were listed bare.  The
    document is the 16x16 run's, trimmed to what the report reads; the hinged roof's table
    (which has limit points) gets no such note."""
    from core_se3.catalogue.case import get_case
    from core_se3.catalogue.family_sze import report, table_curves
    import numpy as np

    def cp(lam, bracket, step, neg):
        return dict(kind="limit", load_factor=lam, bracket=bracket, step=step, negative_eigenvalues=neg)
    pairs = [(0.14727, 0.14491, 21), (0.16589, 0.14480, 25), (0.20504, 0.18320, 31), (0.31901, 0.31570, 39)]
    cps = [c for hi, lo, k in pairs for c in (cp(hi, [hi, hi], k, [0, 1]), cp(lo, [lo, lo], k + 2, [1, 0]))]
    doc = dict(params=dict(load_max=dict(value=1.0)), reference=dict(deviation=0.0316, n_points=53, curves=[], P_max=1.0),
               critical_points=cps)
    for name, monotonic in (("sze-pinched-cylinder", True), ("sze-hinged-roof", False)):
        assert all(np.all(np.diff(tl) > 0) for _, tl, _ in table_curves(get_case(name))) is monotonic
    doc["reference"]["monotonic"] = True
    (note,) = [x for x in report(doc) if "no limit point" in x]
    assert "snaps of this discrete model" in note and "0.1659 -> 0.1448" in note and note.count("->") == 4
    doc["reference"]["monotonic"] = False
    assert not [x for x in report(doc) if "no limit point" in x]


_SZE = ["sze-hemisphere", "sze-slit-annular", "sze-pullout", "sze-pinched-cylinder", "sze-semicylinder",
        "sze-hinged-roof", "sze-hinged-roof-6.35"]
_LENGTH_KEYS = ("R", "L", "h", "r_in", "r_out")


def _in_units(case, a, s):
    """The case's parameters with every length times a, E times s, load_max times s a^2 (s a for
    the annulus' line force); angles and the penalty factors over E h (k_pin, ...) unchanged."""
    f = s * a ** (1 if case.units["load_max"] == "force/length" else 2)
    return {k: v * a if k in _LENGTH_KEYS else v * s if k == "E" else v * f if k == "load_max" else v
            for k, v in case.params.items() if k in _LENGTH_KEYS + ("E", "load_max")}



@pytest.mark.parametrize("name", _SZE)
@pytest.mark.parametrize("a, s", [(1e3, 1e-6), (0.0254, 6.894757e3)])
def test_a_sze_table_is_compared_with_a_run_in_other_units(name, a, s):
    """Every Sze table against its own points in other units (lengths x a, E x s; a = 1e3 with
    s = 1e-6 is sze-hemisphere's R = 10000, h = 40, E = 68.25; a = 0.0254, s = 6894.757 inches
    and psi to m and Pa): the deviation is 0 (round-off), as in the table's units, and P_max is
    the table's load in the run's units.  Before: 'not compared: the reference entry is for R =
    10, the run has R = 10000'.  h alone changed in those units is still not compared."""
    from core_se3.catalogue import get_case, case_params
    from core_se3.catalogue.family_sze import table_comparison, table_scale
    from core_se3.catalogue.measures import curve_columns, table_curves
    case = get_case(name)
    curves, cols = table_curves(case), curve_columns(case)
    lams = curves[0][1]
    f = s * a ** (1 if case.units["load_max"] == "force/length" else 2)
    for scale, p in ((1.0, case_params(case, None)), (a, case_params(case, _in_units(case, a, s)))):
        probes = [{c["probe"]: np.zeros(3) for c in cols} for _ in lams]
        for (_, _, tu), c in zip(curves, cols):
            for pr, u in zip(probes, tu):
                pr[c["probe"]][c["component"]] = c["sign"] * u * scale
        ref, per = table_comparison(case, p, lams, probes)
        assert ref["error"] is not None and ref["error"] <= 1e-12, ref.get("note")
        assert ref["P_max"] == pytest.approx(table_scale(case, case_params(case, None))[0] * (f if scale != 1.0 else 1.0),
                                             rel=1e-14)
    h_only = case_params(case, dict(_in_units(case, a, s), h=1.1 * a * case.params["h"]))
    ref, _ = table_comparison(case, h_only, lams, probes)
    assert ref["error"] is None and "the reference entry is for h" in ref["note"]


def test_sze_hemisphere_in_other_units_has_the_error_of_the_tables_units():
    """sze-hemisphere (8x8) with R = 10000, h = 40, E = 68.25 (lengths x 1e3, E x 1e-6: the
    forces are the same) and with lengths x 2, E x 3 (P to 4800): the same path in other units,
    compared with the carried table: the deviation equals that in the table's units (measured
    0.0417529, equal to 1e-13 relative; before: not compared), the probes u / a to 1e-9 of
    their largest value (Newton's tolerance)."""
    from core_se3.catalogue import get_case
    case = get_case("sze-hemisphere")
    doc0 = catalogue.run_case("sze-hemisphere", mesh=(8, 8))[0]
    e0 = doc0["reference"]["error"]
    assert e0 is not None and 0.01 < e0 < 0.1
    for a, s in ((1e3, 1e-6), (2.0, 3.0)):
        doc1 = catalogue.run_case("sze-hemisphere", mesh=(8, 8), overrides=_in_units(case, a, s))[0]
        ref = doc1["reference"]
        assert ref["error"] == pytest.approx(e0, rel=1e-9), ref.get("note")
        assert ref["P_max"] == pytest.approx(400.0 * s * a * a, rel=1e-14) and ref["length_scale"] == a
        assert len(doc1["steps"]) == len(doc0["steps"])
        u0 = np.array([st["probes"]["A"]["u"] for st in doc0["steps"]])
        u1 = np.array([st["probes"]["A"]["u"] for st in doc1["steps"]]) / a
        assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
