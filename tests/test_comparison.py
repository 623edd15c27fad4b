"""Harness logic of the comparison package (issue 5): error norms, rate fits, time-to-error,
reference closed forms and table building.  NumPy/SciPy only, no solver runs."""
from math import pi

import numpy as np
import pytest

from comparison.metrics import (circle_tip, fit_rate, geometric_mean_ratio, interp_reference,
                                mindlin_strip_J, path_distance, time_to_error)
from comparison.tables import fmt, markdown_table, pct


def test_path_distance_is_max_step_distance_over_largest_displacement():
    e = np.array([[1.0, 0.0, 0.0], [0.0, 4.0, 3.0]])      # largest |e| = 5
    d = e + np.array([[0.0, 0.1, 0.0], [0.0, 0.0, -0.3]])
    err, per = path_distance(d, e, scale=5.0)
    assert per == pytest.approx([0.02, 0.06])
    assert err == pytest.approx(0.06)
    # default scale: largest displacement of either path (here |d_2| = 4.75 < 5)
    assert path_distance(d, e)[0] == pytest.approx(0.06)
    with pytest.raises(ValueError):
        path_distance(d[:1], e)
    with pytest.raises(ValueError):
        path_distance(np.zeros((2, 3)), np.zeros((2, 3)))


def test_interp_reference_exact_for_cubics_and_nan_outside():
    x = np.linspace(0.0, 2.0, 9)
    V = np.column_stack([x ** 3 - x, 2 * x ** 2])
    q = np.array([0.33, 1.7, 2.5])
    out = interp_reference(q, x, V)
    assert out[:2, 0] == pytest.approx(q[:2] ** 3 - q[:2], abs=1e-12)
    assert out[:2, 1] == pytest.approx(2 * q[:2] ** 2, abs=1e-12)
    assert np.all(np.isnan(out[2]))


def test_fit_rate_recovers_power_law_and_uses_finest_points():
    h = np.array([1.0, 0.5, 0.25, 0.125, 0.0625])
    err = 3.0 * h ** 2
    err[0] = 10.0      # pre-asymptotic coarse point: ignored by last=3
    p, C = fit_rate(h, err, last=3)
    assert p == pytest.approx(2.0, abs=1e-12)
    assert C == pytest.approx(3.0, rel=1e-12)
    assert np.isnan(fit_rate([1.0], [0.1])[0])


def test_time_to_error_measured_extrapolated_and_floor():
    t = np.array([1.0, 2.0, 4.0, 8.0])
    e = np.array([1e-1, 1e-2, 1e-3, 1e-4])                 # t = 1e-1 ** ... : t ∝ e^(-0.301)
    tt, how = time_to_error(t, e, 1e-2)
    assert (tt, how) == (pytest.approx(2.0), "measured")
    tt, how = time_to_error(t, e, 10 ** -2.5)              # halfway in log between runs 2 and 3
    assert how == "measured" and tt == pytest.approx(np.sqrt(8.0))
    tt, how = time_to_error(t, e, 1e-6)                    # two decades beyond: 2 more doublings
    assert how == "extrapolated" and tt == pytest.approx(32.0, rel=1e-9)
    # a model on an error floor never reaches it
    tt, how = time_to_error(t, [1e-1, 1e-3, 1.1e-3, 1.2e-3], 1e-4)
    assert how == "not reached" and np.isnan(tt)
    assert time_to_error(t, e, 1.0) == (1.0, "measured")


def test_mindlin_strip_J_matches_the_tabulated_strip():
    """core_se3/data/elastica.json, 5_strip_torsion_seed_strip: w = 0.25, h = 0.1."""
    from core_se3.catalogue.references import elastica_entry
    p = elastica_entry("5_strip_torsion_seed_strip")["params"]
    assert mindlin_strip_J(p["w"], p["h"]) == pytest.approx(p["J_mindlin_ks=1"], rel=1e-6)
    assert mindlin_strip_J(p["w"], p["h"], 5 / 6) == pytest.approx(p["J_mindlin_ks=5/6"], rel=1e-6)
    # thin limit: the Kirchhoff plate w h^3/3 (edge layer ~ h/w)
    w, h = 0.25, 1e-4
    assert mindlin_strip_J(w, h) / (w * h ** 3 / 3) == pytest.approx(1 - 2 * h / (np.sqrt(12) * w), rel=1e-9)


def test_circle_tip_matches_rollup_entry():
    """core_se3/data/elastica.json, 2_pure_bending_rollup_out_of_plane (exact circle)."""
    from core_se3.catalogue.references import elastica_entry
    e = elastica_entry("2_pure_bending_rollup_out_of_plane")
    L = 10.0
    EI = 1.2e7 * 1.0 * 0.1 ** 3 / 12
    k = np.asarray(e["load"]) / EI
    u, v, th = circle_tip(L, k)
    assert u == pytest.approx(np.asarray(e["tip"]["u"]), abs=1e-9)
    assert v == pytest.approx(np.asarray(e["tip"]["v"]), abs=1e-9)
    assert th[-1] == pytest.approx(6 * pi)


def test_geometric_mean_ratio():
    assert geometric_mean_ratio([2.0, 8.0, np.nan], [1.0, 2.0, 1.0]) == pytest.approx(np.sqrt(8.0))


def test_tables_and_formats():
    t = markdown_table(["a", "b"], [[1, "x|y"], ["–", 2]])
    assert t.splitlines() == ["| a | b |", "|---|---|", "| 1 | x/y |", "| – | 2 |"]
    with pytest.raises(ValueError):
        markdown_table(["a"], [[1, 2]])
    assert fmt(None) == fmt(float("nan")) == "–"
    assert fmt(1.23456e-5) == "1.23e-05"
    assert pct(0.001234) == "0.12 %"
    assert pct(None) == "–"


def _pareto_data():
    runs = []
    for model, c, t0 in (("core_se3", 1.0, 0.1), ("fenicsx_ref", 0.1, 1.0)):
        for j, nx in enumerate((4, 8, 16, 32)):
            err = c * nx ** -2.0 if model == "core_se3" else max(c * nx ** -4.0, 2e-3)   # fx: floor
            runs.append(dict(case="cantilever-shear", model=model, nx=nx, n_dofs=10 * nx, status="ok",
                             time=t0 * 2 ** j, jit=5.0 if model == "fenicsx_ref" else 0.0,
                             timings=dict(setup=0.0, jit=0.0, assembly=0.0, solve=0.0, other=0.0),
                             iterations=10, error=err))
    return dict(runs=runs, repeats=1, targets=[1e-2, 1e-3, 1e-4])


def test_pareto_summary_rates_times_and_floor():
    from comparison import pareto
    s = pareto.summarize(_pareto_data())
    core, fx = s[("cantilever-shear", "core_se3")], s[("cantilever-shear", "fenicsx_ref")]
    assert core["rate"] == pytest.approx(2.0, abs=1e-9)
    # core: error 1/nx^2 reaches 1e-3 between nx = 16 (3.9e-3, t = 0.4) and nx = 32 (9.8e-4, t = 0.8)
    t, how = core["times"][1e-3]
    assert how == "measured" and 0.4 < t <= 0.8
    # 1e-4 lies beyond: extrapolated along t ∝ e^(-1/2): 0.8 * sqrt(9.77e-4 / 1e-4)
    t, how = core["times"][1e-4]
    assert how == "extrapolated" and t == pytest.approx(0.8 * np.sqrt(32 ** -2 / 1e-4), rel=1e-6)
    # fenicsx_ref sits on its 2e-3 floor: 0.1 % is not reached, and the JIT is summed apart
    assert fx["times"][1e-3][1] == "not reached" and fx["min_error"] == pytest.approx(2e-3)
    assert fx["jit"] == pytest.approx(20.0)
    md = pareto.markdown(_pareto_data())
    assert "not reached (floor)" in md and "(extrap.)" in md


def test_locking_table_marks_failures_and_torsion_ratio():
    from comparison import locking
    runs = [dict(case="cantilever-shear", L_over_h=r, model=m, variant=v, mesh=[8, 2], grid=[4, 1],
                 n_dofs=1, status=("failed: no convergence" if v == "seed" else "ok"), wall=0.1,
                 error=(None if v == "seed" else e))
            for r, e in ((10.0, 1e-3), (1e4, 0.5)) for m, v in locking.VARIANTS]
    runs.append(dict(case="torsion", L_over_h=10.0, model="core_se3", variant="default", mesh=[10, 4],
                     grid=[5, 2], n_dofs=1, status="ok", wall=0.1, error=1.1))
    md = locking.markdown(dict(runs=runs))
    assert "| core default | 8×2 | 0.1 % | 50 % |" in md
    assert "| core seed | 8×2 | fails | fails |" in md
    assert "| core default | 10×4 | 1.1 |" in md
    assert "Failures:" in md


def test_pareto_exact_model_has_no_rate():
    from comparison import pareto
    d = _pareto_data()
    for r in d["runs"]:
        if r["model"] == "core_se3":
            r["error"] = 1e-15 * (1 + r["nx"] % 3)      # round-off noise only
    s = pareto.summarize(d)[("cantilever-shear", "core_se3")]
    assert np.isnan(s["rate"]) and s["times"][1e-4] == (0.1, "measured")
    assert "exact (round-off)" in pareto.markdown(d)


def test_arc_tip_matches_half_cylinder_entry_and_reduces_to_circle():
    """core_se3/data/elastica.json, 4_arch_halfcircle_end_moment_R10over2pi (arc length 5)."""
    from comparison.metrics import arc_tip
    from core_se3.catalogue.references import elastica_entry
    e = elastica_entry("4_arch_halfcircle_end_moment_R10over2pi")
    p = e["params"]
    u, v = arc_tip(p["L_arc"], 1.0 / p["R"], np.asarray(e["load"]) / p["EI"])
    assert u == pytest.approx(np.asarray(e["tip"]["u"]), abs=1e-9)
    assert v == pytest.approx(np.asarray(e["tip"]["v"]), abs=1e-9)
    k = np.array([0.0, 1e-9, 0.3, 2.0])
    cu, cv, _ = circle_tip(10.0, k)
    au, av = arc_tip(10.0, 0.0, k)
    assert au == pytest.approx(cu, abs=1e-12) and av == pytest.approx(cv, abs=1e-12)


def test_stress_counts_a_warned_wrong_run_as_reported():
    """A thin-shell run that converged wrong but warned (the seed's ElementWarning) is 'fail'
    (reported), one that converged wrong silently is 'WRONG', a warned right one 'pass'."""
    from comparison import stress
    run = dict(status="ok", warning=None)
    assert stress._thin_outcome(True, False, run) == "WRONG"
    assert stress._thin_outcome(True, False, dict(run, warning="element 'seed' ... locks")) == "fail"
    assert stress._thin_outcome(True, True, dict(run, warning="element 'seed' ... locks")) == "pass"
    assert stress._thin_outcome(False, False, dict(status="failed: x")) == "fail"


def test_report_torsion_finding_does_not_cite_psri_equal_to_full_as_evidence():
    """REPORT.md said the torsion torque ratio was 'unchanged ... by fenicsx_ref's integration
    (full vs PSRI differ by 2.1e-14 %)'.  On the 20x6 grid of the 1 x 0.25 strip the Q2 cells
    (diameter 0.065) are smaller than h = 0.1, so PSRI's alpha = min(1, (h/h_e)^2) = 1: the two
    runs are the same scheme, equal by construction, and prove nothing.  The text now says so;
    on the coarse 10x3 grid (h_e = 0.130 > h) there is nothing to add."""
    from comparison.report import _findings, _psri_alpha_note
    row = dict(case="torsion", nu=0.0, overrides=dict(angle=pi / 2, nu=0.0),
               levels=[dict(mesh_fx=[10, 3], torque_ratio=[1.105], dist_full_psri=1e-3),
                       dict(mesh_fx=[20, 6], torque_ratio=[1.103], dist_full_psri=2e-16)])
    assert _psri_alpha_note(dict(row, levels=row["levels"][:1])) == ""
    assert "= 1" in _psri_alpha_note(row) and "0.065" in _psri_alpha_note(row)
    text = "\n".join(_findings(dict(agreement=dict(cases=[row]), stress=dict(tests=[]),
                                    locking=dict(runs=[]))))
    assert "unchanged by refinement and by fenicsx_ref's integration" not in text
    assert "does not test locking" in text


def test_agreement_levels_refine_the_width_where_nu_makes_it_vary():
    """With nu = 0.3 a strip's deflection varies across the width (anticlastic bending); the two
    grid levels must refine that direction too, else the 'fine grid' distance is the common
    width error: it was fx 16x2 / core 32x4 on both levels, 0.11 % (cantilever) and 0.22 %
    (follower pressure), which fall to 0.054 % and 0.065 % on 16x4 / 32x8."""
    from comparison.agreement import CASES, _mesh_core, _nu_mesh
    for name, _, _, _, meshes in CASES:
        if name == "torsion":
            continue
        m = [_nu_mesh(name, mm, 0.3, lev) for lev, mm in enumerate(meshes)]
        assert m[1][0] > m[0][0], (name, m)
        if m[1][1] > 1:
            assert m[1][1] > m[0][1], (name, m)          # refined across the width as well
        assert _mesh_core(m[1]) == (2 * m[1][0], 2 * m[1][1])
    assert _nu_mesh("cantilever-shear", (16, 1), 0.0, 1) == (16, 1)   # nu = 0: uniform across


def test_study_data_records_the_machine_its_times_were_measured_on(tmp_path, monkeypatch):
    """REPORT.md's CPU row was the machine that rendered the page: after `report --reuse` on
    another host it said 'AMD EPYC' above pareto times measured on an Intel Xeon.  Each study's
    data now stores its own CPU and load; data without it is shown as 'not recorded'."""
    import types
    from comparison import common, report
    monkeypatch.setattr(common, "OUT", str(tmp_path))
    mod = types.SimpleNamespace(run=lambda quick, seed: dict(runs=[]))
    data, _ = report._run_or_load("fake", mod, quick=False, seed=False, reuse=False)
    m = common.load("fake")["machine"]
    assert m["cpu"] == report.environment()["cpu"] and m["cores"] >= 1 and m["load_start"] >= 0
    row = report._machines({"fake": data, "old": {}}, {"fake": 1.0, "old": None})
    assert m["cpu"] in row and "old: not recorded" in row


def test_quick_run_does_not_overwrite_the_full_study_data(tmp_path, monkeypatch):
    """`python -m comparison agreement --quick` (3 of 8 cases, for development) wrote
    reports/data/agreement.json over the full study, and a later `report --reuse` rendered those 3
    cases as the published agreement.  Quick runs now write agreement-quick.json."""
    import json
    from comparison import __main__ as cli, agreement, common
    monkeypatch.setattr(common, "OUT", str(tmp_path))
    (tmp_path / "data").mkdir()
    full = tmp_path / "data" / "agreement.json"
    full.write_text(json.dumps(dict(cases=["the full study"])))
    monkeypatch.setattr(agreement, "run", lambda quick, seed: dict(cases=["quick"], quick=quick))
    monkeypatch.setattr(agreement, "markdown", lambda data: ("", {}))
    monkeypatch.setattr(agreement, "plot", lambda data, path: None)
    monkeypatch.setattr("core_se3.backend.pin_for_timing", lambda: None)
    assert cli.main(["agreement", "--quick", "--no-seed"]) == 0
    assert json.loads(full.read_text()) == dict(cases=["the full study"])
    assert common.load("agreement", quick=True)["cases"] == ["quick"]
