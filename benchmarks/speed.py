#!/usr/bin/env python3
"""Run time of whole solves on both backends, 1 and 2 threads (issue 13 acceptance).

For each case (catalogue cases at the meshes below and a 100x100 plate) and each configuration
(backend numba/numpy x threads 1/2), a child process -- with ``CORE_SE3_BACKEND``,
``NUMBA_NUM_THREADS`` and the BLAS thread variables set, so nothing leaks between configurations
-- solves the case once to warm up (imports, numba compilation or cache load, first BLAS call)
and then times best-of-N further solves.  Reported per configuration: Newton iterations
(assemblies with a tangent), assembly and linear solve time per iteration, setup and the total.
``floor`` is the linear solve (factorisation + solve) per iteration: the cost a Newton iteration
cannot go below with a direct solver; ``asm/solve`` is how close the compiled path comes to it.

Then the README's main job (``core-se3 bench run cantilever-shear --plot --vtu --json``) is timed
as a whole process, cold (an empty numba cache: the first run after installing) and warm, with the
default backend ('auto', which keeps this small job on NumPy) and with numba forced.

    .venv/bin/python benchmarks/speed.py                     # everything (~15 min)
    .venv/bin/python benchmarks/speed.py --cases cantilever-shear rollup --no-numpy
    .venv-np2/bin/python benchmarks/speed.py --cases cantilever-shear   # without petsc4py

Writes ``benchmarks/results/speed.{md,json}``.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"

# name -> (mesh, description); None = the case's own mesh
CASES = {
    "cantilever-shear": ((16, 1), "catalogue, 10 load steps"),
    "rollup": ((10, 1), "catalogue, roll-up to 2 pi"),
    "arch-follower": ((40, 1), "catalogue, follower-loaded arch"),
    "torsion": ((20, 6), "catalogue, strip twisted by 2 turns"),
    "magnetic-cantilever": (None, "catalogue, Zhao et al. magnetic cantilever"),
    "magnetic-gripper": (None, "catalogue, cross-shaped gripper (unstructured)"),
    "sze-hemisphere": ((16, 16), "Sze et al. 2004, quarter hemisphere, arc length"),
    "sze-pinched-cylinder": ((48, 48), "Sze et al. 2004, octant pinched cylinder, arc length"),
    "plate-100x100": ((100, 100), "clamped square plate, end shear, 5 load steps"),
}
CONFIGS = [("numba", 1), ("numba", 2), ("numpy", 1), ("numpy", 2)]
THREAD_VARS = ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


# ----------------------------------------------------------------------- child process ----
def _plate(mesh):
    """A 100x100 flat plate 10 x 10 x 0.1 clamped on x = 0 under an end shear of 1/4 of the
    force that bends it through a quarter turn (a moderately nonlinear state)."""
    import core_se3 as cs
    nx, ny = mesh
    m = cs.mesh.rectangle(10.0, 10.0, nx, ny)
    mat = cs.Material(E=1.2e6, nu=0.3, h=0.1)
    p = cs.Problem(m, mat)
    p.clamp("x0")
    D = mat.E * mat.h ** 3 / 12.0 / (1 - mat.nu ** 2)
    p.add_edge_force("x1", (0.0, 0.0, 2.0 * D * 10.0 / 10.0 ** 2))   # P L^2 / (D b) = 2
    return p


def _iterations(res):
    its = [e.get("iterations") for e in res.log if isinstance(e, dict)]
    its = [i for i in its if isinstance(i, int)]
    return sum(its) if its else sum(s.iterations for s in res.steps)


def _solve_once(name, mesh):
    t0 = time.perf_counter()
    if name == "plate-100x100":
        p = _plate(mesh)
        t_setup = time.perf_counter() - t0
        res = p.solve(steps=5)
        res.timings["setup"] += t_setup
        err = None
    else:
        from core_se3.catalogue.run import run_case
        doc, res, _ = run_case(name, mesh=mesh)
        ref = doc.get("reference") or {}
        err = ref.get("error")
    total = time.perf_counter() - t0
    return dict(total=total, iterations=_iterations(res), error=err,
                **{k: float(res.timings.get(k, 0.0)) for k in ("setup", "assembly", "solve", "other")})


def child(name, mesh, budget):
    t0 = time.perf_counter()
    import core_se3                                            # noqa: F401
    t_import = time.perf_counter() - t0
    first = _solve_once(name, mesh)                            # warm-up: compile / cache load
    best, runs, spent = None, 0, 0.0
    while runs < 1 or (spent < budget and runs < 5):
        r = _solve_once(name, mesh)
        runs += 1
        spent += r["total"]
        if best is None or r["total"] < best["total"]:
            best = r
    best.update(first_total=first["total"], import_time=t_import, runs=runs)
    print("RESULT " + json.dumps(best))


# ---------------------------------------------------------------------- parent process ----
def run_config(name, mesh, backend, threads, budget, timeout):
    env = dict(os.environ, CORE_SE3_BACKEND=backend, PYTHONPATH=str(ROOT))
    env.update({v: str(threads) for v in THREAD_VARS})
    cmd = [sys.executable, __file__, "--child", name, "--budget", str(budget)]
    if mesh is not None:
        cmd += ["--mesh", f"{mesh[0]}x{mesh[1]}"]
    try:
        out = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return dict(status=f"timeout (> {timeout:.0f} s)")
    for line in out.stdout.splitlines():
        if line.startswith("RESULT "):
            return dict(status="ok", **json.loads(line[7:]))
    return dict(status="error", error=(out.stderr or out.stdout)[-2000:])


def main_job(cache_dir, outdir, backend=None):
    """Whole-process wall time of the README's main job (threads as the machine's default;
    backend: CORE_SE3_BACKEND for it, None = the default, 'auto')."""
    exe = Path(sys.executable).with_name("core-se3")
    cmd = ([str(exe)] if exe.exists() else [sys.executable, "-m", "core_se3"])
    cmd += ["bench", "run", "cantilever-shear", "--plot", f"{outdir}/c.png", "--vtu", f"{outdir}/c",
            "--json", f"{outdir}/c.json"]
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir), PYTHONPATH=str(ROOT))
    env.pop("CORE_SE3_BACKEND", None)
    if backend:
        env["CORE_SE3_BACKEND"] = backend
    # a default installation keeps Python's bytecode cache (pip compiles it at install); this
    # machine's shell sets PYTHONDONTWRITEBYTECODE=1, which would recompile core_se3's ~110
    # modules at every start (+0.15 s here)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    t = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, capture_output=True)
    wall = time.perf_counter() - t
    doc = json.loads(Path(f"{outdir}/c.json").read_text())
    return dict(wall=wall, solve=doc["timings"]["assembly"] + doc["timings"]["solve"]
                + doc["timings"]["other"], **{f"t_{k}": v for k, v in doc["timings"].items()})


def _fmt(x, scale=1.0, nd=3):
    return "n/a" if x is None else f"{x * scale:.{nd}f}"


def write_report(rows, jobs, meta):
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "speed.json").write_text(json.dumps(dict(meta=meta, rows=rows, main_job=jobs), indent=1))
    L = ["# core_se3 speed benchmark", "",
         f"`python benchmarks/speed.py` on {meta['date']} ({meta['machine']})", "",
         "Per case and configuration (backend, threads): Newton iterations (tangent assemblies), "
         "assembly and linear solve per iteration [ms], setup and whole solve [s] (best of the "
         "warm runs), error against the case's reference. *floor* = the linear solve: "
         "*asm/floor* = assembly per iteration / linear solve per iteration.", "",
         "| case | mesh | backend | thr | its | asm ms/it | solve ms/it | asm/floor | setup s | total s | error |",
         "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if r["status"] != "ok":
            L.append(f"| {r['case']} | {r['mesh']} | {r['backend']} | {r['threads']} | "
                     f"{r['status']} |  |  |  |  |  |  |")
            continue
        n = max(r["iterations"], 1)
        L.append(f"| {r['case']} | {r['mesh']} | {r['backend']} | {r['threads']} | {r['iterations']} | "
                 f"{_fmt(r['assembly'] / n, 1e3)} | {_fmt(r['solve'] / n, 1e3)} | "
                 f"{r['assembly'] / max(r['solve'], 1e-12):.2f} | {r['setup']:.3f} | {r['total']:.3f} | "
                 f"{'' if r['error'] is None else format(r['error'], '.2e')} |")
    # speed-ups numba vs numpy at equal threads
    L += ["", "Speed-up of the whole solve, numba over numpy (same threads), and two threads over one:", "",
          "| case | numpy/numba 1 thr | numpy/numba 2 thr | numba 1thr/2thr (assembly) |", "|---|---:|---:|---:|"]
    by = {(r["case"], r["backend"], r["threads"]): r for r in rows if r["status"] == "ok"}
    for case in dict.fromkeys(r["case"] for r in rows):
        def ratio(a, b, key="total"):
            return f"{a[key] / b[key]:.2f}" if a and b and b[key] > 0 else "n/a"
        L.append(f"| {case} | {ratio(by.get((case, 'numpy', 1)), by.get((case, 'numba', 1)))} | "
                 f"{ratio(by.get((case, 'numpy', 2)), by.get((case, 'numba', 2)))} | "
                 f"{ratio(by.get((case, 'numba', 1)), by.get((case, 'numba', 2)), 'assembly')} |")
    if jobs:
        L += ["", "README main job (`core-se3 bench run cantilever-shear --plot --vtu --json`), whole "
              "process wall time [s]; *solve* = assembly + linear solve + other inside the solver:", "",
              "| run | wall s | setup s | solve s | wall - solve s |", "|---|---:|---:|---:|---:|"]
        for k, j in jobs.items():
            L.append(f"| {k} | {j['wall']:.2f} | {j['t_setup']:.3f} | {j['solve']:.3f} | {j['wall'] - j['solve']:.2f} |")
        for k, j in jobs.items():
            if "overheads" in j:
                L += ["", f"{k}: the best of 3 runs; wall - solve of the three: "
                      + ", ".join(f"{v:.2f}" for v in j["overheads"]) + " s."]
    L += ["", "Machine: " + ", ".join(f"{k} {v}" for k, v in meta.items() if k not in ("date",)), ""]
    (RESULTS / "speed.md").write_text("\n".join(L))
    print("\n".join(L))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--mesh", help=argparse.SUPPRESS)
    ap.add_argument("--cases", nargs="*", default=list(CASES))
    ap.add_argument("--no-numpy", action="store_true", help="numba configurations only")
    ap.add_argument("--no-main-job", action="store_true")
    ap.add_argument("--main-job-only", action="store_true",
                    help="time the main job only; keep the case rows of the last speed.json")
    ap.add_argument("--budget", type=float, default=3.0, help="seconds of warm runs per configuration")
    ap.add_argument("--timeout", type=float, default=1800.0)
    a = ap.parse_args()
    if a.child:
        mesh = tuple(int(v) for v in a.mesh.split("x")) if a.mesh else None
        return child(a.child, mesh, a.budget)
    rows = []
    if a.main_job_only:
        rows, a.cases = json.loads((RESULTS / "speed.json").read_text())["rows"], []
    for name in a.cases:
        mesh, desc = CASES[name]
        for backend, threads in CONFIGS:
            if a.no_numpy and backend == "numpy":
                continue
            r = run_config(name, mesh, backend, threads, a.budget, a.timeout)
            r.update(case=name, mesh="default" if mesh is None else f"{mesh[0]}x{mesh[1]}",
                     backend=backend, threads=threads, description=desc)
            print(name, backend, threads, {k: r.get(k) for k in ("status", "iterations", "total", "error")},
                  flush=True)
            rows.append(r)
    jobs = {}
    if not a.no_main_job:
        with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as out:
            # the default backend ('auto': this 16-element job stays on NumPy), then numba
            # forced: its cold run is the first-run compile of the kernels the job uses
            for label, backend in (("default (auto)", None), ("numba", "numba")):
                jobs[f"{label}, cold (empty numba cache)"] = main_job(cache, out, backend)
                warm = [main_job(cache, out, backend) for _ in range(3)]
                jobs[f"{label}, warm"] = min(warm, key=lambda j: j["wall"] - j["solve"])
                jobs[f"{label}, warm"]["overheads"] = [j["wall"] - j["solve"] for j in warm]
    import numpy
    meta = dict(date=datetime.datetime.now().isoformat(timespec="seconds"),
                machine=f"{platform.processor() or platform.machine()}, nproc {os.cpu_count()}",
                python=platform.python_version(), numpy=numpy.__version__)
    try:
        import numba
        meta["numba"] = numba.__version__
    except ImportError:
        meta["numba"] = "not installed"
    write_report(rows, jobs, meta)


if __name__ == "__main__":
    sys.exit(main())
