"""Nodal normals against the positions: the chord-normal measure on correct and on wrong frames,
and what wrong normals do to an answer (docs/ELEMENTS.md, "Nodal normals against the positions").

    .venv/bin/python benchmarks/chord_normals.py      -> benchmarks/results/chord_normals.md (~1 min)

mu = |c . (n_a + n_b)| / |c| per mesh edge (``core_se3.fem.warp.chord_normal_mismatch``), its
ratio to the bar CHORD_NORMAL_FLOOR + CHORD_NORMAL_CURVED phi_ends^2 (above 1: the ElementWarning),
the largest normal turn across an edge; then linear answers with wrong normals over the same mesh
with its own.
"""
from __future__ import annotations

import datetime
import glob
import os
import tempfile
import warnings
from pathlib import Path

import meshio
import numpy as np

from core_se3 import Material, Problem, lie, mesh
from core_se3.catalogue import shell_course as sc
from core_se3.fem.warp import CHORD_NORMAL_CURVED, CHORD_NORMAL_FLOOR, CHORD_NORMAL_TURN, chord_normal_bar, chord_normal_mismatch
from core_se3.mesh.readers import from_meshio

import curved_frames as cf

OUT = Path(__file__).parent / "results" / "chord_normals.md"


def _frames(X, quads, d3, d1=None):
    d1 = np.tile([1.0, 0.3, 0.1], (len(X), 1)) if d1 is None else d1
    return mesh.Mesh(mesh.frames_from(X, d1, d3), quads)


def _file(X, q):
    return from_meshio(meshio.Mesh(X, [("quad", q)]))


def _surface(n, kind):
    """A 2 x 2 patch n x n with its exact normals: the saddle z = u v / 2 on a grid turned by 0.5 rad
    (edges off its rulings), the paraboloid z = (x^2 + 0.3 y^2) / 2."""
    m = mesh.rectangle(2.0, 2.0, n, n, x0=-1.0)
    X = m.X.copy()
    if kind == "saddle":
        c, s = np.cos(0.5), np.sin(0.5)
        u, v = c * X[:, 0] - s * X[:, 1], s * X[:, 0] + c * X[:, 1]
        X[:, 2] = 0.5 * u * v
        return _frames(X, m.quads, np.stack([-0.5 * (c * v + s * u), -0.5 * (c * u - s * v), np.ones(len(X))], 1))
    X[:, 2] = 0.5 * (X[:, 0] ** 2 + 0.3 * X[:, 1] ** 2)
    return _frames(X, m.quads, np.stack([-X[:, 0], -0.3 * X[:, 1], np.ones(len(X))], 1))


def _torus(n, Rt=3.0, rt=1.0):
    a, b = np.meshgrid(np.linspace(0, 2 * np.pi, 2 * n + 1)[:-1], np.linspace(0, 2 * np.pi, n + 1)[:-1], indexing="ij")
    X = np.stack([(Rt + rt * np.cos(b)) * np.cos(a), (Rt + rt * np.cos(b)) * np.sin(a), rt * np.sin(b)], -1).reshape(-1, 3)
    d3 = np.stack([np.cos(b) * np.cos(a), np.cos(b) * np.sin(a), np.sin(b)], -1).reshape(-1, 3)
    i = np.arange(2 * n * n).reshape(2 * n, n)
    q = np.stack([i, np.roll(i, -1, 0), np.roll(np.roll(i, -1, 0), -1, 1), np.roll(i, -1, 1)], -1).reshape(-1, 4)
    return _frames(X, q, d3, np.stack([-np.sin(a), np.cos(a), 0 * a], -1).reshape(-1, 3))


def _corrugated(n, A=0.1, shift=0.37):
    m = mesh.rectangle(1.0, 0.5, n, 2)
    X = m.X.copy()
    w = 2 * np.pi * (X[:, 0] + shift / n)
    X[:, 2] = A * np.sin(w)
    return _frames(X, m.quads, np.stack([-A * 2 * np.pi * np.cos(w), 0 * w, np.ones(len(X))], 1))


def _half_tube():
    th = np.radians(np.linspace(-60.0, 60.0, 9))
    X = np.array([[np.cos(t), np.sin(t), z] for z in np.linspace(0.0, 4.0, 9) for t in th])
    q = np.array([[j * 9 + i, j * 9 + i + 1, (j + 1) * 9 + i + 1, (j + 1) * 9 + i] for j in range(8) for i in range(8)])
    return X, q


def _ellipsoid_cap(n, jitter=0.15, seed=1):
    """tests/test_element.py's cap (an ellipsoid's, axes 1.3, 0.8, 1; interior nodes moved along it)."""
    rng = np.random.default_rng(seed)
    t, f = np.linspace(0.3, 0.9, n + 1), np.linspace(-0.6, 0.6, n + 1)
    P = []
    for i, a in enumerate(t):
        for j, b in enumerate(f):
            if 0 < i < n and 0 < j < n:
                a, b = a + jitter * (t[1] - t[0]) * rng.uniform(-1, 1), b + jitter * (f[1] - f[0]) * rng.uniform(-1, 1)
            P.append([1.3 * np.sin(a) * np.cos(b), 0.8 * np.sin(a) * np.sin(b), np.cos(a)])
    q = [[j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i] for j in range(n) for i in range(n)]
    return np.array(P), np.array(q)


def correct_meshes():
    """{name: Mesh} of correct frames: generators, files, Gmsh's domes, the examples, general surfaces."""
    out = {f"hemisphere quarter {n}x{n}": mesh.hemisphere_quarter(10.0, 18.0, n, n) for n in (2, 4, 8)}
    out["Scordelis-Lo roof 2x2"] = mesh.cylinder_panel(25.0, 25.0, 0.0, np.radians(40), 2, 2)
    out["arch 4x1 (pi)"] = mesh.cylinder_arch(1.0, np.pi, 0.2, 4, 1)
    for nx, ny in ((6, 1), (12, 2), (24, 4)):
        out[f"twisted beam 90 deg {nx}x{ny}"] = sc.twisted_mesh(12.0, 1.1, np.pi / 2, nx, ny)
    out["twisted beam 720 deg 12x2"] = sc.twisted_mesh(12.0, 1.1, 4 * np.pi, 12, 2)
    for nx, ny in ((12, 4), (24, 8), (96, 32)):
        out[f"Raasch hook {nx}x{ny} (a curvature jump inside an edge)"] = sc.hook_mesh(nx, ny)
    for n in (6, 12, 32):
        out[f"corrugated sheet z = 0.1 sin(2 pi x), {n} per wave"] = _corrugated(n)
    out["half tube from a file, 15 deg elements (the reader's edge normals)"] = _file(*_half_tube())
    for n in (2, 4, 8, 16):
        out[f"closed cubed sphere from a file, {n} per face"] = _file(*cf.cubed_sphere(n))
    for n in (4, 8):
        g, q = cf.whole_hemisphere(n)
        out[f"whole hemisphere from a file {n}"] = _file(g[:, :3, 3], q)
        out[f"quarter, nodes moved by 0.3, from a file {2 * n}"] = cf._quarter_file(2 * n, 0.3, {})(
            mesh.hemisphere_quarter(10.0, 18.0, 2 * n, 2 * n))
    for path in sorted(glob.glob(str(Path(__file__).parents[1] / "examples" / "*.msh"))):
        out["examples/" + os.path.basename(path)] = from_meshio(path)
    with tempfile.TemporaryDirectory() as tmp:
        for size in (1.6, 0.8):
            cf.gmsh_dome(size, os.path.join(tmp, "dome.msh"))
            out[f"Gmsh dome, size {size}"] = from_meshio(os.path.join(tmp, "dome.msh"))
    for n in (2, 4, 8):
        out[f"saddle, grid off its rulings, {n}x{n}"] = _surface(n, "saddle")
        out[f"paraboloid {n}x{n}"] = _surface(n, "paraboloid")
    out["torus 3 / 1, 8x4"] = _torus(4)
    for n in (4, 8, 16):
        X, q = _ellipsoid_cap(n)
        out[f"ellipsoid cap {n}x{n} (axes 1.3, 0.8, 1), its exact normals"] = _frames(X, q, -X / [1.69, 0.64, 1.0])
    return out


def tilted(g, deg, keep=(), seed=0):
    """Frames g turned each about a random tangent axis by up to ``deg`` (``keep``: nodes left)."""
    rng = np.random.default_rng(seed)
    axis = np.cross(g[:, :3, 2], rng.normal(size=(len(g), 3)))
    axis *= (np.radians(deg) * rng.uniform(0.0, 1.0, len(g)) / np.linalg.norm(axis, axis=1))[:, None]
    axis[np.asarray(keep, int)] = 0.0
    out = g.copy()
    out[:, :3, :3] = np.stack([lie.exp_so3(w) for w in axis]) @ g[:, :3, :3]
    return out


def sphere_normals_on_plate(kappa, n=8):
    m = mesh.rectangle(2.0, 2.0, n, n, x0=-1.0)
    d3 = m.X + [0.0, 0.0, 1.0 / kappa] if kappa else np.tile([0.0, 0.0, 1.0], (m.n_nodes, 1))
    return mesh.Mesh(mesh.frames_from(m.X, np.tile([1.0, 0, 0], (m.n_nodes, 1)), d3), m.quads, edges=m.edges)


def wrong_meshes():
    """{name: Mesh} of wrong frames."""
    out = {f"plate 2 x 2, {n}x{n}, a sphere's normals, curvature {k}": sphere_normals_on_plate(k, n)
           for k in (0.1, 0.3) for n in (2, 8)}
    base = {"plate 8x8": mesh.rectangle(1.0, 1.0, 8, 8), "hemisphere 8x8": mesh.hemisphere_quarter(10.0, 18.0, 8, 8),
            "hemisphere 4x4": mesh.hemisphere_quarter(10.0, 18.0, 4, 4),
            "hemisphere 2x2": mesh.hemisphere_quarter(10.0, 18.0, 2, 2),
            "roof 4x4": mesh.cylinder_panel(25.0, 25.0, 0.0, np.radians(40), 4, 4),
            "twisted beam 12x2": sc.twisted_mesh(12.0, 1.1, np.pi / 2, 12, 2)}
    for name, m in base.items():
        for d in (5, 10, 20):
            out[f"{name}, tilted at random by up to {d} deg"] = mesh.Mesh(tilted(m.g0, d), m.quads)
        g = m.g0.copy()
        g[m.n_nodes // 2, :3, 1:3] *= -1.0
        out[f"{name}, one node's normal flipped"] = mesh.Mesh(g, m.quads)
        g = m.g0.copy()
        g[:, :3, :3] = lie.exp_so3([0.0, np.radians(5.0), 0.0]) @ g[:, :3, :3]
        out[f"{name}, all frames turned by 5 deg about y (not the positions)"] = mesh.Mesh(g, m.quads)
    for n in (4, 8, 16):
        X, q = _ellipsoid_cap(n)
        out[f"ellipsoid cap from a file {n}x{n} (the reader's boundary normals)"] = _file(X, q)
    s = np.linspace(0.0, 1.0, 5)
    X = np.array([p for z in s for p in [[x, 0.0, z] for x in s[::-1][:-1]] + [[0.0, y, z] for y in s]])
    q = np.array([[j * 9 + i, j * 9 + i + 1, (j + 1) * 9 + i + 1, (j + 1) * 9 + i] for j in range(4) for i in range(8)])
    out["an L angle (a 90 deg fold) from a file, 4x4 per face"] = _file(X, q)
    return out


def rows(meshes):
    out = []
    for name, m in meshes.items():
        mu, phi, ends = chord_normal_mismatch(m.X, m.edge_nodes, m.g0)
        r = mu / chord_normal_bar(ends)
        out.append(f"| {name} | {mu.max():.2g} | {np.degrees(phi.max()):.0f} | {r.max():.2g} | {(r > 1).sum()} / {len(r)} |")
    return out


def _pressed_plate(kappa, h):
    m = sphere_normals_on_plate(kappa)
    p = Problem(m, Material(1e4, 0.3, h))
    for e in ("x0", "x1", "y0", "y1"):
        p.fix(e, (0, 1, 2))
    p.add_pressure(-h ** 3)
    return float(np.abs(p.solve_linear().displacements()[:, 2]).max())


def _hemisphere(n, deg):
    def transform(m):
        keep = np.concatenate([m.node_set("y0"), m.node_set("y1")])   # the supports' body-frame dofs
        return mesh.Mesh(tilted(m.g0, deg, keep), m.quads, edges=m.edges)
    p, measure = sc.pinched_hemisphere(n, transform=transform if deg else None)
    return measure(p.solve_linear())


def answer_rows():
    out = []
    for h in (0.01, 0.005, 0.001):
        flat = _pressed_plate(0.0, h)
        out.append(f"| plate 2 x 2, 8x8, edges pinned, pressed, h {h}: a sphere's normals of curvature 0.1 / 0.3 | "
                   + " / ".join(f"{_pressed_plate(k, h) / flat:.3f}" for k in (0.1, 0.3)) + " |")
    for n in (4, 8):
        ref = _hemisphere(n, 0.0)
        out.append(f"| pinched hemisphere {n}x{n}, R/h 250, interior normals tilted at random by up to 2 / 5 / 10 / 20 deg | "
                   + " / ".join(f"{_hemisphere(n, d) / ref:.3f}" for d in (2, 5, 10, 20)) + " |")
    return out


def main():
    warnings.simplefilter("ignore")
    head = ["| mesh | max mu | max normal turn across an edge [deg] | max mu / bar | edges above the bar |",
            "|---|---|---|---|---|"]
    text = [f"# Nodal normals against the positions ({datetime.date.today()})", "",
            f"`python benchmarks/chord_normals.py`; bar = {CHORD_NORMAL_FLOOR} + {CHORD_NORMAL_TURN} phi_ends + "
            f"{CHORD_NORMAL_CURVED} phi_ends^2.", "",
            "## Correct frames", ""] + head + rows(correct_meshes()) + \
           ["", "## Wrong frames, and a mesh file's own where they are off (a flipped normal warns by its turn, "
            "above 120 deg)", ""] + head + rows(wrong_meshes()) + \
           ["", "## Answers with wrong normals over those with the right ones (linear)", "", "| case | ratio |", "|---|---|"] \
           + answer_rows()
    OUT.write_text("\n".join(text) + "\n")
    print("\n".join(text))


if __name__ == "__main__":
    main()
