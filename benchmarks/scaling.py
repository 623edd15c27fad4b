#!/usr/bin/env python3
"""Assembly vs. sparse-solve scaling of the default SE(3) shell element (issues 2 and 13).

For square-ish flat plates of 10^2, 10^3, 10^4 and 10^5 quads (clamped at x = 0, dead edge force
on x = L) at a deformed state g = g0 exp(eta) (random twist eta on the free nodes), this times, in
one run:

* setup     -- the one-time ``Assembler`` construction (sparsity pattern and CSR slot map) and,
               for the compiled backend, its fixed CSR pattern and the element's kernels;
* compiled  -- one full tangent assembly with the numba backend as the Newton loop does it,
               ``problem.evaluate(g, lam, tangent=True, out=data)`` (element and loads written
               into the CSR data of the fixed pattern), with 1 and 2 numba threads;
* assembly  -- the same with the NumPy reference:
               ``element.evaluate(g, tangent=True)`` + ``problem.external(g, lam)`` +
               ``assembler.matrix(...)`` + the free residual vector, split into
               kernel (element.evaluate) and sparse (loads + CSR assembly + residual);
* mumps / superlu -- one sparse LU factorisation + solve (``core_se3.linalg.make_solver``) of
               the same matrix, equilibrated as ``checked_solve`` does before it factorises
               (S K S, S = |diag K|^-1/2).  SuperLU runs in a child process with a time and
               memory limit, because an unlucky pivot sequence can fill in catastrophically.

Timings are best of ``--repeats`` (more for cheap cases, see ``--min-time``; fewer at 10^5).  Results are printed and written
to ``benchmarks/results/scaling.{md,json}`` with machine information.

    .venv/bin/python benchmarks/scaling.py                      # 1e2 .. 1e5 elements
    .venv/bin/python benchmarks/scaling.py --max-elements 1e4 --repeats 5

Works without petsc4py (MUMPS columns are then 'n/a').
"""
from __future__ import annotations

import argparse
import datetime
import io
import json
import math
import multiprocessing as mp
import os
import platform
import re
import sys
import time
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import scipy
import scipy.sparse as sp

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:          # run from a checkout without installing
    sys.path.insert(0, str(ROOT))

from core_se3 import lie                                    # noqa: E402
from core_se3.solvers.linalg import available_solvers, make_solver  # noqa: E402
from core_se3.fem import Material                      # noqa: E402
from core_se3.mesh import rectangle                         # noqa: E402
from core_se3.model import Problem                        # noqa: E402
from core_se3.backend import numba_available               # noqa: E402

SIZES = (100, 1_000, 10_000, 100_000)
E_MOD, NU, H = 1.2e6, 0.3, 0.1
LENGTH = 10.0              # plate length along x; elements are square
EDGE_FORCE = (0.0, 0.0, 1.0)
LAM = 1.0
TWIST_ROT = 0.05           # rad, std of the random rotation part of eta
TWIST_TRANS = 0.05         # times the element size, std of the translation part

RATIO_LIMIT = 0.2          # compiled assembly / MUMPS solve at 1e4 elements (issue 13)
LINEAR_LIMIT = 1.3         # (t/n_el at 1e5) / (t/n_el at 1e3)
THREADS_LIMIT = 1.6        # compiled assembly, 1 thread / 2 threads, at 1e4 and above


# ------------------------------------------------------------------------------- helpers --
def grid_shape(n_el):
    """(nx, ny) with nx * ny = n_el, as square as possible (nx >= ny)."""
    ny = max(d for d in range(1, int(math.isqrt(n_el)) + 1) if n_el % d == 0)
    return n_el // ny, ny


def best_of(fn, repeats, budget, min_time=0.0, max_runs=25):
    """Run fn() at least ``repeats`` times -- more, up to ``max_runs``, while the runs so far
    took less than ``min_time`` s (cheap cases get a stable minimum) -- but stop once
    ``budget`` seconds are spent; return (best time, result of the best run, number of runs)."""
    best, out, runs, spent = math.inf, None, 0, 0.0
    while runs < max(1, repeats) or (spent < min_time and runs < max_runs):
        t = time.perf_counter()
        res = fn()
        dt = time.perf_counter() - t
        runs += 1
        spent += dt
        if dt < best:
            best, out = dt, res
        if spent + dt > budget:
            break
    return best, out, runs


def build(n_el, seed, backend="numpy"):
    nx, ny = grid_shape(n_el)
    t = time.perf_counter()
    mesh = rectangle(LENGTH, LENGTH * ny / nx, nx, ny)
    problem = Problem(mesh, Material(E=E_MOD, nu=NU, h=H), backend=backend)
    problem.clamp("x0")
    problem.add_edge_force("x1", EDGE_FORCE)
    t_pre = time.perf_counter() - t
    rng = np.random.default_rng(seed)
    eta = rng.standard_normal((mesh.n_nodes, 6))
    eta[:, :3] *= TWIST_TRANS * LENGTH / nx
    eta[:, 3:] *= TWIST_ROT
    eta[problem.constraint_mask()] = 0.0
    g = mesh.g0 @ lie.exp(eta)
    return problem, g, (nx, ny), t_pre


def assemble(problem, asm, g):
    """One Newton-iteration assembly; returns (K, r_free, t_kernel, t_sparse)."""
    t0 = time.perf_counter()
    ev = problem.element.evaluate(g, tangent=True)
    t1 = time.perf_counter()
    f, Kn, Ke = problem.external(g, LAM, tangent=True)
    Ke_tot = ev.element_blocks if Ke is None else ev.element_blocks + Ke
    K = asm.matrix(Ke_tot, ev.edge_blocks, ev.node_blocks + Kn)
    r = asm.vector(ev.r - f)
    t2 = time.perf_counter()
    return K, r, t1 - t0, t2 - t1


def equilibrate(K, b):
    """S K S, S b with S = |diag K|^-1/2 (what ``checked_solve`` factorises)."""
    d = np.abs(K.diagonal())
    d[d == 0] = 1.0
    S = sp.diags(1.0 / np.sqrt(d))
    return (S @ K @ S).tocsr(), S @ b


def rel_residual(K, x, b):
    return float(np.linalg.norm(K @ x - b) / max(np.linalg.norm(b), 1e-300))


# ------------------------------------------------------ SuperLU in a guarded child process --
def _superlu_child(path, repeats, budget, min_time, mem_bytes, queue):
    try:
        if mem_bytes:
            import resource
            resource.setrlimit(resource.RLIMIT_AS, (mem_bytes, mem_bytes))
        data = np.load(path)
        K = sp.csr_matrix((data["data"], data["indices"], data["indptr"]), shape=tuple(data["shape"]))
        b = data["b"]
        solver = make_solver("superlu")
        t, x, runs = best_of(lambda: solver.solve(K, b), repeats, budget, min_time)
        queue.put(dict(status="ok", time=t, runs=runs, residual=rel_residual(K, x, b)))
    except MemoryError:
        queue.put(dict(status="out of memory"))
    except BaseException as exc:  # SuperLU reports running out of memory as SystemError
        msg = f"{type(exc).__name__}: {exc}"
        queue.put(dict(status="out of memory" if "expand" in msg.lower() or "memory" in msg.lower()
                       else "error", error=msg))


def time_superlu(K, b, repeats, budget, min_time, timeout, mem_bytes, tmpdir):
    path = Path(tmpdir) / f"scaling_superlu_{os.getpid()}.npz"
    np.savez(path, data=K.data, indices=K.indices, indptr=K.indptr, shape=np.array(K.shape), b=b)
    ctx = mp.get_context("spawn")
    queue = ctx.Queue()
    proc = ctx.Process(target=_superlu_child, args=(str(path), repeats, budget, min_time, mem_bytes, queue))
    proc.start()
    try:
        try:
            res = queue.get(timeout=timeout)
        except Exception:
            res = dict(status=f"timeout (> {timeout:.0f} s)")
        proc.join(5)
    finally:
        if proc.is_alive():
            proc.terminate()
            proc.join(5)
        path.unlink(missing_ok=True)
    return res


# ----------------------------------------------------------------------- machine info -----
def _loaded_blas():
    """Shared libraries of BLAS/LAPACK mapped into this process (after a MUMPS and a NumPy call)."""
    libs = set()
    try:
        with open("/proc/self/maps") as fh:
            for line in fh:
                p = line.split()[-1] if "/" in line else ""
                name = os.path.basename(p).lower()
                if (re.search(r"blas|lapack|mkl|atlas", name) and ".cpython-" not in name
                        and not re.search(r"combblas|scalapack", name)):
                    libs.add(os.path.realpath(p))
    except OSError:
        pass
    return sorted(libs)


def _numpy_blas():
    try:
        cfg = np.show_config(mode="dicts")              # NumPy >= 2
        blas = cfg.get("Build Dependencies", {}).get("blas", {})
        return f"{blas.get('name', '?')} {blas.get('version', '')}".strip()
    except TypeError:                                    # NumPy 1.x prints only
        buf = io.StringIO()
        with redirect_stdout(buf):
            np.show_config()
        lines = [ln.strip() for ln in buf.getvalue().splitlines()]
        for i, ln in enumerate(lines):
            if ln.startswith("blas") and i + 1 < len(lines):
                for nxt in lines[i + 1:i + 6]:
                    if nxt.startswith("libraries"):
                        return f"{ln.rstrip(':')} {nxt}"
        return "unknown"


def machine_info():
    info = dict(
        date=datetime.datetime.now().isoformat(timespec="seconds"),
        host=platform.node(),
        platform=platform.platform(),
        python=sys.version.split()[0],
        executable=sys.executable,
        nproc=os.cpu_count(),
        affinity=len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        numpy=np.__version__,
        scipy=scipy.__version__,
        numpy_blas_build=_numpy_blas(),
        threads_env={k: os.environ[k] for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                                "MKL_NUM_THREADS") if k in os.environ},
    )
    try:
        with open("/proc/cpuinfo") as fh:
            info["cpu"] = next((ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")),
                               platform.processor())
    except OSError:
        info["cpu"] = platform.processor()
    try:
        with open("/proc/meminfo") as fh:
            info["mem_total_gb"] = round(int(fh.readline().split()[1]) / 2**20, 1)
    except (OSError, ValueError, IndexError):
        pass
    try:
        import petsc4py
        from petsc4py import PETSc
        info["petsc4py"] = petsc4py.__version__
        info["petsc"] = ".".join(map(str, PETSc.Sys.getVersion()))
    except Exception:
        info["petsc4py"] = None
    try:
        import threadpoolctl
        info["threadpools"] = [dict(api=d.get("internal_api"), version=d.get("version"),
                                    threads=d.get("num_threads"), lib=d.get("filepath"))
                               for d in threadpoolctl.threadpool_info()]
    except ImportError:
        info["threadpools"] = None
    return info


# --------------------------------------------------------------------------- driver -------
def run_case(n_el, args, have_mumps, log):
    problem, g, (nx, ny), t_pre = build(n_el, args.seed)
    mesh = problem.mesh
    row = dict(n_el=mesh.n_elements, nx=nx, ny=ny, n_nodes=mesh.n_nodes, elem_init_s=t_pre)
    t = time.perf_counter()
    asm = problem.assembler()
    row["setup_s"] = time.perf_counter() - t
    row["n_dof"] = asm.nfree
    row["nnz"] = asm.nnz
    big = n_el >= 100_000
    reps = min(args.repeats, 2) if big else args.repeats

    def one_assembly():
        t = time.perf_counter()
        K, r, tk, ts = assemble(problem, asm, g)
        return dict(total=time.perf_counter() - t, kernel=tk, sparse=ts, K=K, r=r)

    _, best, runs = best_of(one_assembly, reps, args.budget, min_time=0 if big else args.min_time)
    K, r = best.pop("K"), best.pop("r")
    row["assembly_runs"] = runs
    row.update(assembly_s=best["total"], kernel_s=best["kernel"], sparse_s=best["sparse"])
    log(f"  assembly {best['total']:.3f} s (kernel {best['kernel']:.3f}, sparse {best['sparse']:.3f}); "
        f"best of {runs}; setup {row['setup_s']:.2f} s; {asm.nfree} dofs, nnz {asm.nnz}")

    if numba_available():
        import numba
        t = time.perf_counter()
        pattern = asm.pattern()
        problem.element.compiled(pattern)
        row["setup_compiled_s"] = time.perf_counter() - t
        problem.backend = "numba"
        data = pattern.new_data()
        ev = problem.evaluate(g, LAM, tangent=True, out=data)         # compile / load the cache
        row["compiled_vs_numpy"] = float(abs(ev.K - K).max() / abs(K).max())
        for thr in (1, 2):
            numba.set_num_threads(min(thr, numba.config.NUMBA_NUM_THREADS))
            tc, _, runs = best_of(lambda: problem.evaluate(g, LAM, tangent=True, out=data), reps,
                                  args.budget, min_time=0 if big else args.min_time)
            row[f"compiled_{thr}t_s"] = tc
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        problem.backend = "numpy"
        log(f"  compiled {row['compiled_1t_s']:.4f} s (1 thread), {row['compiled_2t_s']:.4f} s (2 threads); "
            f"setup {row['setup_compiled_s']:.2f} s; |K_numba - K_numpy| / |K| = {row['compiled_vs_numpy']:.1e}")
    else:
        row.update(compiled_1t_s=None, compiled_2t_s=None, setup_compiled_s=None)
    Ks, bs = equilibrate(K, -r)
    del K
    solve_reps = 1 if big else args.repeats
    if have_mumps and not args.no_mumps:
        solver = make_solver("mumps")
        tm, x, runs = best_of(lambda: solver.solve(Ks, bs), solve_reps, args.budget,
                             min_time=0 if big else args.min_time)
        row.update(mumps_s=tm, mumps_runs=runs, mumps_residual=rel_residual(Ks, x, bs))
        log(f"  mumps    {tm:.3f} s (best of {runs}; relative residual {row['mumps_residual']:.1e})")
    else:
        row.update(mumps_s=None, mumps_status="n/a (no petsc4py)" if not have_mumps else "skipped")
    if args.no_superlu or n_el > args.superlu_max_elements:
        row.update(superlu_s=None, superlu_status="skipped")
        log("  superlu  skipped")
    else:
        res = time_superlu(Ks, bs, solve_reps, args.budget, 0 if big else args.min_time,
                           args.superlu_timeout,
                           int(args.superlu_mem_gb * 2**30) if args.superlu_mem_gb else 0,
                           args.tmpdir)
        if res["status"] == "ok":
            row.update(superlu_s=res["time"], superlu_runs=res["runs"], superlu_residual=res["residual"])
            log(f"  superlu  {res['time']:.3f} s (best of {res['runs']}; relative residual "
                f"{res['residual']:.1e})")
        else:
            row.update(superlu_s=None, superlu_status=res["status"], superlu_error=res.get("error"))
            log(f"  superlu  {res['status']} {res.get('error', '')}")
    row["assembly_over_mumps"] = (row["assembly_s"] / row["mumps_s"]) if row.get("mumps_s") else None
    c1 = row.get("compiled_2t_s")
    row["compiled_over_mumps"] = (c1 / row["mumps_s"]) if row.get("mumps_s") and c1 else None
    return row


def _fmt(v, spec=".3f", missing="n/a"):
    return missing if v is None else format(v, spec)


def table(rows):
    ref = next((r for r in rows if r["n_el"] == 1000), None)
    head = ["n_el", "mesh", "n_dof", "setup s", "numba setup s", "numba 1 thr s", "numba 2 thr s",
            "numpy asm s", "kernel s", "sparse s", "mumps s", "superlu s", "numba/mumps", "numpy/mumps",
            "numba per el / 1e3", "1 thr / 2 thr"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---:" for _ in head) + "|"]
    for r in rows:
        key = "compiled_2t_s" if r.get("compiled_2t_s") else "assembly_s"
        per = (r[key] / r["n_el"]) / (ref[key] / ref["n_el"]) if ref and ref.get(key) else None
        r["per_element_vs_1e3"] = per
        thr = (r["compiled_1t_s"] / r["compiled_2t_s"]) if r.get("compiled_2t_s") else None
        r["threads_speedup"] = thr
        slu = _fmt(r.get("superlu_s")) if r.get("superlu_s") is not None else r.get("superlu_status", "n/a")
        mum = _fmt(r.get("mumps_s")) if r.get("mumps_s") is not None else "n/a"
        lines.append("| " + " | ".join([
            f"{r['n_el']:,}", f"{r['nx']}x{r['ny']}", f"{r['n_dof']:,}", _fmt(r["setup_s"], ".2f"),
            _fmt(r.get("setup_compiled_s"), ".2f"), _fmt(r.get("compiled_1t_s"), ".4f"),
            _fmt(r.get("compiled_2t_s"), ".4f"),
            _fmt(r["assembly_s"]), _fmt(r["kernel_s"]), _fmt(r["sparse_s"]), mum, slu,
            _fmt(r.get("compiled_over_mumps"), ".3f"), _fmt(r["assembly_over_mumps"], ".2f"),
            _fmt(per, ".2f"), _fmt(thr, ".2f")]) + " |")
    return "\n".join(lines)


def verdict(rows):
    by = {r["n_el"]: r for r in rows}
    out = {}
    r4 = by.get(10_000)
    key = "compiled_2t_s" if r4 and r4.get("compiled_2t_s") else "assembly_s"
    if r4 and r4.get("mumps_s"):
        v = r4[key] / r4["mumps_s"]
        out["ratio_1e4"] = dict(value=v, limit=RATIO_LIMIT, ok=v <= RATIO_LIMIT)
    if 1_000 in by and 100_000 in by:
        v = (by[100_000][key] / 100_000) / (by[1_000][key] / 1_000)
        out["linearity_1e3_1e5"] = dict(value=v, limit=LINEAR_LIMIT, ok=v <= LINEAR_LIMIT)
    for n in (10_000, 100_000):
        r = by.get(n)
        if r and r.get("threads_speedup"):
            out[f"threads_{n:.0e}"] = dict(value=r["threads_speedup"], limit=THREADS_LIMIT,
                                           ok=r["threads_speedup"] >= THREADS_LIMIT)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--max-elements", type=float, default=1e5,
                    help="largest mesh (elements) of the series 1e2, 1e3, 1e4, 1e5 (default 1e5)")
    ap.add_argument("--sizes", type=lambda s: [int(float(x)) for x in s.split(",")],
                    help="explicit comma-separated element counts (overrides the series)")
    ap.add_argument("--repeats", type=int, default=3,
                    help="best of N repeats (default 3; at 1e5 elements at most 2 for assembly, 1 for solves)")
    ap.add_argument("--min-time", type=float, default=1.0,
                    help="below 1e5 elements, keep repeating a cheap measurement (up to 25 runs) until "
                         "this many seconds are spent, for a stable minimum (default 1)")
    ap.add_argument("--budget", type=float, default=60.0,
                    help="stop repeating a measurement once it has used this many seconds (default 60)")
    ap.add_argument("--superlu-max-elements", type=float, default=1e4,
                    help="skip SuperLU above this many elements (default 1e4)")
    ap.add_argument("--superlu-timeout", type=float, default=600.0,
                    help="give up on one SuperLU measurement after this many seconds (default 600)")
    ap.add_argument("--superlu-mem-gb", type=float, default=None,
                    help="address-space limit of the SuperLU child process in GiB "
                         "(default: 3/4 of the available memory)")
    ap.add_argument("--no-mumps", action="store_true")
    ap.add_argument("--no-superlu", action="store_true")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results",
                    help="directory for scaling.md and scaling.json (default benchmarks/results)")
    ap.add_argument("--tmpdir", default=os.environ.get("TMPDIR", "/tmp"))
    args = ap.parse_args(argv)

    if args.superlu_mem_gb is None:
        try:
            with open("/proc/meminfo") as fh:
                avail = next(int(ln.split()[1]) for ln in fh if ln.startswith("MemAvailable"))
            args.superlu_mem_gb = 0.75 * avail / 2**20
        except (OSError, StopIteration):
            args.superlu_mem_gb = 0
    sizes = args.sizes or [n for n in SIZES if n <= args.max_elements]
    have_mumps = "mumps" in available_solvers()

    def log(msg):
        print(msg, flush=True)

    info = machine_info()
    log(f"core-se3 scaling benchmark: {info['cpu']}, {info['nproc']} cpus, NumPy {info['numpy']}, "
        f"SciPy {info['scipy']}, petsc4py {info.get('petsc4py') or 'n/a'}")
    load0 = os.getloadavg()
    rows = []
    t_run = time.perf_counter()
    for n in sizes:
        log(f"n_el = {n:,}")
        rows.append(run_case(n, args, have_mumps, log))
    load1 = os.getloadavg()
    info["blas_loaded"] = _loaded_blas()
    info["loadavg_start"], info["loadavg_end"] = load0, load1
    tab = table(rows)
    checks = verdict(rows)
    print()
    print(tab)
    print()
    for name, c in checks.items():
        print(f"{name}: {c['value']:.3f} (limit {c['limit']}) -> {'PASS' if c['ok'] else 'FAIL'}")
    print(f"BLAS loaded: {', '.join(info['blas_loaded']) or 'unknown'}; load average "
          f"{load0[0]:.2f} -> {load1[0]:.2f}; total {time.perf_counter() - t_run:.0f} s")

    args.out.mkdir(parents=True, exist_ok=True)
    payload = dict(benchmark="core_se3 scaling", machine=info,
                   setup=dict(material=dict(E=E_MOD, nu=NU, h=H), plate_length=LENGTH,
                              edge_force=EDGE_FORCE, support="clamp x0", load="dead edge force x1",
                              state=f"g0 exp(eta), eta ~ N(0,1) * ({TWIST_TRANS} * element size, "
                                    f"{TWIST_ROT} rad), seed {args.seed}",
                              solve="one factorisation + solve of the equilibrated S K S",
                              repeats=args.repeats),
                   rows=rows, checks=checks)
    (args.out / "scaling.json").write_text(json.dumps(payload, indent=2, default=float) + "\n")
    md = ["# core_se3 scaling benchmark", "",
          f"`{' '.join([Path(sys.executable).name, 'benchmarks/scaling.py'] + (argv or sys.argv[1:]))}` "
          f"on {info['date']}", "",
          tab, "",
          *(f"- **{k}**: {c['value']:.3f} (limit {c['limit']}): {'PASS' if c['ok'] else 'FAIL'}"
            for k, c in checks.items()), "",
          "Times in seconds, best of the repeats. *numba 1/2 thr* = one compiled tangent assembly "
          "(`problem.evaluate(g, lam, tangent=True, out=data)`: element and loads written into the "
          "CSR data of the fixed pattern) with 1 and 2 numba threads; *numpy asm* = the NumPy "
          "reference: kernel (`element.evaluate`, residual + tangent blocks) + sparse (loads, CSR "
          "assembly, free residual); *setup* = one-time `Assembler` construction, *numba setup* its "
          "fixed CSR pattern and the element kernels' data (neither in the assembly times); "
          "*mumps*/*superlu* = one LU factorisation + solve of the equilibrated matrix; "
          "*numba/mumps* with 2 threads (limit 0.2 at 10^4); *numba per el / 1e3* = compiled "
          "assembly time per element relative to the 10^3 case (limit 1.3 at 10^5).", "",
          "Machine: " + ", ".join(f"{k} {info.get(k)}" for k in
                                  ("cpu", "nproc", "mem_total_gb", "python", "numpy", "scipy",
                                   "petsc4py", "petsc")),
          f"BLAS (loaded): {', '.join(info['blas_loaded']) or 'unknown'}; NumPy build: "
          f"{info['numpy_blas_build']}; thread env: {info['threads_env'] or 'default'}; "
          f"load average {load0[0]:.2f} at start, {load1[0]:.2f} at end.", ""]
    kept = ""                       # setup_cost.py's section, kept
    if (args.out / "scaling.md").exists():
        old = (args.out / "scaling.md").read_text()
        mark = "## Set-up and iteration against the factorisation"
        kept = ("\n" + mark + old.split(mark, 1)[1]) if mark in old else ""
    (args.out / "scaling.md").write_text("\n".join(md) + kept)
    print(f"wrote {args.out / 'scaling.md'} and {args.out / 'scaling.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
