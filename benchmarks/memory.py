"""Peak memory of a serial run against its number of unknowns: the measurements behind
``core-se3 run --check``'s estimate (``core_se3/scenario/memory.py``).

Each size runs in its own process (``getrusage`` ``ru_maxrss``: the peak resident memory of the
process, the imports included): a square plate of n x n default elements, clamped on one edge,
under a small pressure, one load step of ``Problem.solve`` with the given backend and the
default ('auto') linear solver, which is the banded LU for strips, SuperLU below 2000 unknowns
and MUMPS above.  A fit  peak = base + a N + b N log2 N  (N the unknowns) over the sizes with
MUMPS is printed, and the fit's error at each size.

    python benchmarks/memory.py [--backend numba|numpy] [--sizes 20 40 80 120 160]

Writes benchmarks/results/memory.md.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
CHILD = r"""
import json, resource, sys, time
from core_se3 import Problem, Material, mesh
n = int(sys.argv[1])
t0 = time.perf_counter()
p = Problem(mesh.rectangle(1.0, 1.0, n, n), Material(1e6, 0.3, 0.01), backend=sys.argv[2])
p.clamp("x0"); p.add_pressure(1e-3)
p.solve(steps=1)
print(json.dumps(dict(n=n, dofs=6 * (n + 1) ** 2, free=6 * (n + 1) * n, elements=n * n,
                      peak=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0,
                      seconds=time.perf_counter() - t0)))
"""


def measure(n, backend):
    env = dict(os.environ, CORE_SE3_BACKEND=backend)
    out = subprocess.run([sys.executable, "-c", CHILD, str(n), backend], capture_output=True, text=True, env=env,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def fit(rows):
    """Least squares of peak = base + a N + b N log2 N over the rows (N the free unknowns)."""
    N = np.array([r["free"] for r in rows], float)
    A = np.stack([np.ones_like(N), N, N * np.log2(N)], 1)
    coef, *_ = np.linalg.lstsq(A, np.array([r["peak"] for r in rows]), rcond=None)
    return coef


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--backend", default="numba")
    ap.add_argument("--sizes", type=int, nargs="+", default=[20, 40, 80, 120, 160])
    args = ap.parse_args()
    rows = [measure(n, args.backend) for n in args.sizes]
    big = [r for r in rows if r["free"] >= 2000]
    base, a, b = fit(big)
    lines = [f"# Peak memory of a serial run ({args.backend} backend, 'auto' linear solver)", "",
             "| plate | elements | free unknowns N | peak [MiB] | fit [MiB] | fit error | time [s] |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        f = base + a * r["free"] + b * r["free"] * np.log2(r["free"])
        lines.append(f"| {r['n']}x{r['n']} | {r['elements']} | {r['free']} | {r['peak'] / 2**20:.0f} | {f / 2**20:.0f} | "
                     f"{100 * (f / r['peak'] - 1):+.1f} % | {r['seconds']:.1f} |")
    lines += ["", f"fit (N >= 2000, MUMPS): peak = {base / 2**20:.1f} MiB + {a:.1f} B N + {b:.2f} B N log2 N"]
    text = "\n".join(lines) + "\n"
    print(text)
    with open(os.path.join(HERE, "results", f"memory-{args.backend}.md"), "w") as fh:
        fh.write(text)


if __name__ == "__main__":
    main()
