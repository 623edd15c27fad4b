#!/usr/bin/env python3
"""Reach and cost of load-stepped Newton, displacement vs mixed (MIP) iteration (issue 14).

For each case at its own thickness (L/h as in the catalogue, ~100) and at L/h = 1e4 (the loads
rescaled so that the same deformation is asked for: bending loads x (h'/h)^3, magnetic fields
x (h'/h)^2, curvatures and prescribed angles unchanged), and for each iteration
(``NewtonOptions.iteration`` = 'displacement', the plain Newton of the first round, and 'mip'):

* **largest single step**: the largest fraction s of the case's full load, among 1, 1/2, ...,
  1/64, that one load step with no cut-back reaches (s = 1: the whole path in one step);
* **path**: the case's own load steps (cut-backs allowed): tries, failed tries, Newton
  iterations, linear solves and solve time to the end of the path.

Every configuration runs in a child process with a time limit.  Writes
``benchmarks/results/reach.{md,json}``.  (The step-size independence of every case and example,
issue 29, is ``benchmarks/robustness.py``.)

    .venv/bin/python benchmarks/reach.py                  # all cases (~15 min)
    .venv/bin/python benchmarks/reach.py --cases rollup cantilever-shear --no-thin
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
ITERATIONS = ("displacement", "mip")
FRACTIONS = [1.0, 0.5, 0.25, 0.125, 1 / 16, 1 / 32, 1 / 64]

# case -> (length key, {load key: exponent of h'/h}, steps of the path or None = the case's,
#          mesh or None); a load key with exponent 0 is a normalised load (k, angle)
CASES = {
    "rollup": ("L", {"k": 0}, None, None),
    "cantilever-shear": ("L", {"load_max": 3}, None, None),
    "pressure-strip": ("L", {"load_max": 3}, None, None),
    "arch-follower": ("R", {"load_max": 3}, None, None),
    "torsion": ("L", {"angle": 0}, None, None),
    "torsion-rollup": ("L", {}, None, None),
    "magnetic-cantilever": ("L", {"Ba_max": 2}, None, None),
    "magnetic-gripper": ("finger_length", {"Ba_max": 2}, None, None),
    "sze-slit-annular": ("r_out", {"load_max": 3}, 20, None),
    "sze-hemisphere": ("R", {"load_max": 3}, 20, None),
    "sze-pullout": ("R", {"load_max": 3}, 20, None),
}
SZE_LOAD_CONTROL = ("sze-slit-annular", "sze-hemisphere", "sze-pullout")   # load control here


# ----------------------------------------------------------------------------- child ------
def _overrides(name, thin, frac):
    from core_se3.catalogue import case_params, get_case
    lkey, loads, _, _ = CASES[name]
    p = case_params(get_case(name), None)
    ov = {}
    ratio = 1.0
    if thin:
        h_new = p[lkey] / 1e4
        ratio = h_new / p["h"]
        ov["h"] = h_new
    for key, expo in loads.items():
        ov[key] = p[key] * ratio ** expo * (frac if frac is not None else 1.0)
    if frac is not None and not loads:
        raise ValueError(f"{name}: no load parameter to scale")
    return ov, p[lkey] / (ov.get("h", p["h"]))


def _solve(name, thin, frac, iteration, steps, max_cutbacks):
    from core_se3.catalogue import build_problem, case_params, get_case, run_case
    ov, slender = _overrides(name, thin, frac)
    t0 = time.perf_counter()
    kw = dict(iteration=iteration, max_cutbacks=max_cutbacks)
    if name in SZE_LOAD_CONTROL:
        case = get_case(name)
        prob = build_problem(case, case_params(case, ov))
        res = prob.solve(steps=steps or CASES[name][2], control="load", **kw)
    else:
        _, res, _ = run_case(name, overrides=ov, steps=steps, **kw)
    dt = time.perf_counter() - t0
    log = res.log
    return dict(slenderness=slender, tries=len(log), failed=sum(not e["converged"] for e in log),
                iterations=sum(e["iterations"] for e in log),
                linear_solves=sum(e.get("linear_solves", 0) for e in log), time=dt,
                solve_time=res.timings["assembly"] + res.timings["solve"] + res.timings["other"])


def child(args):
    name, thin, iteration, mode = args.child, args.thin, args.iteration, args.mode
    from core_se3.errors import CoreSE3Error
    if mode == "path":
        try:
            out = dict(status="ok", **_solve(name, thin, None, iteration, None, 12))
        except CoreSE3Error as exc:
            out = dict(status="failed", error=str(exc)[:300])
    elif not CASES[name][1]:
        out = dict(status="n/a (no load parameter to scale)")
    else:
        out = dict(status="ok", largest=None, tries=[])
        for frac in FRACTIONS:
            try:
                r = _solve(name, thin, frac, iteration, 1, 0)
                out["tries"].append(dict(fraction=frac, converged=True, iterations=r["iterations"]))
                out["largest"] = frac
                out["iterations_at_largest"] = r["iterations"]
                break
            except CoreSE3Error as exc:
                out["tries"].append(dict(fraction=frac, converged=False, error=str(exc)[:160]))
    print("RESULT " + json.dumps(out))


# ---------------------------------------------------------------------------- parent ------
def run(name, thin, iteration, mode, timeout):
    cmd = [sys.executable, __file__, "--child", name, "--iteration", iteration, "--mode", mode]
    if thin:
        cmd.append("--thin")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return dict(status=f"timeout (> {timeout:.0f} s)")
    for line in out.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    return dict(status="error", error=(out.stderr or out.stdout)[-800:])


def _frac(x):
    if x is None:
        return "< 1/64"
    return "1" if x == 1 else f"1/{round(1 / x)}"


def save(rows):
    """Merge ``rows`` into reach.json (rows of other cases kept, e.g. from a run of the
    other cases alongside; a file lock serialises the writers) and rewrite reach.md."""
    import fcntl
    import numpy
    from core_se3.backend import default_backend
    meta = dict(date=datetime.datetime.now().isoformat(timespec="seconds"),
                machine=f"{platform.processor() or platform.machine()}, nproc {os.cpu_count()}",
                python=platform.python_version(), numpy=numpy.__version__, backend=default_backend())
    RESULTS.mkdir(parents=True, exist_ok=True)
    key = lambda r: (r["case"], r["thin"], r["iteration"])          # noqa: E731
    with open(RESULTS / ".reach.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        path = RESULTS / "reach.json"
        old = json.loads(path.read_text())["rows"] if path.exists() else []
        mine = {key(r) for r in rows}
        merged = [r for r in old if key(r) not in mine] + list(rows)
        order = {name: i for i, name in enumerate(CASES)}
        merged.sort(key=lambda r: (order.get(r["case"], len(order)), r["thin"], ITERATIONS.index(r["iteration"])))
        write(merged, meta)


def write(rows, meta):
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "reach.json").write_text(json.dumps(dict(meta=meta, rows=rows), indent=1))
    L = ["# Reach of load-stepped Newton: displacement vs mixed (MIP) iteration", "",
         f"`python benchmarks/reach.py` on {meta['date']} ({meta['machine']}, backend {meta['backend']})", "",
         "*largest step*: the largest fraction of the case's full load reached in ONE load step with no "
         "cut-back (its Newton iterations in brackets); *path*: the case's own load steps with cut-backs: "
         "tries (failed), Newton iterations, linear solves, solve time.", "",
         "| case | L/h | iteration | largest step | path tries (failed) | iterations | linear solves | solve s |",
         "|---|---:|---|---|---:|---:|---:|---:|"]
    for r in rows:
        one, path = r["single"], r["path"]
        big = (f"{_frac(one.get('largest'))} ({one.get('iterations_at_largest', '-')} it)"
               if one.get("status") == "ok" else one.get("status"))
        if path.get("status") == "ok":
            cols = (f"{path['tries']} ({path['failed']}) | {path['iterations']} | {path['linear_solves']} | "
                    f"{path['solve_time']:.2f}")
        else:
            cols = f"{path.get('status')}: {path.get('error', '')[:60]} | | | "
        L.append(f"| {r['case']} | {r['slenderness']:.0f} | {r['iteration']} | {big} | {cols} |")
    L += ["", f"Machine: python {meta['python']}, numpy {meta['numpy']}", ""]
    (RESULTS / "reach.md").write_text("\n".join(L))
    print("\n".join(L))


def main():
    from core_se3.backend import pin_for_timing
    pin_for_timing()          # time the compiled product, not 'auto''s NumPy start
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--iteration", default="mip", help=argparse.SUPPRESS)
    ap.add_argument("--mode", default="path", help=argparse.SUPPRESS)
    ap.add_argument("--thin", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--cases", nargs="*", default=list(CASES))
    ap.add_argument("--no-thin", action="store_true", help="only the catalogue thickness")
    ap.add_argument("--timeout", type=float, default=600.0)
    a = ap.parse_args()
    if a.child:
        return child(a)
    rows = []
    for name in a.cases:
        for thin in ((False,) if a.no_thin else (False, True)):
            for it in ITERATIONS:
                single = run(name, thin, it, "single", a.timeout)
                path = run(name, thin, it, "path", a.timeout)
                sl = path.get("slenderness") or (1e4 if thin else float("nan"))
                row = dict(case=name, thin=thin, slenderness=sl, iteration=it, single=single, path=path)
                print(name, "thin" if thin else "", it, _frac(single.get("largest")),
                      {k: path.get(k) for k in ("status", "tries", "failed", "iterations", "linear_solves")},
                      flush=True)
                rows.append(row)
                save(rows)                   # after every row: a long run keeps what it measured
    save(rows)


if __name__ == "__main__":
    sys.exit(main())
