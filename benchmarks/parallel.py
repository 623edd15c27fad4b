"""Distributed assembly and solve (core_se3.parallel, issue 17) on 1 and 2 ranks.

    python benchmarks/parallel.py run            # every measurement below, then the report
    python benchmarks/parallel.py report         # benchmarks/results/parallel.md from parallel.json

Each measurement is one ``mpirun -n R`` of this file (``worker`` mode, one thread per rank:
OMP_NUM_THREADS = NUMBA_NUM_THREADS = 1), on a square plate clamped on one side under a
follower pressure (the default element, mixed iteration):

* ``iteration``: N x N elements; after a warm-up (compilation, MUMPS analysis) the median of
  three of: the assembly (every rank's element and load kernels into its CSR data, the COO
  values into the MPIAIJ tangent, the ghost sums of the nodal forces, the global norms), the
  MUMPS solve (equilibration, factorisation, refinement, ghost update), and one whole Newton
  iteration (assembly, solve, exponential update with ghost frames, linear stress update);
  the peak resident memory of every rank;
* ``solve``: one load step to convergence with an iterative solver (GAMG), time and memory
  (``large N ...``: 2 ranks at L/h = 10 with GMRES(30); ``large1 N ...``: the same on one rank,
  whose PETSc matrix shares the kernels' CSR, with two numba threads);
* ``gamg``: GAMG's Krylov iterations per Newton iteration against L/h and the mesh.

The results go to benchmarks/results/parallel.json; ``report`` writes parallel.md.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = os.path.join(HERE, "results", "parallel.json")


def plate(n, h=0.01, p=None):
    from core_se3 import Material, Problem, mesh
    prob = Problem(mesh.rectangle(1.0, 1.0, n, n), Material(1e6, 0.3, h))
    prob.clamp("x0")
    # a moderate load: tip deflection ~ 0.1 L at L/h = 100, scaled with the bending stiffness
    prob.add_pressure(0.1 * 8 * 1e6 * h ** 3 / 12 if p is None else p, follower=True)
    prob.add_probe("tip", "x1")
    return prob


def _best(f, k=3):
    """(least wall time, least CPU time of this rank) over k calls (the machine is shared: the
    least is the one least disturbed)."""
    ts, cs = [], []
    for _ in range(k):
        t, c = time.perf_counter(), time.process_time()
        f()
        ts.append(time.perf_counter() - t)
        cs.append(time.process_time() - c)
    return float(min(ts)), float(min(cs))


def worker_iteration(n, linear="mumps"):
    from core_se3.parallel import DistributedRun, world
    comm = world()
    prob = plate(n)
    t0 = time.perf_counter()
    run = DistributedRun(prob, comm, linear, None, "auto")
    setup = time.perf_counter() - t0
    g = run.local_frames(prob.mesh.g0)
    lam = 1.0
    stress = run.stress(g, 0.0)
    ev = run.evaluate(g, lam, tangent=True, stress=stress)          # warm-up: compilation
    run.solve(ev, g, probe=False)                                   # warm-up: MUMPS analysis
    comm.Barrier()
    t_asm, c_asm = _best(lambda: (run.evaluate(g, lam, tangent=True, stress=stress), comm.Barrier()), 5)
    ev = run.evaluate(g, lam, tangent=True, stress=stress)
    comm.Barrier()

    def solve():
        run.evaluate(g, lam, tangent=True, stress=stress)           # the factorisation needs a fresh K
        e = run.evaluate(g, lam, tangent=True, stress=stress)
        comm.Barrier()
        t, c = time.perf_counter(), time.process_time()
        run.solve(e, g)
        comm.Barrier()
        return time.perf_counter() - t, time.process_time() - c
    t_sol, c_sol = (float(min(x)) for x in zip(*[solve() for _ in range(3)]))

    def iteration():
        e = run.evaluate(g, lam, tangent=True, stress=stress)
        eta = run.solve(e, g)
        run.retract(g, eta)
        run.linear_stress(e, eta)
        comm.Barrier()
    t_it, c_it = _best(iteration)
    mine, allm = run.memory()
    out = dict(kind="iteration", n=n, elements=n * n, dofs=6 * (n + 1) ** 2, ranks=comm.size, setup=setup,
               assembly=t_asm, solve=t_sol, iteration=t_it, memory=allm,
               cpu=comm.allgather(dict(assembly=c_asm, solve=c_sol, iteration=c_it)),
               load_average=os.getloadavg()[0],
               owned_nodes=comm.allgather(run.n_own), elements_per_rank=comm.allgather(len(run.sub.elements)))
    run.close()
    return out


def worker_solve(n, linear="gamg", h=0.01, opts=None):
    from core_se3.parallel import world
    comm = world()
    prob = plate(n, h)
    t = time.perf_counter()
    try:
        res = prob.solve(steps=1, solver="distributed", linear=linear, petsc_options=opts or {}, max_cutbacks=2)
    except Exception as exc:                     # a solver that fails is a result too
        return dict(kind="solve", n=n, elements=n * n, dofs=6 * (n + 1) ** 2, ranks=comm.size, linear=linear,
                    L_over_h=1.0 / h, wall=time.perf_counter() - t, error=str(exc)[:300], newton=None, krylov=None,
                    memory=comm.allgather(__import__("resource").getrusage(0).ru_maxrss * 1024.0))
    wall = time.perf_counter() - t
    import numba
    return dict(kind="solve", n=n, elements=n * n, dofs=6 * (n + 1) ** 2, ranks=comm.size, linear=linear,
                threads=numba.get_num_threads(), L_over_h=1.0 / h, wall=wall, large=bool(opts), options=opts or {}, newton=[s.iterations for s in res.steps][1:],
                krylov=res.parallel["linear_iterations"], memory=res.parallel["memory_peak"],
                timings={k: v for k, v in res.timings.items()},
                tip=np.asarray(res.final.probes["tip"]["u"]).tolist())


def launch(ranks, *args, timeout=3600, threads=1):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1",
               NUMBA_NUM_THREADS=str(threads), PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    tmp = os.path.join(HERE, "results", f".parallel-{os.getpid()}.json")
    cmd = ["mpirun", "-n", str(ranks), "-x", "PYTHONPATH", "-x", "OMP_NUM_THREADS", "-x", "NUMBA_NUM_THREADS",
           sys.executable, os.path.abspath(__file__), "worker", tmp, *map(str, args)]
    p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
    if p.returncode != 0:
        print(p.stdout[-2000:], p.stderr[-4000:], file=sys.stderr)
        return None
    with open(tmp) as fh:
        out = json.load(fh)
    os.unlink(tmp)
    return out


def load():
    if os.path.exists(OUT):
        with open(OUT) as fh:
            return json.load(fh)
    return {"runs": []}


def save(doc):
    with open(OUT, "w") as fh:
        json.dump(doc, fh, indent=1)


def record(doc, r):
    if r is None:
        return
    key = lambda x: (x["kind"], x["n"], x["ranks"], x.get("linear"), x.get("L_over_h"), x.get("large", False))  # noqa
    doc["runs"] = [x for x in doc["runs"] if key(x) != key(r)] + [r]
    doc["load_average"] = os.getloadavg()
    save(doc)
    print(json.dumps({k: v for k, v in r.items() if k not in ("timings",)}))


def run_all(which):
    doc = load()
    if "iteration" in which:
        for n in (100, 316):
            for ranks in (1, 2):
                record(doc, launch(ranks, "iteration", n))
    if "gamg" in which:
        for n, Lh in [(50, 10), (50, 100), (50, 1000), (50, 10000), (100, 10), (100, 100), (100, 1000),
                      (200, 10), (200, 100), (316, 10)]:
            record(doc, launch(2, "solve", n, "gamg", 1.0 / Lh))
    if "hypre" in which:                  # BoomerAMG on the same plates (docs/PARALLEL.md)
        for n, Lh in [(50, 10), (50, 100), (50, 1000), (100, 10), (100, 100)]:
            record(doc, launch(2, "solve", n, "hypre", 1.0 / Lh))
    for mode, ranks, threads in (("large", 2, 1), ("large1", 1, 2)):
        # L/h = 10 (GAMG's robust range), GMRES(30): memory. large1: one rank (PETSc's matrix shares
        # the kernels' CSR: the leanest layout) with two numba threads for the element kernels
        if mode in which:
            args = []
            for a in which[which.index(mode) + 1:]:
                if not a.isdigit():
                    break
                args.append(int(a))
            for n in args or [1000]:
                record(doc, launch(ranks, "solve", n, "gamg", 0.1, "ksp_gmres_restart=30", timeout=7200,
                                   threads=threads))


def report():
    doc = load()
    runs = doc["runs"]
    L = ["# Distributed assembly and solve (core_se3.parallel)", "",
         "`python benchmarks/parallel.py run` (one `mpirun -n R` per row, one thread per rank unless the notes say otherwise); "
         f"machine: 2 cores, 24 GB, shared (load average {doc.get('load_average', ['?'])[0]:.1f} at the last run).", ""]
    it = sorted([r for r in runs if r["kind"] == "iteration"], key=lambda r: (r["n"], r["ranks"]))
    if it:
        L += ["## Per Newton iteration: 1 and 2 ranks (MUMPS)", "",
              "| elements | dofs | ranks | assembly [s] | solve [s] | Newton iteration [s] | memory per rank [GB] | "
              "speed-up assembly | speed-up iteration |", "|---|---|---|---|---|---|---|---|---|"]
        base = {r["n"]: r for r in it if r["ranks"] == 1}
        for r in it:
            b = base.get(r["n"])
            sa = f"{b['assembly'] / r['assembly']:.2f}x" if b else ""
            si = f"{b['iteration'] / r['iteration']:.2f}x" if b else ""
            L.append(f"| {r['elements']:,} | {r['dofs']:,} | {r['ranks']} | {r['assembly']:.3f} | {r['solve']:.3f} | "
                     f"{r['iteration']:.3f} | {', '.join(f'{m / 1e9:.2f}' for m in r['memory'])} | {sa} | {si} |")
        L.append("")
    sv = sorted([r for r in runs if r["kind"] == "solve"], key=lambda r: (r["n"], r["L_over_h"]))
    if sv:
        L += ["## One load step to convergence with an iterative solver", "",
              "| solver | ranks | elements | dofs | L/h | Newton iterations | Krylov iterations per Newton iteration | "
              "wall [s] | peak memory per rank [GB] | memory per dof [kB] |", "|---|---|---|---|---|---|---|---|---|---|"]
        for r in sorted(sv, key=lambda r: (r.get("linear", "gamg"), r["n"], r["L_over_h"], r["ranks"])):
            head = (f"| {r.get('linear', 'gamg')} | {r['ranks']} | {r['elements']:,} | {r['dofs']:,} | "
                    f"{r['L_over_h']:g} |")
            if r.get("error"):
                L.append(f"{head} failed | {r['error'][:120]} | {r['wall']:.1f} | | |")
                continue
            L.append(f"{head} {r['newton']} | {r['krylov']} | {r['wall']:.1f} | "
                     f"{', '.join(f'{m / 1e9:.2f}' for m in r['memory'])} | {sum(r['memory']) / r['dofs'] / 1e3:.1f} |")
        L.append("")
    with open(os.path.join(HERE, "results", "parallel.md"), "w") as fh:
        fh.write("\n".join(L) + "\n" + doc.get("notes", ""))
    print("\n".join(L))


if __name__ == "__main__":
    from core_se3.backend import pin_for_timing
    pin_for_timing()              # one rank runs serially too: time the compiled product
    if sys.argv[1] == "worker":
        out, kind, *rest = sys.argv[2:]
        if kind == "iteration":
            r = worker_iteration(int(rest[0]))
        else:
            r = worker_solve(int(rest[0]), rest[1], float(rest[2]), dict(a.split("=") for a in rest[3:]))
        from core_se3.parallel import world
        if world().rank == 0:
            with open(out, "w") as fh:
                json.dump(r, fh)
    elif sys.argv[1] == "run":
        run_all(sys.argv[2:] or ["iteration", "gamg"])
        report()
    else:
        report()
