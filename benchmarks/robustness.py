#!/usr/bin/env python3
"""Step-size independence of every catalogue case and example scenario (issue 29).

Each case runs with 1 load step, 2, its default and 4x its default (arc-length cases: the first
step dlam0 = lam_end / steps, so a 1-step path asks for the whole load at once); each run is
a child process with a time limit.  The final state of each run is compared with that of the
finest run that finished (4x default, else the default):

    d = max(max_n |x_n - x_n^ref| / U, max_n |R_n - R_n^ref|_F)

U the largest nodal displacement along the reference path (the path's scale), and the final
load factors within 1e-6 max(1, |lam_ref|) (an arc-length path ends where its displacement
does).  A cell is

* ``= d``: the same state (d <= 1e-6);
* ``= at tol d; ... d_t``: d > 1e-6, but solved again with Newton's rtol/dtol and every
  contact's gap tolerance divided by 100, the run and its reference agree to d_t <= 1e-6 and
  d_t <= d / 10: the difference is the stated tolerances (a contact's 1e-6 h), not another state;
* ``DIFFERS d``: a different state reported as converged -- a converged-looking wrong answer
  (the target is none);
* ``stop: <message>``: the run stopped and said why (the message, shortened);
* ``timeout`` / ``error``.

Further parts (``--part``), each a section of the same results:

* ``zhao``: the Zhao et al. magnetic cantilever (L 17.2, h 0.42, nu 0) at q = A Br Ba L^2 /
  (mu0 E I) = 5 ... 30 in ONE load step on 20x1 ... 120x1: the tip's error against the elastica
  (within 0.5 %) or the message;
* ``translation``: the README cantilever (16x1, 10 steps) with its mesh moved to x0 = 0, 10,
  ..., 1e9: the tip displacement and the Newton iterations of every step, against x0 = 0;
* ``critical``: the critical load factors of the buckling cases (the hinged roofs' limit
  points, a deep cantilever strip's lateral-torsional buckling) from first steps dlam0 = 0.5
  ... 0.01, against the value refined to 1e-6;
* ``candidates``: what detects a load step that converged onto another equilibrium (the path
  check's measurements, docs/STEPS.md);
* ``cost``: benchmarks/speed.py's cases with this tree and with ``--baseline`` (a checkout of
  main), in alternating child processes: what the checks add.

Writes ``benchmarks/results/robustness.{md,json}`` (a part run keeps the other parts' rows).

    .venv/bin/python benchmarks/robustness.py                      # the step table (~1 h)
    .venv/bin/python benchmarks/robustness.py --cases rollup example:rotating-field --timeout 300
    .venv/bin/python benchmarks/robustness.py --part zhao translation critical candidates
    git worktree add /tmp/main main && .venv/bin/python benchmarks/robustness.py --part cost --baseline /tmp/main
    .venv/bin/python benchmarks/robustness.py --part cost --baseline /tmp/main --rounds 1 --repeats 1   # ~2 x speed.py
"""
from __future__ import annotations

import argparse
import datetime
import fcntl
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
EXAMPLES = ROOT / "examples"
SAME = 1e-6                 # agreement: 1e-6 of the path's scale


def all_cases():
    """Catalogue case names, then 'example:NAME' for every example scenario file."""
    from core_se3.catalogue import CASES
    return list(CASES) + [f"example:{p.stem}" for p in sorted(EXAMPLES.glob("*.toml"))]


# ----------------------------------------------------------------------------- child ------
def default_steps(name):
    """The case's (example's) own number of load steps."""
    if name.startswith("example:"):
        from core_se3 import scenario
        return int(scenario.load(EXAMPLES / f"{name[8:]}.toml").solver["steps"])
    from core_se3.catalogue import get_case
    return int(get_case(name).steps)


TIGHT = 100.0               # the tolerance rerun of a differing cell: Newton's and contact's / 100


def _tighten(prob):
    """Divide the gap tolerance of every contact load of ``prob`` by TIGHT (in place)."""
    for ld in prob.loads:
        if hasattr(ld, "gap_error") and getattr(ld, "tol", None):
            ld.tol /= TIGHT
    return prob


def _solve(name, steps, tight=False):
    """(Result, Problem) of a run with ``steps`` load steps; ``tight``: with Newton's rtol and
    dtol and every contact's gap tolerance divided by TIGHT."""
    extra = dict(rtol=1e-10 / TIGHT, dtol=1e-10 / TIGHT) if tight else {}
    if name.startswith("example:"):
        import warnings
        from core_se3 import scenario
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scn = scenario.load(EXAMPLES / f"{name[8:]}.toml")
        s = scn.solver
        kw = dict(steps=steps)
        if s["control"] == "arclength":
            kw = dict(dlam0=s["lam_end"] / steps)
        if tight:
            _tighten(scn.problem)
        return scn.problem.solve(**kw, **extra), scn.problem
    from core_se3.catalogue import get_case, run_case
    if tight:
        import core_se3.catalogue.run as R
        build = R.build_problem
        R.build_problem = lambda *a, **k: _tighten(build(*a, **k))
    # the arc-length cases of the Sze et al. family start from their own dlam0: set it from steps,
    # with room for the steps a small first step takes to the end of the path
    kw = dict(dlam0=1.0 / steps, max_steps=100_000) if get_case(name).extra.get("dlam0") is not None else {}
    _, res, prob = run_case(name, steps=steps, **kw, **extra)
    return res, prob


def child(name, steps, out, tight=False):
    from core_se3.errors import CoreSE3Error
    t0 = time.perf_counter()
    try:
        res, prob = _solve(name, steps, tight)
    except CoreSE3Error as exc:
        return dict(status="stop", message=" ".join(str(exc).split()), kind=type(exc).__name__,
                    time=time.perf_counter() - t0)
    g0 = prob.mesh.g0
    steps_ = [s for s in res.steps if getattr(s, "g", None) is not None]
    final = steps_[-1]
    U = max(float(np.abs(s.g[:, :3, 3] - g0[:, :3, 3]).max()) for s in steps_)
    np.savez(out, g=final.g)
    log = [e for e in res.log if isinstance(e, dict)]
    return dict(status="ok", lam=float(final.load_factor), scale=U, time=time.perf_counter() - t0,
                tries=len(log), iterations=sum(int(e.get("iterations") or 0) for e in log),
                rejected=sum("path check" in str(e.get("reason", "")) for e in log),
                critical=[f"{c.kind} at {c.lam:.6g}" for c in getattr(res, "critical_points", [])])


def run(name, steps, timeout, workdir, tight=False):
    out = os.path.join(workdir, f"{name.replace(':', '_')}_{steps}{'_tight' if tight else ''}.npz")
    cmd = [sys.executable, __file__, "--child", name, "--steps", str(steps), "--out", out] + ["--tight"] * tight
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return dict(status="timeout", message=f"no answer in {timeout:.0f} s"), None
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            r = json.loads(line[7:])
            return r, (np.load(out)["g"] if r["status"] == "ok" else None)
    return dict(status="error", message=(p.stderr or p.stdout)[-400:]), None


def distance(g, ref, scale):
    """max(position difference / scale, rotation difference) of two states (module docstring)."""
    dx = np.abs(g[:, :3, 3] - ref[:, :3, 3]).max() / max(scale, 1e-300)
    dR = np.sqrt(((g[:, :3, :3] - ref[:, :3, :3]) ** 2).sum((1, 2))).max()
    return float(max(dx, dR))


def study(name, timeout, workdir):
    d = default_steps(name)
    counts = sorted({1, 2, d, 4 * d})
    runs = {}
    for n in counts:
        r, g = run(name, n, timeout, workdir)
        runs[n] = (r, g)
        print(f"  {name} steps={n}: {r['status']} {r.get('message', '')[:120]}", flush=True)
    ref_n = next((n for n in (4 * d, d) if runs[n][0]["status"] == "ok"), None)
    row = dict(case=name, default=d, runs={})
    for n in counts:
        r, g = runs[n]
        cell = dict(r)
        if r["status"] == "ok" and ref_n is not None:
            rr, gr = runs[ref_n]
            if gr.shape != g.shape:
                cell["status"] = "error"
                cell["message"] = "different meshes"
            else:
                cell["d"] = distance(g, gr, rr["scale"])
                cell["lam_ref"] = rr["lam"]
                # the load factor too (an arc-length path ends where a displacement is reached)
                same_lam = abs(r["lam"] - rr["lam"]) <= SAME * max(1.0, abs(rr["lam"]))
                cell["verdict"] = "ref" if n == ref_n else "same" if cell["d"] <= SAME and same_lam else "DIFFERS"
                if cell["verdict"] == "DIFFERS" and same_lam:
                    cell.update(_tolerance_rerun(name, n, ref_n, cell["d"], timeout, workdir))
        row["runs"][str(n)] = cell
    row["reference"] = ref_n
    return row


def _tolerance_rerun(name, n, ref_n, d, timeout, workdir):
    """A differing cell and its reference solved again with the tolerances divided by TIGHT:
    when their distance drops below SAME and by at least TIGHT / 10, the difference was the
    solvers' stated tolerances (verdict 'tol'), not another state."""
    (a, ga), (b, gb) = run(name, n, timeout, workdir, True), run(name, ref_n, timeout, workdir, True)
    if a["status"] != "ok" or b["status"] != "ok":
        return dict(d_tight=None, tight_message=(a.get("message") or b.get("message") or "")[:200])
    dt = distance(ga, gb, b["scale"])
    print(f"  {name} steps={n}: d {d:.2e}, with the tolerances / {TIGHT:g}: {dt:.2e}", flush=True)
    return dict(d_tight=dt, verdict="tol" if dt <= SAME and dt <= d * 10 / TIGHT else "DIFFERS")


# ----------------------------------------------------------------------------- parts ------
ZHAO_Q = list(range(5, 31))
ZHAO_MESHES = (20, 40, 60, 90, 120)
ZHAO_TOL = 0.005


def zhao_part():
    """One-step Zhao cantilever runs: dict(q, nx, error or message, iterations, tries)."""
    from core_se3.catalogue import run_case
    from core_se3.errors import CoreSE3Error
    rows = []
    for q in ZHAO_Q:
        for nx in ZHAO_MESHES:
            ov = dict(nu=0.0, L=17.2, h=0.42, Ba_max=0.0078328 * q / 20)    # q = 20 at 7.8328 mT
            try:
                doc, res, _ = run_case("magnetic-cantilever", mesh=(nx, 1), steps=1, overrides=ov)
                rows.append(dict(q=q, nx=nx, error=float(doc["reference"]["error"]), tries=len(res.log),
                                 iterations=sum(e["iterations"] for e in res.log),
                                 rejected=sum("path check" in e["reason"] for e in res.log)))
            except CoreSE3Error as exc:
                rows.append(dict(q=q, nx=nx, message=" ".join(str(exc).split())))
            print("  zhao", rows[-1], flush=True)
    return rows


def readme_cantilever(x0):
    from core_se3 import Material, Problem, mesh
    p = Problem(mesh.rectangle(10.0, 1.0, 16, 1, x0=x0), Material(E=1.2e6, nu=0.0, h=0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 4.0))
    p.add_probe("tip", "x1")
    return p


def translation_part():
    from core_se3.errors import CoreSE3Error
    rows = []
    for x0 in [0.0] + [10.0 ** k for k in range(1, 10)]:
        try:
            res = readme_cantilever(x0).solve(steps=10)
            rows.append(dict(x0=x0, u=[float(v) for v in res.final.probes["tip"]["u"]],
                             iterations=[int(st.iterations) for st in res.steps[1:]]))
        except CoreSE3Error as exc:
            rows.append(dict(x0=x0, message=" ".join(str(exc).split())))
        print("  translation", rows[-1], flush=True)
    return rows


def ltb_strip():
    """A deep cantilever strip (10 x 1 x 0.05, E 1.2e6, nu 0, 40x4) under an in-plane tip force
    along its width: lateral-torsional buckling at P ~ 4.013 sqrt(EI_z GJ) / L^2 (beam theory)."""
    from core_se3 import Material, Problem, mesh
    p = Problem(mesh.rectangle(10.0, 1.0, 40, 4), Material(1.2e6, 0.0, 0.05))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 1.0, 0.0))
    p.add_probe("tip", "x1")
    return p


def candidates_part():
    """What detects a step that converged elsewhere: the Zhao cantilever (q 5 ... 30, 20/40/90
    elements, 1, 2 and 4 steps) solved WITHOUT the path check; every converged try is compared
    with a 64-step path to its load factor (wrong: positions off by more than 1e-3 ell) and the
    candidates are evaluated on it: the path check's measures (solvers.step_checks), the change of the
    negative-eigenvalue count and of det K's sign between the try's start and end states, the
    ratio of the converged increment to the tangent predictor, the iteration count."""
    import core_se3.solvers.newton as N
    from core_se3.catalogue import build_problem, case_params, get_case, run_case
    from core_se3.errors import CoreSE3Error
    from core_se3.solvers.convergence import scaled_norm
    from core_se3.solvers.stability import inertia
    seen = []
    log_try = N._log_try

    def spy(result, tries, lam_try, out, augmentation=None, quiet=False):
        seen.append((lam_try, out))
        return log_try(result, tries, lam_try, out, augmentation, quiet)

    N._log_try = spy
    rows, refs = [], {}
    case = get_case("magnetic-cantilever")
    try:
        for q in (5, 8, 11, 14, 15, 16, 17, 18, 20, 22, 25, 30):
            for nx in (20, 40, 90):
                ov = dict(nu=0.0, L=17.2, h=0.42, Ba_max=0.0078328 * q / 20)
                prob = build_problem(case, case_params(case, ov), (nx, 1))
                for steps in (1, 2, 4):
                    seen.clear()
                    try:
                        run_case("magnetic-cantilever", mesh=(nx, 1), steps=steps, overrides=ov, path_check=False)
                    except CoreSE3Error:
                        pass
                    g_prev, lam_prev = prob.mesh.g0.copy(), 0.0
                    for lam, out in list(seen):
                        if not out.ok:
                            continue
                        key = (q, nx, round(lam, 12))
                        if key not in refs:
                            refs[key] = prob.solve(steps=max(8, int(64 * lam)), lam_end=lam).final.g
                        err = np.abs(out.g[:, :3, 3] - refs[key][:, :3, 3]).max() / prob.length_scale
                        s0, n0 = inertia(prob.evaluate(g_prev, lam_prev).K)
                        s1, n1 = inertia(prob.evaluate(out.g, lam).K)
                        jump = scaled_norm(out.eta_sum, prob.length_scale, moment=False) / out.pred
                        rows.append(dict(q=q, nx=nx, steps=steps, lam=lam, iterations=out.iterations,
                                         contraction=out.contraction, travel=out.travel,
                                         theta_all=_theta_all(out.incs), jump=float(jump), n0=n0, n1=n1, s0=s0,
                                         s1=s1, error=float(err), wrong=bool(err > 1e-3),
                                         increments=[float(x) for x in out.incs]))
                        g_prev, lam_prev = out.g, lam
                print("  candidates", q, nx, len(rows), flush=True)
    finally:
        N._log_try = log_try
    return rows


def _theta_all(incs):
    """The largest ratio of two successive corrections above round-off, at any scale."""
    a = np.asarray(incs, float)
    keep = (a[1:] > 1e-8) & (a[:-1] > 0) if len(a) > 1 else np.zeros(0, bool)
    return float(np.max(a[1:][keep] / a[:-1][keep])) if np.any(keep) else 0.0


def _path_check(r):
    """The path check of this tree on a try's recorded corrections (the row's ``contraction`` is
    the tree's that recorded it)."""
    from core_se3.solvers.step_checks import path_measures, path_refusal
    return bool(path_refusal(*path_measures(r["increments"])))


def _reach(r):
    """A growth of a correction by GROWTH_REACH of the step's scale (min(|eta_0|, pi ell))."""
    from core_se3.solvers.step_checks import GROWTH_CAP, GROWTH_REACH
    a = np.asarray(r["increments"], float)
    return len(a) > 1 and np.max(a[1:] - a[:-1]) >= GROWTH_REACH * min(a[0], GROWTH_CAP)


CANDIDATES = (("the path check (growth at the step's scale or by a quarter of it, or travel >= 1.5)", _path_check),
              ("a growth by a quarter of the step's scale (GROWTH_REACH) alone", _reach),
              ("any growth of a correction (Theta_k >= 1 at any scale)", lambda r: r["theta_all"] >= 1.0),
              ("negative-eigenvalue count changed", lambda r: r["n1"] != r["n0"]),
              ("det K sign changed", lambda r: r["s1"] != r["s0"]),
              ("increment / predictor outside [0.5, 1.5]", lambda r: not 0.5 <= r["jump"] <= 1.5),
              ("more than 8 iterations", lambda r: r["iterations"] > 8))


def _candidates_section(rows):
    # a jump is a wrong try from a right start (the tries after it continue it)
    first, prev_wrong = [], {}
    for r in rows:
        k = (r["q"], r["nx"], r["steps"])
        if r["wrong"] and not prev_wrong.get(k, False):
            first.append(r)
        prev_wrong[k] = r["wrong"]
    right = [r for r in rows if not r["wrong"]]
    L = ["## What detects a step that converged elsewhere", "",
         f"The Zhao cantilever (q = 5 ... 30, 20/40/90x1, 1, 2 and 4 steps) solved without the path check: "
         f"{len(rows)} converged tries, {len(rows) - len(right)} off the path (positions more than 1e-3 ell from a "
         f"64-step path), {len(first)} of them jumps from a state on the path.", "",
         "| candidate | jumps found | right tries refused |", "|---|---:|---:|"]
    for name, f in CANDIDATES:
        L.append(f"| {name} | {sum(map(f, first))} of {len(first)} | {sum(map(f, right))} of {len(right)} |")
    thetas = sorted(r["contraction"] for r in first)
    L += ["", f"The smallest growth of a jump at the step's scale: {thetas[0]:.3g}." if thetas else "", ""]
    return L


def cost_child(repeats=3):
    """Each case of benchmarks/speed.py solved once to warm up and then ``repeats`` times (the
    best counts), with the core_se3 on PYTHONPATH: dict case -> (seconds, Newton iterations)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from speed import CASES as SPEED_CASES, _solve_once
    out = {}
    for name, (mesh, _) in SPEED_CASES.items():
        _solve_once(name, mesh)
        runs = [_solve_once(name, mesh) for _ in range(repeats)]
        best = min(runs, key=lambda r: r["total"])
        out[name] = (best["total"], best["iterations"])
    return out


def cost_part(baseline, rounds=3, repeats=3, timeout=3600):
    """speed.py's cases with this tree's core_se3 and with ``baseline``'s (a checkout of main),
    alternately in ``rounds`` pairs of child processes (numba, one thread): per case the best
    time of each and their ratio."""
    env0 = dict(os.environ, CORE_SE3_BACKEND="numba")
    env0.update({v: "1" for v in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")})
    seen = {"checks": [], "baseline": []}
    for _ in range(rounds):
        for which, path in (("checks", ROOT), ("baseline", Path(baseline))):
            p = subprocess.run([sys.executable, __file__, "--cost-child", "--repeats", str(repeats)],
                               capture_output=True, text=True,
                               timeout=timeout, env=dict(env0, PYTHONPATH=str(path)))
            line = next((x for x in p.stdout.splitlines() if x.startswith("RESULT ")), None)
            if line is None:
                raise RuntimeError(f"cost child ({which}) failed: {p.stderr[-800:]}")
            seen[which].append(json.loads(line[7:]))
            print("  cost", which, seen[which][-1], flush=True)
    rows = []
    for name in seen["checks"][0]:
        a = min(r[name][0] for r in seen["checks"])
        b = min(r[name][0] for r in seen["baseline"])
        rows.append(dict(case=name, checks=a, baseline=b, ratio=a / b, iterations=seen["checks"][0][name][1],
                         iterations_baseline=seen["baseline"][0][name][1]))
    return dict(rows=rows, rounds=rounds, repeats=repeats, baseline=str(baseline))


def _cost_section(cost):
    rows = cost["rows"]
    ta, tb = sum(r["checks"] for r in rows), sum(r["baseline"] for r in rows)
    L = ["## Cost of the checks", "",
         f"benchmarks/speed.py's cases (numba, one thread), each the best of {cost.get('repeats', 3)} warm "
         "solve(s), with this tree and "
         f"with main's code ({cost['rounds']} alternating pairs of processes; the best of each): whole solve [s], "
         "Newton iterations (tangent assemblies).", "",
         f"**Total {ta:.3f} s against {tb:.3f} s: {ta / tb - 1:+.1%}.**", "",
         "| case | with the checks s | main s | ratio | iterations (main) |", "|---|---:|---:|---:|---:|"]
    for r in rows:
        L.append(f"| {r['case']} | {r['checks']:.3f} | {r['baseline']:.3f} | {r['ratio']:.3f} | "
                 f"{r['iterations']} ({r['iterations_baseline']}) |")
    return L + [""]


CRITICAL_CASES = ("sze-hinged-roof", "sze-hinged-roof-6.35", "ltb-strip")
DLAM0 = (0.5, 0.2, 0.1, 0.05, 0.02, 0.01)


def _critical_run(name, dlam0, tol):
    from core_se3.catalogue import run_case
    from core_se3.solvers import arc_length
    if name == "ltb-strip":
        res = arc_length(ltb_strip(), lam_end=1.0, dlam0=dlam0, stability=True, critical_tol=tol)
    else:
        _, res, _ = run_case(name, dlam0=dlam0, critical_tol=tol)
    return [dict(kind=c.kind, lam=float(c.lam), accuracy=c.accuracy) for c in res.critical_points], res


def critical_part():
    from core_se3.errors import CoreSE3Error
    rows = []
    for name in CRITICAL_CASES:
        ref, _ = _critical_run(name, 0.01, 1e-6)
        row = dict(case=name, reference=ref, runs={})
        for d in DLAM0:
            t0 = time.perf_counter()
            try:
                cps, res = _critical_run(name, d, 1e-3)
                row["runs"][str(d)] = dict(critical=cps, time=time.perf_counter() - t0,
                                           bisections=sum(e.get("bisections", 0) for e in res.log))
            except CoreSE3Error as exc:
                row["runs"][str(d)] = dict(message=" ".join(str(exc).split()))
            print("  critical", name, d, row["runs"][str(d)], flush=True)
        rows.append(row)
    return rows


# ---------------------------------------------------------------------------- report ------
def _cell(c, ref):
    st = c["status"]
    if st == "ok":
        tag = "ref" if ref else {"same": "=", "tol": "= at tol"}.get(c.get("verdict"), "**DIFFERS**")
        extra = f", {c['rejected']} rejected" if c.get("rejected") else ""
        if c.get("critical"):              # passed and recorded (limit_check off, or arc length)
            extra += ", passed " + ", ".join(c["critical"][:2]) + (" ..." if len(c["critical"]) > 2 else "")
        d = "" if ref or "d" not in c else f" {c['d']:.0e}"
        if "d_tight" in c:
            d += f"; tolerances / {TIGHT:g}: " + (f"{c['d_tight']:.0e}" if c["d_tight"] is not None
                                                 else "stop: " + c.get("tight_message", "")[:60])
        return f"{tag}{d} ({c['iterations']} it{extra})"
    msg = c.get("message", "")
    return f"{st}: {msg[:150]}" + ("..." if len(msg) > 150 else "")


def write(data):
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "robustness.json").write_text(json.dumps(data, indent=1))
    L = _steps_section(data.get("rows", []), data["meta"])
    if data.get("zhao"):
        L += _zhao_section(data["zhao"])
    if data.get("translation"):
        L += _translation_section(data["translation"])
    if data.get("critical"):
        L += _critical_section(data["critical"])
    if data.get("candidates"):
        L += _candidates_section(data["candidates"])
    if data.get("cost"):
        L += _cost_section(data["cost"])
    if data.get("note"):
        L += ["## Closing note", "", data["note"], ""]
    meta = data["meta"]
    L += [f"Machine: python {meta['python']}, numpy {meta['numpy']}", ""]
    (RESULTS / "robustness.md").write_text("\n".join(L))


def _zhao_section(rows):
    L = ["## Zhao cantilever in one load step", "",
         f"q = A Br Ba L^2 / (mu0 E I) (L 17.2, h 0.42, nu 0; Ba = 7.8328 mT q / 20), ONE requested load step; "
         f"the tip's error against `3_magnetic_perpendicular_field` (within {ZHAO_TOL:.1%}: the target), the "
         "Newton iterations of all tries and in brackets the tries the path check refused.", ""]
    worst = max((r["error"] for r in rows if "error" in r), default=float("nan"))
    bad = [r for r in rows if "error" in r and r["error"] > ZHAO_TOL]
    stops = [r for r in rows if "message" in r]
    L.append(f"**{len(rows)} runs: largest error {worst:.3%}; {len(bad)} above {ZHAO_TOL:.1%}; "
             f"{len(stops)} refused.**")
    L += ["", "| q | " + " | ".join(f"{n}x1" for n in ZHAO_MESHES) + " |", "|---:|" + "---|" * len(ZHAO_MESHES)]
    by = {(r["q"], r["nx"]): r for r in rows}
    for q in sorted({r["q"] for r in rows}):
        cells = []
        for n in ZHAO_MESHES:
            r = by.get((q, n))
            if r is None:
                cells.append("")
            elif "error" in r:
                cells.append(f"{r['error']:.3%} ({r['iterations']} it, {r['tries']} tries"
                             + (f", {r['rejected']} refused" if r["rejected"] else "") + ")")
            else:
                cells.append("stop: " + r["message"][:80])
        L.append(f"| {q} | " + " | ".join(cells) + " |")
    return L + [""]


def _translation_section(rows):
    L = ["## Translation: the README cantilever moved to x0", "",
         "16x1, P = 4, 10 load steps; the tip displacement and the Newton iterations of each step, and the "
         "largest difference of u from x0 = 0.", "",
         "| x0 | tip u | iterations per step | max |u - u(x0 = 0)| |", "|---:|---|---|---:|"]
    u0 = next((r["u"] for r in rows if r["x0"] == 0 and "u" in r), None)
    for r in rows:
        if "u" in r:
            d = max(abs(a - b) for a, b in zip(r["u"], u0)) if u0 else float("nan")
            L.append(f"| {r['x0']:g} | ({', '.join(f'{v:.10g}' for v in r['u'])}) | {r['iterations']} | {d:.1e} |")
        else:
            L.append(f"| {r['x0']:g} | stop: {r['message'][:120]} | | |")
    return L + [""]


def _critical_section(rows):
    L = ["## Critical load factors from any first step", "",
         "Arc length with stability (the default), first step dlam0 as given: the first critical point's load "
         "factor, its relative distance from the reference (dlam0 0.01, critical_tol 1e-6), and the bisections "
         "that located it (target: within 1e-3).", "",
         "| case | reference | " + " | ".join(f"dlam0 {d:g}" for d in DLAM0) + " |",
         "|---|---|" + "---|" * len(DLAM0)]
    for r in rows:
        ref = r["reference"][0]["lam"] if r["reference"] else None
        cells = []
        for d in DLAM0:
            x = r["runs"].get(str(d), {})
            if x.get("critical"):
                lam = x["critical"][0]["lam"]
                cells.append(f"{lam:.6f} ({abs(lam - ref) / abs(ref):.1e}, {x['bisections']} bis.)" if ref else f"{lam:.6f}")
            else:
                cells.append(x.get("message", "none")[:80])
        kind = r["reference"][0]["kind"] if r["reference"] else ""
        L.append(f"| {r['case']} | {kind} {ref:.7f} | " + " | ".join(cells) + " |" if ref is not None
                 else f"| {r['case']} | none | " + " | ".join(cells) + " |")
    return L + [""]


def _steps_section(rows, meta):
    n_diff = sum(c.get("verdict") == "DIFFERS" for r in rows for c in r["runs"].values())
    n_ok = sum(c.get("verdict") == "same" for r in rows for c in r["runs"].values())
    n_tol = sum(c.get("verdict") == "tol" for r in rows for c in r["runs"].values())
    n_ref = sum(c.get("verdict") == "ref" for r in rows for c in r["runs"].values())
    n_stop = sum(c["status"] == "stop" for r in rows for c in r["runs"].values())
    L = ["# Step-size independence: every case and example with 1, 2, default and 4x default steps", "",
         f"`python benchmarks/robustness.py` on {meta['date']} ({meta['machine']}, backend {meta['backend']}, "
         f"{meta['solver_checks']})", "",
         f"Each final state is compared with the finest run that finished (*ref*: 4x default, else the "
         f"default): d = max(max |x - x_ref| / U, max |R - R_ref|_F), U the largest displacement along the "
         f"reference path; `=` agrees to d <= {SAME:g}; `= at tol`: d > {SAME:g}, but the run and its "
         f"reference solved again with Newton's rtol/dtol and the contacts' gap tolerance divided by {TIGHT:g} "
         f"agree to {SAME:g} and to a tenth of d (the difference is the stated tolerances, not another state); "
         "**DIFFERS** is a converged-looking wrong answer; "
         "`stop:` the run stopped with that message. In brackets: the Newton iterations of the run (all "
         "tries) and the tries the path check rejected.", "",
         f"**{len(rows)} cases, {n_ref} reference runs; {n_ok} runs agree with their reference, {n_tol} agree to their tolerances, {n_stop} stopped "
         f"with a message, {n_diff} differ.**", "",
         "| case | default | 1 step | 2 steps | default | 4x default |", "|---|---:|---|---|---|---|"]
    for r in rows:
        d = r["default"]
        cells = []
        for n in (1, 2, d, 4 * d):
            c = r["runs"].get(str(n))
            cells.append("" if c is None else _cell(c, n == r["reference"]))
        if d in (1, 2):
            cells[2] = "(as above)"
        L.append(f"| {r['case']} | {d} | " + " | ".join(cells) + " |")
    return L + [""]


def save(rows=None, **parts):
    import numpy
    from core_se3.backend import default_backend
    meta = dict(date=datetime.datetime.now().isoformat(timespec="seconds"),
                machine=f"{platform.processor() or platform.machine()}, nproc {os.cpu_count()}",
                python=platform.python_version(), numpy=numpy.__version__, backend=default_backend(),
                solver_checks="path_check and limit_check on (the defaults)")
    path = RESULTS / "robustness.json"
    RESULTS.mkdir(parents=True, exist_ok=True)
    with open(RESULTS / ".robustness.lock", "w") as lock:     # parts may run in parallel processes
        fcntl.flock(lock, fcntl.LOCK_EX)
        _merge(path, rows, meta, parts)


def _merge(path, rows, meta, parts):
    data = json.loads(path.read_text()) if path.exists() else {}
    if rows:
        mine = {r["case"] for r in rows}
        order = {c: i for i, c in enumerate(all_cases())}
        data["rows"] = sorted([r for r in data.get("rows", []) if r["case"] not in mine] + list(rows),
                              key=lambda r: order.get(r["case"], len(order)))
        data["meta"] = meta
    data.update(parts)
    data.setdefault("meta", meta)
    write(data)


def main():
    from core_se3.backend import pin_for_timing
    pin_for_timing()
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--steps", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--out", help=argparse.SUPPRESS)
    ap.add_argument("--tight", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--cases", nargs="*", default=None, help="case names or example:NAME (default all)")
    ap.add_argument("--timeout", type=float, default=900.0, help="per run [s]")
    ap.add_argument("--part", nargs="*", default=["steps"],
                    choices=("steps", "zhao", "translation", "critical", "candidates", "cost"))
    ap.add_argument("--baseline", help="a checkout of main (--part cost)")
    ap.add_argument("--cost-child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--rounds", type=int, default=3, help="alternating pairs of processes (--part cost)")
    ap.add_argument("--repeats", type=int, default=3, help="warm solves per case and process (--part cost)")
    a = ap.parse_args()
    if a.child:
        print("RESULT " + json.dumps(child(a.child, a.steps, a.out, a.tight)))
        return 0
    if a.cost_child:
        print("RESULT " + json.dumps(cost_child(a.repeats)))
        return 0
    parts = dict(zhao=zhao_part, translation=translation_part, critical=critical_part,
                 candidates=candidates_part, cost=lambda: cost_part(a.baseline, a.rounds, a.repeats))
    for part in a.part:
        if part in parts:
            save(**{part: parts[part]()})
    if "steps" in a.part:
        rows = []
        with tempfile.TemporaryDirectory() as work:
            for name in a.cases or all_cases():
                rows.append(study(name, a.timeout, work))
                save(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
