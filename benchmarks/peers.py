#!/usr/bin/env python3
"""core_se3 side by side with Kratos Multiphysics (issues 13 and 14): run time at equal error and
the reach of one load step, on this machine, in one run.

* **cantilever-shear** (P L^2/EI to 4 in 10 load steps, Kirchhoff elastica reference
  ``1_cantilever_tip_force_kirchhoff``, the catalogue's error measure): both codes on a sequence
  of nx x 1 meshes; per mesh the tip error, the solve time (inside the process: core_se3
  assembly + solve + other; Kratos ``t_solve``) and the whole-process wall time of a command
  that solves and reports (core_se3: ``core-se3 bench run cantilever-shear --mesh NXx1 --json``;
  Kratos: ``kratos_strip.py``); the times to 0.1 % error are interpolated in log-log between the
  meshes that bracket it.
* **rollup 10x1 in ONE load step** to k = 0.25, 0.5, 1 (a full circle): Newton iterations and
  solve time, both codes.

Kratos is not a dependency: it runs from its own venv (``../shared/peers/README.md``:
``pip install KratosMultiphysics==10.4.0 KratosStructuralMechanicsApplication==10.4.0
KratosLinearSolversApplication==10.4.0``), given by ``--kratos-python``; the peer models are
``../shared/peers/kratos_strip.py``.  Every run uses one thread (OMP/OpenBLAS/numba = 1) and is
repeated ``--repeats`` times (fastest kept).  Writes ``benchmarks/results/peers.{md,json}``.

    .venv/bin/python benchmarks/peers.py --kratos-python /work/peers/kratos-venv/bin/python
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
PEERS = ROOT.parent / "shared" / "peers"
MESHES = (4, 6, 8, 12, 16, 24, 32)
ONE_THREAD = {v: "1" for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                               "NUMBA_NUM_THREADS")}
TARGET = 1e-3


def _env(backend=None):
    env = dict(os.environ, PYTHONPATH=str(ROOT), **ONE_THREAD)
    env.pop("CORE_SE3_BACKEND", None)
    if backend:                          # None: core_se3's default ('auto')
        env["CORE_SE3_BACKEND"] = backend
    # as a default installation: Python's bytecode cache on (this machine's shell sets
    # PYTHONDONTWRITEBYTECODE=1, +0.15 s per core_se3 start; Kratos is compiled code)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def _wall(cmd, repeats, cwd=None, backend=None):
    best, out = math.inf, None
    for _ in range(repeats):
        t = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True, env=_env(backend), cwd=cwd)
        dt = time.perf_counter() - t
        if p.returncode != 0:
            raise RuntimeError(f"{' '.join(map(str, cmd))} failed: {p.stderr[-1500:]}")
        if dt < best:
            best, out = dt, p.stdout
    return best, out


def _kratos_result(stdout):
    line = next(ln for ln in stdout.splitlines() if ln.startswith("RESULT "))
    return json.loads(line[7:])


def cantilever_error(lams, u_tip):
    """The catalogue's error of tip displacements (k, 3) at load factors lams (P = 4 lam)."""
    from core_se3.catalogue import elastica_entry, error_against_reference
    ref = elastica_entry("1_cantilever_tip_force_kirchhoff")
    L, EI = 10.0, 1.2e6 * 1.0 * 0.1 ** 3 / 12
    q = [0.0] + [4.0 * lam * L ** 2 / EI for lam in lams]
    d = [[0.0, 0.0]] + [[u[0] / L, u[2] / L] for u in u_tip]
    return error_against_reference(q, d, dict(load=ref["load"], u=ref["tip"]["u"], v=ref["tip"]["v"]))[0]


def core_cantilever(nx, repeats):
    with tempfile.TemporaryDirectory() as tmp:
        exe = Path(sys.executable).with_name("core-se3")
        cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "core_se3"]
        run = cmd + ["bench", "run", "cantilever-shear", "--mesh", f"{nx}x1", "--json", f"{tmp}/c.json"]
        wall_numba, _ = _wall(run, repeats, backend="numba")
        wall, _ = _wall(run, repeats)                   # the default backend, last: its c.json
        doc = json.loads(Path(f"{tmp}/c.json").read_text())
    solve_once = sum(doc["timings"][k] for k in ("assembly", "solve", "other"))
    code = ("import json, time, sys\nfrom core_se3.catalogue import run_case\n"
            f"run_case('cantilever-shear', mesh=({nx}, 1))\nbest = None\n"
            f"for _ in range({max(repeats, 3)}):\n"
            f"    d, r, _ = run_case('cantilever-shear', mesh=({nx}, 1))\n"
            "    t = r.timings['assembly'] + r.timings['solve'] + r.timings['other']\n"
            "    best = t if best is None or t < best else best\n"
            "print('RESULT ' + json.dumps(dict(solve=best, its=sum(s.iterations for s in r.steps))))")
    _, out = _wall([sys.executable, "-c", code], 1, backend="numba")
    r = _kratos_result(out)
    return dict(nx=nx, error=doc["reference"]["error"], solve=r["solve"], wall=wall, iterations=r["its"],
                wall_numba=wall_numba, solve_once=solve_once)


def kratos_cantilever(py, nx, repeats):
    wall, out = _wall([py, str(PEERS / "kratos_strip.py"), "--problem", "shear", "--elem", "thick",
                       "--nx", str(nx), "--steps", "10"], repeats)
    r = _kratos_result(out)
    err = cantilever_error([s["lam"] for s in r["steps"]], [s["u"] for s in r["steps"]])
    return dict(nx=nx, error=err, solve=r["t_solve"], wall=wall, iterations=r["total_iterations"],
                converged=r["all_converged"])


def time_to(rows, key, target=TARGET):
    """Time (key) to reach the error target, log-log between the bracketing meshes."""
    pts = sorted((r["error"], r[key]) for r in rows if r.get("error") and r["error"] > 0)
    for (e1, t1), (e2, t2) in zip(pts, pts[1:]):
        if e1 <= target <= e2:
            w = (math.log(target) - math.log(e1)) / (math.log(e2) - math.log(e1))
            return math.exp(math.log(t1) + w * (math.log(t2) - math.log(t1)))
    return None


def rollup_one_step(py, k, repeats):
    code = ("import json\nfrom core_se3.catalogue import run_case\n"
            f"run_case('rollup', overrides=dict(k={k}), steps=1)\nbest = None\n"
            f"for _ in range({max(repeats, 3)}):\n"
            f"    d, r, _ = run_case('rollup', overrides=dict(k={k}), steps=1, max_cutbacks=0)\n"
            "    t = r.timings['assembly'] + r.timings['solve'] + r.timings['other']\n"
            "    best = t if best is None or t < best else best\n"
            "print('RESULT ' + json.dumps(dict(solve=best, its=r.final.iterations, "
            "error=d['reference']['error'] if d.get('reference') else None)))")
    _, out = _wall([sys.executable, "-c", code], 1, backend="numba")
    core = _kratos_result(out)
    kr = None
    if py:
        _, kout = _wall([py, str(PEERS / "kratos_strip.py"), "--problem", "rollup", "--elem", "thick",
                         "--nx", "10", "--steps", "1", "--k", str(k)], repeats)
        r = _kratos_result(kout)
        kr = dict(its=r["total_iterations"], solve=r["t_solve"], converged=r["all_converged"])
    return dict(k=k, core=core, kratos=kr)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kratos-python", default=str(ROOT.parent / "peers" / "kratos-venv" / "bin" / "python"))
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    py = a.kratos_python if Path(a.kratos_python).exists() else None
    if py is None:
        print(f"Kratos not found at {a.kratos_python}: only core_se3 runs")
    core, krat = [], []
    for nx in MESHES:
        core.append(core_cantilever(nx, a.repeats))
        if py:
            krat.append(kratos_cantilever(py, nx, a.repeats))
        print(nx, core[-1], krat[-1] if krat else "", flush=True)
    roll = [rollup_one_step(py, k, a.repeats) for k in (0.25, 0.5, 1.0)]
    t = {"core_se3": {k: time_to(core, k) for k in ("solve", "wall", "solve_once", "wall_numba")},
         "kratos": {k: time_to(krat, k) for k in ("solve", "wall")}}
    meta = dict(date=datetime.datetime.now().isoformat(timespec="seconds"), nproc=os.cpu_count(),
                load=os.getloadavg())
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "peers.json").write_text(json.dumps(dict(meta=meta, core=core, kratos=krat, rollup=roll,
                                                        time_to_target=t), indent=1))
    L = ["# core_se3 and Kratos Multiphysics side by side", "",
         f"`python benchmarks/peers.py` on {meta['date']} (2 shared cores, one thread per run, fastest of "
         f"{a.repeats}; load average {meta['load'][0]:.2f}).", "",
         "## cantilever-shear, 10 load steps, error against the Kirchhoff elastica", "",
         "core_se3: *solve* warm on numba (the best of repeated solves in one process), *once* the "
         "solve inside the one-shot `core-se3 bench run` process, *whole process* that command's wall "
         "time with the default backend ('auto', which keeps these small jobs on NumPy) and with "
         "`CORE_SE3_BACKEND=numba`.", "",
         "| nx | core_se3 error | its | solve s | once s | whole process s | numba: whole s | Kratos error | its | solve s | whole process s |",
         "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for i, c in enumerate(core):
        k = krat[i] if krat else None
        L.append(f"| {c['nx']} | {100 * c['error']:.4f} % | {c['iterations']} | {c['solve']:.4f} | "
                 f"{c['solve_once']:.4f} | {c['wall']:.2f} | {c['wall_numba']:.2f} | "
                 + (f"{100 * k['error']:.4f} % | {k['iterations']} | {k['solve']:.4f} | {k['wall']:.2f} |" if k else "| | | |"))

    def f(x):
        return "not reached" if x is None else f"{x:.4f} s"
    L += ["", f"Time to {100 * TARGET:g} % error (log-log between the bracketing meshes):", "",
          "| | core_se3 | Kratos | core / Kratos |", "|---|---:|---:|---:|"]
    for key, kkey, label in (("solve", "solve", "solve (core_se3 warm, numba)"),
                             ("solve_once", "solve", "solve (core_se3 once, default)"),
                             ("wall", "wall", "whole process (core_se3 default)"),
                             ("wall_numba", "wall", "whole process (core_se3 numba)")):
        c, k = t["core_se3"][key], t["kratos"].get(kkey) if krat else None
        L.append(f"| {label} | {f(c)} | {f(k)} | {c / k:.2f} |" if c and k else f"| {label} | {f(c)} | {f(k)} | |")
    L += ["", "## rollup 10x1 from the flat strip in one load step", "",
          "| k | tip rotation | core_se3 its | solve s | Kratos its | solve s |", "|---:|---:|---:|---:|---:|---:|"]
    for r in roll:
        kr = r["kratos"] or {}
        L.append(f"| {r['k']} | {2 * r['k']:g} pi | {r['core']['its']} | {r['core']['solve']:.4f} | "
                 f"{kr.get('its', '')} | {kr.get('solve', float('nan')):.4f} |")
    L.append("")
    (RESULTS / "peers.md").write_text("\n".join(L))
    print("\n".join(L))


if __name__ == "__main__":
    sys.exit(main())
