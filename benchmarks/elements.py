"""Properties a-e of the default element and of the seed's scheme, measured side by side.

    .venv/bin/python benchmarks/elements.py [--out benchmarks/results/elements.md]

a. path independence: cantilever-shear at P = 1, one load step vs 40 (max nodal |du| / L), and
   invariance of energy and residual under a superposed rigid motion with |w| = 20 pi;
b. tangent: max relative difference between the element tangent and central differences of
   its residual along g <- g exp(eps eta) (for the seed, the state is updated incrementally as
   in its Algorithm 1); Newton iterations of one step of the cantilever;
c. zero-energy modes of a free distorted 2x2 patch (eigenvalues < 1e-10 lambda_max of the
   finite-difference tangent: the derivative of the residual the element actually uses);
d. locking: cantilever-shear error at L/h = 100 and 1e4 (32 x 1, P L^2/EI to 1);
e. exactness: rollup to k = 1 on 10 x 1 elements, tip distance to the exact circle / L.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from core_se3 import Material, Problem, lie, mesh as M
from core_se3.catalogue import run_case
from core_se3.errors import CoreSE3Error


def _kw(element):
    """The seed converges linearly (its tangent is not its residual's derivative): give it more
    iterations per step but fewer cut-backs, so that a failing case fails in bounded time."""
    return dict(max_iter=300, max_cutbacks=3) if element == "seed" else dict(max_iter=30)


def _problem(element, nx=16, P=1.0):
    p = Problem(M.rectangle(10.0, 1.0, nx, 1), Material(1.2e6, 0.0, 0.1), element=element)
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, P))
    p.add_probe("tip", "x1")
    return p


def prop_a(element):
    out = {}
    try:
        r1 = _problem(element).solve(steps=1, max_cutbacks=0, max_iter=_kw(element)['max_iter'], rtol=1e-12, dtol=1e-12)
        r40 = _problem(element).solve(steps=40, **_kw(element), rtol=1e-12, dtol=1e-12)
        out["path_1_vs_40"] = float(np.abs(r1.displacements() - r40.displacements()).max() / 10.0)
    except CoreSE3Error as exc:
        out["path_1_vs_40"] = f"failed: {str(exc)[:60]}"
    # superposed rigid motion on a deformed state
    p = _problem(element, nx=4)
    rng = np.random.default_rng(0)
    g = p.mesh.g0 @ lie.exp(0.2 * rng.standard_normal((p.mesh.n_nodes, 6)))
    if getattr(p.element, "stateful", False):
        p.element.update(lie.log(lie.inv(p.mesh.g0) @ g))
    e1, r1 = p.element.evaluate(g, tangent=False).energy, p.element.evaluate(g, tangent=False).r
    h = lie.exp(np.r_[1.0, 2.0, 3.0, 20 * np.pi * np.array([0.6, 0.0, 0.8])])
    e2, r2 = p.element.evaluate(h @ g, tangent=False).energy, p.element.evaluate(h @ g, tangent=False).r
    out["rigid_energy"] = float(abs(e2 - e1) / abs(e1))
    out["rigid_residual"] = float(np.abs(r2 - r1).max() / np.abs(r1).max())
    return out


def _fd_tangent(p, g, h=1e-6):
    el = p.element
    stateful = getattr(el, "stateful", False)
    n = p.mesh.n_nodes
    if stateful:
        el.save()
    ev = el.evaluate(g, tangent=True)
    K = np.zeros((6 * n, 6 * n))
    q = p.mesh.quads
    for k in range(len(q)):
        for a in range(4):
            for b in range(4):
                K[6 * q[k, a]:6 * q[k, a] + 6, 6 * q[k, b]:6 * q[k, b] + 6] += ev.element_blocks[k, a, b]
    for E, (a, b) in enumerate(p.mesh.edge_nodes if ev.edge_blocks is not None else ()):   # the seed: none
        for i, A in enumerate((a, b)):
            for j, B in enumerate((a, b)):
                K[6 * A:6 * A + 6, 6 * B:6 * B + 6] += ev.edge_blocks[E, i, j]
    for i in range(n if ev.node_blocks is not None else 0):
        K[6 * i:6 * i + 6, 6 * i:6 * i + 6] += ev.node_blocks[i]
    Kfd = np.zeros_like(K)
    for j in range(6 * n):
        d = np.zeros((n, 6))
        d.ravel()[j] = h
        rs = []
        for s in (1, -1):
            if stateful:
                el.restore()
                el.update(s * d)
            rs.append(el.evaluate(g @ lie.exp(s * d), tangent=False).r.ravel())
        Kfd[:, j] = (rs[0] - rs[1]) / (2 * h)
    if stateful:
        el.restore()
    return K, Kfd


def prop_b_c(element):
    out = {}
    p = _problem(element, nx=2)
    rng = np.random.default_rng(1)
    g = p.mesh.g0 @ lie.exp(0.3 * rng.standard_normal((p.mesh.n_nodes, 6)))
    if getattr(p.element, "stateful", False):
        p.element.update(lie.log(lie.inv(p.mesh.g0) @ g))
    K, Kfd = _fd_tangent(p, g)
    out["tangent_fd_mismatch"] = float(np.abs(K - Kfd).max() / np.abs(Kfd).max())
    # zero modes of a free distorted 2x2 patch at the reference state
    m = M.rectangle(1.0, 1.0, 2, 2)
    g0 = m.g0.copy()
    g0[4, :3, 3] += [0.13, -0.08, 0.0]
    pp = Problem(M.Mesh(g0, m.quads, m.edges), Material(1e4, 0.3, 0.1), element=element)
    _, Kfd0 = _fd_tangent(pp, pp.mesh.g0)
    ev = np.sort(np.abs(np.linalg.eigvals(Kfd0)))
    out["zero_modes"] = int(np.sum(ev < 1e-10 * ev[-1]))
    try:
        r = _problem(element, P=1.0).solve(steps=1, max_cutbacks=0, max_iter=300)
        out["newton_iterations_P1"] = r.final.iterations
    except CoreSE3Error as exc:
        out["newton_iterations_P1"] = f"failed: {str(exc)[:60]}"
    return out


def prop_d(element):
    out = {}
    for Lh in (100.0, 1e4):
        h = 10.0 / Lh
        EI = 1.2e6 * h ** 3 / 12
        try:
            doc, _, _ = run_case("cantilever-shear", mesh=(32, 1), steps=4, element=element,
                                 overrides=dict(h=h, load_max=EI / 100.0), **_kw(element))
            out[f"error_L/h={Lh:g}"] = doc["reference"]["error"]
        except CoreSE3Error as exc:
            out[f"error_L/h={Lh:g}"] = f"failed: {str(exc)[:60]}"
    return out


def prop_e(element):
    try:
        doc, res, _ = run_case("rollup", mesh=(10, 1), steps=8, element=element,
                               overrides=dict(k=1.0), **_kw(element))
        u = np.array(doc["steps"][-1]["probes"]["tip"]["u"])
        return {"rollup_k1_tip_error/L": float(np.linalg.norm(u - np.array([-10.0, 0, 0])) / 10.0)}
    except CoreSE3Error as exc:
        return {"rollup_k1_tip_error/L": f"failed: {str(exc)[:60]}"}


def main():
    from core_se3.backend import pin_for_timing
    pin_for_timing()          # time the compiled product, not 'auto''s NumPy start
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="benchmarks/results/elements.md")
    args = ap.parse_args()
    rows = {}
    for element in ("default", "seed"):
        t = time.perf_counter()
        r = {}
        for f in (prop_a, prop_b_c, prop_d, prop_e):
            r.update(f(element))
        r["seconds"] = time.perf_counter() - t
        rows[element] = r
        print(element, r, flush=True)
    keys = list(rows["default"])
    fmt = lambda v: f"{v:.3g}" if isinstance(v, float) else str(v)
    lines = ["| property | default | seed |", "|---|---|---|"]
    lines += [f"| {k} | {fmt(rows['default'][k])} | {fmt(rows['seed'][k])} |" for k in keys]
    import os
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as fh:
        fh.write("# Default element vs the seed's scheme (benchmarks/elements.py)\n\n" + "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
