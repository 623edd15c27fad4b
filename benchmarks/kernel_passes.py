#!/usr/bin/env python3
"""Where the default element's compiled tangent spends its time: each pass of the serial driver
timed alone, per element, on square plates in a bent state (issue 13's small-mesh target).

Passes (``core_se3.kernels.element_passes``): the edges' logs psi = log(g_a^-1 g_b); the
elements (forces and material blocks G^T Dbar G, scattered into the CSR data); the edges
(edge forces, geometric blocks); the nodes (residual sums, 1/2 adt(r)); and, for comparison,
the whole residual-only and tangent drivers.  The plate's law has no v-w coupling, so the
element passes read Dbar's split form (``ElementKernels.split``); the rows "general path"
time the same drivers on the same Dbar through the general path (Dbar unpacked per element,
as for a law that couples v and w).  Best of ``--repeats`` calls each, one thread.
Writes ``benchmarks/results/kernel_passes.md``.

    .venv/bin/python benchmarks/kernel_passes.py
"""
from __future__ import annotations

import argparse
import datetime
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
RESULTS = ROOT / "benchmarks" / "results"

import numpy as np  # noqa: E402


def _setup(n):
    from core_se3 import Material, Problem, lie, mesh as M
    from core_se3 import kernels as K
    from core_se3.errors import ElementTooDistortedError
    mesh = M.rectangle(10.0, 10.0, n, n)
    p = Problem(mesh, Material(1.0e4, 0.3, 0.1), backend="numpy")
    pat = K.Pattern(mesh.quads, mesh.edge_nodes, mesh.elem_edges, mesh.n_nodes, np.ones(6 * mesh.n_nodes, bool))
    ek = K.ElementKernels.from_element(p.element, pat, mode="serial", error=ElementTooDistortedError)
    X = mesh.X
    # a smooth bent and twisted state: the edge turns stay well below pi
    xi = np.zeros((mesh.n_nodes, 6))
    xi[:, 2] = 0.05 * X[:, 0] ** 2
    xi[:, 3] = 0.2 * X[:, 1]
    xi[:, 4] = -0.3 * X[:, 0]
    g = np.ascontiguousarray(np.einsum("nij,njk->nik", mesh.g0, lie.exp(xi)))
    return mesh, pat, ek, g


def _best(f, repeats):
    f()
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t)
    return best


def measure(n, repeats):
    from core_se3.kernels import element_passes as P
    from core_se3.kernels.element import element_residual_serial, element_tangent_serial
    mesh, pat, ek, g = _setup(n)
    topo, cmap, data = pat.topo, pat.map, pat.new_data()
    m, nE, nn = mesh.n_elements, len(ek.edge_nodes), mesh.n_nodes
    me, ed, w = ek.bundles()
    args = (g, me, ed, topo, cmap, w, data, (None, None, None))
    gen = ed._replace(Dsplit=np.empty((0, 24, 12)))
    gargs = (g, me, gen, topo, cmap, w, data, (None, None, None))
    rows = {
        "tangent (whole driver)": lambda: element_tangent_serial(*args),
        "residual (whole driver)": lambda: element_residual_serial(g, me, ed, topo, w),
        "edges: logs": lambda: P.edges_log(g, me, w, 0, nE),
        "elements: forces only": lambda: P.elements_force(me, ed, w, 0, m),
        "elements: forces + material blocks, scattered": lambda: P.elements_tangent(None, me, ed, w, cmap, data,
                                                                                    0, m),
        "edges: forces + geometric blocks, scattered": lambda: P.edges_tangent(None, me, topo, w, None, None, cmap,
                                                                               data, 0, nE),
        "nodes: residual + 1/2 adt(r), scattered": lambda: P.nodes_pass(topo, me.Rq, w, None, None, data, cmap, 0, nn),
        # the general path (a law coupling v and w: Dbar unpacked per element), on the same Dbar
        "general path: tangent (whole driver)": lambda: element_tangent_serial(*gargs),
        "general path: residual (whole driver)": lambda: element_residual_serial(g, me, gen, topo, w),
        "general path: elements, forces + material blocks, scattered": lambda: P.elements_tangent(
            None, me, gen, w, cmap, data, 0, m),
    }
    element_tangent_serial(*args)          # the state the passes read (psi, fe, rE)
    return m, {k: _best(f, repeats) * 1e6 / m for k, f in rows.items()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[12, 100])
    ap.add_argument("--repeats", type=int, default=30)
    a = ap.parse_args()
    res = [measure(n, a.repeats) for n in a.sizes]
    names = list(res[0][1])
    L = ["# The default element's compiled passes, per element", "",
         f"`python benchmarks/kernel_passes.py` on {datetime.datetime.now().isoformat(timespec='seconds')} "
         f"(one thread, best of {a.repeats}; serial driver; a bent and twisted square plate)", "",
         "| pass [us per element] | " + " | ".join(f"{int(round(m ** 0.5))}x{int(round(m ** 0.5))} ({m} el)"
                                                  for m, _ in res) + " |",
         "|---|" + "---:|" * len(res)]
    for k in names:
        L.append(f"| {k} | " + " | ".join(f"{r[k]:.2f}" for _, r in res) + " |")
    L.append("")
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "kernel_passes.md").write_text("\n".join(L))
    print("\n".join(L))


if __name__ == "__main__":
    sys.exit(main())
