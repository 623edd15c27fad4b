"""The price of ``end_check`` (issue 29: the count of negative eigenvalues of sym K at the end of a
load-stepped solve, docs/STEPS.md): speed.py's load-stepped cases solved with it on and off,
alternating in one process (numba, one thread), process CPU time, best of ``--rounds`` each.
Writes benchmarks/results/end_check_cost.md.

    python benchmarks/end_check_cost.py [--rounds 4] [--plate]
"""
from __future__ import annotations

import argparse
import datetime
import os
import sys
import time

for var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")
os.environ.setdefault("CORE_SE3_BACKEND", "numba")
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

CASES = ["cantilever-shear", "rollup", "arch-follower", "torsion", "magnetic-cantilever", "magnetic-gripper"]


def _solve(name, end_check):
    """CPU seconds of one solve of ``name`` (a catalogue case, or speed.py's 100x100 plate)."""
    if name == "plate-100x100":
        import speed
        p = speed._plate((100, 100))
        t0 = time.process_time()
        p.solve(steps=5, end_check=end_check)
        return time.process_time() - t0
    from core_se3.catalogue import run_case
    t0 = time.process_time()
    run_case(name, end_check=end_check)
    return time.process_time() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--plate", action="store_true", help="also the 100x100 plate (about 16 s a solve)")
    a = ap.parse_args()
    import warnings
    warnings.simplefilter("ignore")
    rows = []
    for name in CASES + (["plate-100x100"] if a.plate else []):
        _solve(name, True)                                     # warm-up: kernels, caches
        t = {True: [], False: []}
        for _ in range(a.rounds):
            for on in (True, False):
                t[on].append(_solve(name, on))
        rows.append((name, min(t[True]), min(t[False])))
        print(f"{name}: on {rows[-1][1]:.4f} s, off {rows[-1][2]:.4f} s, ratio {rows[-1][1] / rows[-1][2]:.3f}", flush=True)
    lines = ["# The price of end_check (issue 29)", "",
             f"`python benchmarks/end_check_cost.py --rounds {a.rounds}{' --plate' if a.plate else ''}` on "
             f"{datetime.datetime.now().isoformat(timespec='seconds')}: each case solved with `end_check` on and off "
             "alternately in one process (numba, one thread), process CPU time, best of the rounds. The arc-length "
             "cases of speed.py (sze-hemisphere, sze-pinched-cylinder) do not take the check; cases with followers, "
             "contact or a non-symmetric tangent pay one tangent assembly (the symmetry test) or nothing.", "",
             "| case | on [s] | off [s] | on / off |", "|---|---:|---:|---:|"]
    lines += [f"| {n} | {on:.4f} | {off:.4f} | {on / off:.3f} |" for n, on, off in rows]
    with open(os.path.join(HERE, "results", "end_check_cost.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
