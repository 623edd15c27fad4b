#!/usr/bin/env python3
"""Two source trees timed side by side on benchmarks/speed.py's whole solves.

Starts ``benchmarks/speed.py --child CASE`` (numba backend, one thread, the child's best of its
warm solves within 2 s) from tree A and from tree B in turn, A B A B ..., after one warm-up run
of each (numba's cache of each tree, kept in its own directory), and prints per case the best
total of each tree and the ratios A/B taken pair by pair (min / median / max): pairing keeps the
ratio meaningful while the machine's speed drifts.  Used for the house's phases
(benchmarks/results/house_side_by_side.md); a tree is a checkout or ``git archive REV | tar -x``.

    python benchmarks/side_by_side.py TREE_A TREE_B --rounds 8 --cases cantilever-shear rollup
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

MESH = {"cantilever-shear": "16x1", "rollup": "10x1", "arch-follower": "40x1", "torsion": "20x6",
        "sze-hemisphere": "16x16", "plate-100x100": "100x100"}
THREAD_VARS = ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def child(tree, case, cache):
    """The RESULT dict of one speed.py child of ``tree`` (total, iterations, ...)."""
    env = dict(os.environ, CORE_SE3_BACKEND="numba", PYTHONPATH=tree, NUMBA_CACHE_DIR=cache)
    env.update({v: "1" for v in THREAD_VARS})
    cmd = [sys.executable, os.path.join(tree, "benchmarks", "speed.py"), "--child", case, "--budget", "2.0"]
    if case in MESH:
        cmd += ["--mesh", MESH[case]]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900)
    for line in out.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    raise RuntimeError(f"{tree} {case}: {out.stderr[-1500:]}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--cases", nargs="*", default=list(MESH))
    args = ap.parse_args()
    caches = {t: tempfile.mkdtemp(prefix="side-by-side-") for t in (args.a, args.b)}
    res = {c: {args.a: [], args.b: []} for c in args.cases}
    for c in args.cases:                                # warm-up: each tree's kernels compiled once
        child(args.a, c, caches[args.a])
        child(args.b, c, caches[args.b])
    for r in range(args.rounds):
        for c in args.cases:
            for t in (args.a, args.b):
                res[c][t].append(child(t, c, caches[t]))
            print(c, r, *(round(res[c][t][-1]["total"], 4) for t in (args.a, args.b)), flush=True)
    print("\n| case | A best [s] | B best [s] | A/B per pair: min / median / max | iterations A, B |")
    print("|---|---:|---:|---|---|")
    for c in args.cases:
        ta, tb = ([x["total"] for x in res[c][t]] for t in (args.a, args.b))
        q = [x / y for x, y in zip(ta, tb)]
        print(f"| {c} | {min(ta):.4f} | {min(tb):.4f} | {min(q):.3f} / {statistics.median(q):.3f} / {max(q):.3f} | "
              f"{res[c][args.a][0]['iterations']}, {res[c][args.b][0]['iterations']} |")


if __name__ == "__main__":
    sys.exit(main())
