"""What the least-turn gauge of the nodal frames costs (``core_se3/mesh/gauge.py``): the compiled
element tangent of an annulus whose generated frames turn about the normal (radial d1, the gauge
on) against the same quads with d1 alike (no gauge), in one process, the two timed in turn.

    .venv/bin/python benchmarks/gauge_cost.py      -> benchmarks/results/gauge_cost.md

Only meshes whose frames turn about the normal on flat or developable parts pay it; every other
mesh takes the kernels' path without the rotations (an empty ``Rq``).
"""
from __future__ import annotations

import datetime
import time
import warnings
from pathlib import Path

import numpy as np

from core_se3 import Material, Problem, kernels, lie, mesh
from core_se3.catalogue import patch_tests as pt

OUT = Path(__file__).parent / "results" / "gauge_cost.md"


def tangent_time(m, repeats=7, calls=5):
    """Seconds per element tangent (the least over ``repeats`` rounds of ``calls``) and the driver."""
    p = Problem(m, Material(1e4, 0.3, 0.05), backend="numba")
    p.clamp(m.node_set("x0"))
    pat = kernels.Pattern(m.quads, m.edge_nodes, m.elem_edges, m.n_nodes, p.assembler().free)
    ek = kernels.ElementKernels.from_element(p.element, pat)
    g = m.g0 @ lie.exp(0.01 * np.random.default_rng(0).standard_normal((m.n_nodes, 6)))
    ek.tangent(g)
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        for _ in range(calls):
            ek.tangent(g)
        best = min(best, (time.perf_counter() - t) / calls)
    return best, ek.mode, p.element.gauge is not None


def main():
    warnings.simplefilter("ignore")
    rows = []
    for n in (20, 30, 60):
        radial = mesh.annulus(1.0, 2.0, 1.0, n, n)
        alike = pt.turned_frames(radial, np.zeros(radial.n_nodes))
        alike.edges.update(radial.edges)
        t = {}
        for _ in range(3):                      # in turn, the least of three rounds each
            for key, m in (("gauge", radial), ("alike", alike)):
                s, mode, on = tangent_time(m)
                t[key] = min(t.get(key, np.inf), s)
        rows.append((n, mode, t["gauge"], t["alike"]))
        print(n, mode, rows[-1][2:], flush=True)
    lines = ["# The cost of the nodal frames' gauge", "",
             f"`python benchmarks/gauge_cost.py` on {datetime.datetime.now().isoformat(timespec='seconds')}: the "
             "compiled element tangent (residual and tangent into the CSR) of an annulus sector of 1 rad, the "
             "generator's radial d1 (the gauge on) against the same quads with d1 = x (no gauge), ms per call.", "",
             "| mesh | driver | radial d1 (gauge) | d1 alike | ratio |", "|---|---|---:|---:|---:|"]
    lines += [f"| {n}x{n} | {mode} | {1e3 * a:.2f} | {1e3 * b:.2f} | {a / b:.3f} |" for n, mode, a, b in rows]
    OUT.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
