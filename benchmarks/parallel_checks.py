"""The price of the checks of accepted steps in distributed runs (issue 29, docs/PARALLEL.md):
each case solved by ``distributed_solve`` with the checks on (the defaults: the stability
check's det K sign from MUMPS' determinant, the end check's inertia count with MUMPS' LDL^T,
the snap check of contact steps) and off (``limit_check``, ``end_check``, ``snap_check`` false,
MUMPS without its determinant), alternating in one process per rank count, wall time of the
slowest rank and CPU time of all ranks, best of ``--rounds``.  Writes benchmarks/results/parallel_checks.md.

    python benchmarks/parallel_checks.py [--rounds 3] [--ranks 1 2]

Each rank count is one ``mpirun -n R`` of this file in ``worker`` mode (one thread per rank).
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)

# (name, steps): speed.py's 100x100 plate under its end shear (conservative: the end check
# factorises sym K once), the gripper grasping a sphere (contact: the snap check probes 3 steps)
CASES = (("plate-100x100", 5), ("magnetic-gripper-grasp", 20))
OFF = dict(limit_check=False, end_check=False, snap_check=False)


def _problem(name):
    if name == "plate-100x100":
        import speed
        return speed._plate((100, 100))
    from core_se3.catalogue.case import case_params, get_case
    from core_se3.catalogue.run import build_problem
    case = get_case(name)
    return build_problem(case, case_params(case))


def _solve(comm, name, steps, on):
    """(wall seconds of the slowest rank, CPU seconds of all ranks) of one distributed solve,
    and its tries."""
    from mpi4py import MPI
    from core_se3.parallel import distributed_solve
    p = _problem(name)
    setup = dict(comm=comm) if on else dict(comm=comm, petsc_options={"mat_mumps_icntl_33": 0})
    comm.Barrier()
    t0, c0 = time.perf_counter(), time.process_time()
    res = distributed_solve(p, steps=steps, setup=setup, **({} if on else OFF))
    dt = comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)
    cpu = comm.allreduce(time.process_time() - c0, op=MPI.SUM)
    return (dt, cpu), sum(s.attempts for s in res.steps[1:])


def worker(out, rounds, cases):
    from core_se3.parallel import world
    comm = world()
    rows = []
    for name, steps in [c for c in CASES if c[0] in cases]:
        _solve(comm, name, steps, True)                       # warm-up: kernels, caches
        t = {True: [], False: []}
        tries = {}
        for _ in range(rounds):
            for on in (True, False):
                dt, tries[on] = _solve(comm, name, steps, on)
                t[on].append(dt)
        rows.append(dict(name=name, steps=steps, on=min(w for w, _ in t[True]), off=min(w for w, _ in t[False]),
                         cpu_on=min(c for _, c in t[True]), cpu_off=min(c for _, c in t[False]),
                         tries_on=tries[True], tries_off=tries[False]))
    if comm.rank == 0:
        with open(out, "w") as fh:
            json.dump(dict(ranks=comm.size, rows=rows), fh)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--cases", nargs="+", default=[c for c, _ in CASES], help="a subset of the cases")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.worker:
        return worker(a.worker, a.rounds, a.cases)
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1", OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_mpi_yield_when_idle="1",
               PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    table = []
    for ranks in a.ranks:
        out = os.path.join(tempfile.mkdtemp(), "checks.json")
        cmd = ["mpirun", "-n", str(ranks), "-x", "PYTHONPATH", "-x", "OMP_NUM_THREADS", "-x", "NUMBA_NUM_THREADS",
               sys.executable, os.path.abspath(__file__), "--worker", out, "--rounds", str(a.rounds), "--cases", *a.cases]
        subprocess.run(cmd, env=env, check=True, cwd=ROOT)
        with open(out) as fh:
            doc = json.load(fh)
        for r in doc["rows"]:
            table.append((ranks, r))
            print(f"{ranks} ranks {r['name']}: on {r['on']:.3f} s ({r['tries_on']} tries), off {r['off']:.3f} s "
                  f"({r['tries_off']} tries), ratio {r['on'] / r['off']:.3f}, CPU ratio {r['cpu_on'] / r['cpu_off']:.3f}",
                  flush=True)
    lines = ["# The price of the step checks in distributed runs (issue 29)", "",
             f"`python benchmarks/parallel_checks.py --rounds {a.rounds} --ranks {' '.join(map(str, a.ranks))} --cases "
             f"{' '.join(a.cases)}` on "
             f"{datetime.datetime.now().isoformat(timespec='seconds')}: each case solved by `distributed_solve` "
             "(MUMPS) with the checks on (the defaults) and off (`limit_check`, `end_check`, `snap_check` false, "
             "`mat_mumps_icntl_33 = 0`) alternately in one `mpirun -n R` (one thread per rank), wall time of the "
             "slowest rank and CPU time of all ranks, best of the rounds each; the machine's two cores are shared "
             "with other work (its load average was 8-9 during the runs of this session), so single ratios move by "
             "+-0.2 from run to run.", "",
             "| ranks | case | steps | tries on / off | wall on [s] | wall off [s] | wall on / off | CPU on [s] | "
             "CPU off [s] | CPU on / off |",
             "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    lines += [f"| {n} | {r['name']} | {r['steps']} | {r['tries_on']} / {r['tries_off']} | {r['on']:.3f} | "
              f"{r['off']:.3f} | {r['on'] / r['off']:.3f} | {r['cpu_on']:.3f} | {r['cpu_off']:.3f} | "
              f"{r['cpu_on'] / r['cpu_off']:.3f} |" for n, r in table]
    with open(os.path.join(HERE, "results", "parallel_checks.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
