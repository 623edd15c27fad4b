"""Study 4 -- numerical-stability stress runs, pass / fail.

Every run ends in one of: ``pass`` (converged and right), ``fail`` (reported a failure: no
convergence, refused step) or ``WRONG`` (converged to a wrong answer without saying so -- the
outcome that must not happen).  Tests:

1. Largest single load step (no cut-backs: core_se3 ``max_cutbacks=0``, fenicsx_ref
   ``max_cuts=0``): ``rollup`` to k (tip rotation 2πk) in one step, right = within 1 % of the
   exact circle; ``torsion`` to an end rotation α in one step, right = torque within 1e-4 of the
   same model's 8-steps-per-π path at α (an elastic path has one equilibrium there).
   fenicsx_ref cannot represent |θ| ≥ π (rotation vector): such runs are 'n/a'.
2. Thin shells, L/h = 1e4: the locking study's runs; the deviation is the tip error (cantilever,
   roll-up, arch) or, for torsion, |J/J_other − 1| against the other model's finest grid (the two
   models agree there, see the locking study).  Right = deviation < 1 %, or at most 1.5 times the
   same variant's on the same mesh at L/h = 10 (plain discretisation error of a coarse mesh is
   not a stability failure); a locked element that converges is a silent wrong answer.
3. Near-incompressible ν up to 0.499 (cantilever, PL²/EI to 4): right = both models within 1 %
   of each other (no closed form for the plate strip at ν > 0).
4. Superposed rigid rotation of 10 turns + 0.7 rad about a skew axis applied to a converged
   core_se3 state: the body-frame internal forces and the energy must not change (objectivity);
   fenicsx_ref's rotation vector cannot carry it (n/a).
5. Tangent check at each converged state: core_se3 dense central differences of the residual
   along g exp(εη) (``core_se3.verify.tangent_fd_check``), fenicsx_ref the assembled UFL
   Jacobian against central differences along 3 random directions; pass below 1e-5.
"""
from __future__ import annotations

from math import pi

import numpy as np

from . import common
from .metrics import circle_tip, path_distance
from .models import run_core, run_fenicsx
from .tables import fmt, markdown_table

__all__ = ["run", "markdown"]

TANGENT_BAR = 1e-5
ROLLUP_K = (0.05, 0.125, 0.25, 0.45, 1.0, 2.0, 3.0)
TORSION_EIGHTHS = (1, 2, 4, 6, 8, 16, 24)           # alpha = n pi/8
NUS = (0.3, 0.45, 0.49, 0.499)
MESH = dict(rollup=((10, 1), (5, 1)), torsion=((12, 4), (6, 2)), nu=((16, 4), (8, 2)))


def _thin_outcome(converged, right, run):
    """A thin-shell run's outcome; one that converged wrong but warned that its element is out of
    its range (``core_se3.errors.ElementWarning``) reported it: 'fail', not 'WRONG'."""
    if converged and not right and run.get("warning"):
        return "fail"
    return _outcome(converged, right, True, run["status"])


def _outcome(converged, right, applicable=True, status=""):
    if not applicable or status.startswith("not available"):
        return "n/a"
    if not converged:
        return "fail"
    return "pass" if right else "WRONG"


def _tangent(rec):
    t = rec.get("tangent_check")
    if t is None:
        return None
    return dict(value=t, outcome="pass" if t < TANGENT_BAR else "WRONG")


def run(quick=False, seed=True, locking=None):
    tests = []
    fx_ok = True
    if locking is None:
        try:
            locking = common.load("locking")
        except OSError:
            locking = None
    # 1a. rollup in one step
    ks = ROLLUP_K[:3] if quick else ROLLUP_K
    for k in ks:
        u, v, _ = circle_tip(10.0, np.array([k * 2 * pi / 10.0]))
        ref = np.column_stack([u, v])
        for model in ("core_se3", "fenicsx_ref"):
            common.progress(f"stress rollup k={k} one step, {model}")
            mc, mf = MESH["rollup"]
            if model == "core_se3":
                rec = run_core("rollup", mc, dict(k=k), 1, cap=dict(max_cutbacks=0), tangent_check=True)
            else:
                rec = run_fenicsx("rollup", mf, dict(k=k), 1, max_cuts=0, tangent_check=True)
            appl = not (model == "fenicsx_ref" and 2 * pi * k >= pi)
            conv = rec["status"] == "ok" and len(rec["u"]) == 1
            err = path_distance(np.array(rec["u"])[:, [0, 2]], ref, float(np.linalg.norm(ref)))[0] if conv else None
            tests.append(dict(group="largest step: rollup", model=model, what=f"k = {k:g} (θ = {2 * k:g}π)",
                              value=err, outcome=_outcome(conv, err is not None and err < 0.01, appl, rec["status"]),
                              status=rec["status"], tangent=_tangent(rec) if conv else None,
                              iterations=rec["iterations"]))
            if rec["status"].startswith("not available"):
                fx_ok = False
    # 1b. torsion in one step against the stepped path of the same model
    n8 = TORSION_EIGHTHS[:3] if quick else TORSION_EIGHTHS
    mc, mf = MESH["torsion"]
    common.progress("stress torsion: stepped reference paths")
    path_core = run_core("torsion", mc, dict(angle=3 * pi), 24)
    path_fx = run_fenicsx("torsion", mf, dict(angle=7 * pi / 8), 7)
    for n in n8:
        a = n * pi / 8
        for model, path in (("core_se3", path_core), ("fenicsx_ref", path_fx)):
            appl = not (model == "fenicsx_ref" and a >= pi)
            if not appl:
                tests.append(dict(group="largest step: torsion", model=model, what=f"α = {n}π/8",
                                  value=None, outcome="n/a", status="|θ| ≥ π not representable",
                                  tangent=None, iterations=0))
                continue
            common.progress(f"stress torsion alpha={n}pi/8 one step, {model}")
            if model == "core_se3":
                rec = run_core("torsion", mc, dict(angle=a), 1, cap=dict(max_cutbacks=0), tangent_check=True)
            else:
                rec = run_fenicsx("torsion", mf, dict(angle=a), 1, max_cuts=0, tangent_check=True)
            conv = rec["status"] == "ok" and len(rec["u"]) == 1
            Tref = path["torque"][n - 1] if path["torque"] and len(path["torque"]) >= n else None
            err = abs(rec["torque"][0] - Tref) / abs(Tref) if conv and Tref else None
            tests.append(dict(group="largest step: torsion", model=model, what=f"α = {n}π/8",
                              value=err, outcome=_outcome(conv, err is not None and err < 1e-4, appl, rec["status"]),
                              status=rec["status"], tangent=_tangent(rec) if conv else None,
                              iterations=rec["iterations"]))
    # 2. thin shells from the locking study
    if locking is not None:
        def finest_of(ratio):
            out = {}
            for r in locking["runs"]:  # torsion: the finest default / PSRI grid of each model
                if (r["case"] == "torsion" and r["L_over_h"] == ratio and r["error"] is not None
                        and r["variant"] in ("default", "psri")):
                    if r["model"] not in out or r["n_dofs"] > out[r["model"]]["n_dofs"]:
                        out[r["model"]] = r
            return out
        fin = {ratio: finest_of(ratio) for ratio in (10.0, 1e4)}

        def dev(r):
            if r is None or r["error"] is None:
                return None
            if r["case"] != "torsion":
                return r["error"]
            other = fin[r["L_over_h"]].get("fenicsx_ref" if r["model"] == "core_se3" else "core_se3")
            return None if other is None else abs(r["error"] / other["error"] - 1)

        def twin(r):  # the same model, variant and mesh at L/h = 10
            for q in locking["runs"]:
                if (q["case"], q["model"], q["variant"], q["mesh"], q["L_over_h"]) == \
                        (r["case"], r["model"], r["variant"], r["mesh"], 10.0):
                    return q
            return None

        for r in locking["runs"]:
            if r["L_over_h"] != 1e4:
                continue
            conv = r["status"] == "ok"
            d, d100 = dev(r), dev(twin(r))
            right = conv and d is not None and (d < 0.01 or (d100 is not None and d <= 1.5 * d100))
            what = ("torsion J vs the other model" if r["case"] == "torsion" else f"{r['case']} tip error")
            tests.append(dict(group="thin shell L/h = 1e4", model=r["model"],
                              what=f"{what}, {r['variant']} {r['mesh'][0]}×{r['mesh'][1]}",
                              value=d, value100=d100, outcome=_thin_outcome(conv, right, r),
                              status=r.get("warning") or r["status"], tangent=None, iterations=None))
    # 3. nu -> 0.5
    mc, mf = MESH["nu"]
    for nu in (NUS[:2] if quick else NUS):
        common.progress(f"stress nu={nu}")
        rc = run_core("cantilever-shear", mc, dict(nu=nu), 8, tangent_check=True)
        rf = run_fenicsx("cantilever-shear", mf, dict(nu=nu), 8, tangent_check=True)
        both = rc["status"] == "ok" and rf["status"] == "ok" and len(rc["u"]) == len(rf["u"]) == 8
        d = path_distance(rc["u"], rf["u"])[0] if both else None
        for model, rec in (("core_se3", rc), ("fenicsx_ref", rf)):
            conv = rec["status"] == "ok" and len(rec["u"]) == 8
            tests.append(dict(group="ν → 0.5: cantilever", model=model, what=f"ν = {nu}",
                              value=d, outcome=_outcome(conv, d is not None and d < 0.01, True,
                                                        rf["status"]),
                              status=rec["status"], tangent=_tangent(rec) if conv else None,
                              iterations=rec["iterations"]))
    # 4. superposed rigid rotation (core_se3)
    common.progress("stress rigid rotation")
    tests.append(_rigid_rotation())
    tests.append(dict(group="rigid rotation 10 turns", model="fenicsx_ref", what="rotation vector",
                      value=None, outcome="n/a", status="|θ| < π only", tangent=None, iterations=0))
    return dict(tests=tests, fenicsx=fx_ok, tangent_bar=TANGENT_BAR)


def _rigid_rotation():
    from core_se3 import catalogue, lie
    from core_se3.model.verify import tangent_fd_check
    case = catalogue.get_case("cantilever-shear")
    p = catalogue.case_params(case, {})
    prob = catalogue.build_problem(case, p, (16, 1))
    res = prob.solve(steps=8)
    g = res.final.g
    axis = np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
    w = (20 * pi + 0.7) * axis
    Q = lie.exp(np.concatenate([np.zeros(3), w]))
    g2 = np.einsum("ij,njk->nik", Q, g)
    e1 = prob.element.evaluate(g, tangent=False)
    e2 = prob.element.evaluate(g2, tangent=False)
    dr = float(np.abs(e2.r - e1.r).max() / np.abs(e1.r).max())
    de = float(abs(e2.energy - e1.energy) / abs(e1.energy))
    tc = float(tangent_fd_check(prob, g2, 1.0)[0])
    ok = max(dr, de) < 1e-9
    return dict(group="rigid rotation 10 turns", model="core_se3",
                what="cantilever P L²/EI = 4, |ω| = 20π + 0.7",
                value=max(dr, de), outcome="pass" if ok else "WRONG",
                status=f"Δr/|r| = {dr:.1e}, ΔW/W = {de:.1e}",
                tangent=dict(value=tc, outcome="pass" if tc < TANGENT_BAR else "WRONG"), iterations=None)


def pass_rates(data):
    out = {}
    for t in data["tests"]:
        for kind, outcome in (("run", t["outcome"]),
                              ("tangent", t["tangent"]["outcome"] if t.get("tangent") else None)):
            if outcome in (None, "n/a"):
                continue
            c = out.setdefault((t["model"], kind), dict(pass_=0, fail=0, WRONG=0))
            c["pass_" if outcome == "pass" else outcome] += 1
    return out


def markdown(data):
    rows = []
    for t in data["tests"]:
        tg = t.get("tangent")
        rows.append([t["group"], t["model"], t["what"], t["outcome"],
                     fmt(t["value"], 3) + (f" (L/h = 10: {fmt(t['value100'], 3)})" if t.get("value100") else ""), "–" if not tg else f"{tg['value']:.1e} ({tg['outcome']})",
                     "–" if t.get("iterations") in (None, 0) else t["iterations"],
                     t["status"].replace("failed: ", "")[:100]])
    md = [markdown_table(["test", "model", "run", "outcome", "measure", "tangent check", "Newton its",
                          "status"], rows)]
    pr = pass_rates(data)
    rr = []
    for (model, kind), c in sorted(pr.items()):
        n = c["pass_"] + c["fail"] + c["WRONG"]
        rr.append([model, "runs" if kind == "run" else "tangent checks", f"{c['pass_']}/{n}",
                   c["fail"], c["WRONG"]])
    md.append("\nPass rates (n/a excluded):\n")
    md.append(markdown_table(["model", "what", "pass", "fail (reported)", "WRONG (silent)"], rr))
    return "\n".join(md)
