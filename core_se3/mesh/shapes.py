"""Flat outlines of soft robots with named regions and edges: a star with n arms (a cross for
n = 4), a regular polygon, a rounded rectangle, a disk and an annulus sector.

Every generator takes a target element ``size`` and a ``backend``: ``"structured"`` (blocks of
transfinite quads, always available, the same mesh everywhere), ``"gmsh"`` (Gmsh's OCC outline
meshed into quads, :mod:`core_se3.mesh.gmsh_backend`) or ``"auto"`` (Gmsh where it is
installed, structured otherwise).  Both backends give the same region and node-set names, in
the x-y plane with normal +z; ``save=PATH`` keeps the Gmsh backend's MSH 4.1 file.
Pictures of each shape are in docs/SCENARIOS.md.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import MeshError, warn_angle
from .core import Mesh, frames_from
from .gmsh_backend import gmsh_module, mesh_surfaces

__all__ = ["star", "polygon", "rounded_rectangle", "disk", "annulus_sector", "BACKENDS", "resolve_backend"]

BACKENDS = ("auto", "structured", "gmsh")


def resolve_backend(backend):
    """``"gmsh"`` or ``"structured"`` for a requested backend (``"auto"``: Gmsh if installed).

    Example
    -------
    >>> resolve_backend("structured")
    'structured'
    """
    if backend not in BACKENDS:
        raise MeshError(f"unknown mesh backend {backend!r}; choose one of {', '.join(BACKENDS)}")
    if backend == "auto":
        return "gmsh" if gmsh_module() is not None else "structured"
    return backend


def _n(length, size):
    return max(1, int(math.ceil(length / size - 1e-9)))


def _coons(bottom, right, top, left):
    """Transfinite (Coons) patch from its four boundaries: bottom/top (nu + 1, 3) from left to
    right, left/right (nv + 1, 3) from bottom to top; returns the grid (nv + 1, nu + 1, 3)."""
    nu, nv = len(bottom) - 1, len(left) - 1
    u = np.linspace(0, 1, nu + 1)[None, :, None]
    v = np.linspace(0, 1, nv + 1)[:, None, None]
    P = ((1 - v) * bottom[None] + v * top[None] + (1 - u) * left[:, None] + u * right[:, None]
         - ((1 - u) * (1 - v) * bottom[0] + u * (1 - v) * bottom[-1] + (1 - u) * v * top[0] + u * v * top[-1]))
    return P


def _line(a, b, fractions):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a + np.asarray(fractions)[:, None] * (b - a)


def _assemble(blocks, edges_of, scale):
    """Merge structured blocks [(grid (nv+1, nu+1, 3), region names)] into a Mesh: coincident
    nodes joined, every quad counter-clockwise about +z; edges_of(X) -> {name: ordered ids}."""
    pts, quads, reg = [], [], {}
    off = 0
    for P, names in blocks:
        nv, nu = P.shape[0] - 1, P.shape[1] - 1
        ids = off + np.arange((nv + 1) * (nu + 1)).reshape(nv + 1, nu + 1)
        q = np.stack([ids[:-1, :-1], ids[:-1, 1:], ids[1:, 1:], ids[1:, :-1]], -1).reshape(-1, 4)
        X = P.reshape(-1, 3)
        pts.append(X)
        e0 = len(np.concatenate(quads)) if quads else 0
        quads.append(q)
        for name in names:
            reg.setdefault(name, []).extend(range(e0, e0 + len(q)))
        off += len(X)
    X = np.concatenate(pts)
    quads = np.concatenate(quads)
    key = np.round(X / (1e-9 * scale)).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)                       # keep the first occurrence's order
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    X = X[first[order]]
    quads = rank[inv.ravel()][quads]
    P = X[quads]
    area = np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])[:, 2]
    quads[area < 0] = quads[area < 0][:, ::-1]
    n = len(X)
    g0 = frames_from(X, np.tile([1.0, 0, 0], (n, 1)), np.tile([0, 0, 1.0], (n, 1)))
    return Mesh(g0, quads, edges_of(X), regions={k: np.asarray(v) for k, v in reg.items()})


def _along(X, ids, direction):
    ids = np.asarray(ids, np.int64)
    return ids[np.argsort(X[ids] @ np.asarray(direction, float))]


def _fan_blocks(c, verts, w_of_side, m, p, names):
    """Blocks (centre, mid_k, vertex_k+1, mid_k+1) of a convex polygon; each half side has m
    segments over w/2 from its midpoint (the arm's half width) and p over the rest."""
    n = len(verts)
    blocks = []
    for k in range(n):
        v1 = verts[(k + 1) % n]
        mk, mk1 = (verts[k] + v1) / 2, (v1 + verts[(k + 2) % n]) / 2
        half = np.linalg.norm(v1 - mk)
        fw = min(w_of_side / 2 / half, 1.0)
        fr = np.concatenate([np.linspace(0, fw, m + 1), np.linspace(fw, 1, p + 1)[1:]]) if p else np.linspace(0, 1, m + 1)
        bottom = _line(c, mk, fr)
        left = _line(c, mk1, fr)
        right = _line(mk, v1, fr)
        top = _line(mk1, v1, fr)
        blocks.append((_coons(bottom, right, top, left), names))
    return blocks


def _regular(n, R, angle0):
    th = angle0 + (2 * np.arange(n) - 1) * np.pi / n          # side k centred at angle0 + 2 pi k / n
    return np.stack([R * np.cos(th), R * np.sin(th), np.zeros(n)], -1)


def star(n_arms, arm_length, arm_width, palm=None, size=None, backend="auto", angle0=0.0, save=None):
    """Flat star (an n-arm gripper): a regular polygon palm and ``n_arms`` straight arms, one on
    the middle of each side; ``n_arms = 4`` is a cross.

    Arm k points along the angle angle0 + 2 pi k / n (arm 0 along +x by default).  Regions:
    ``palm``, ``finger_0`` ... ``finger_{n-1}`` and ``fingers`` (all arms); node sets ``tip_k``
    (the end line of arm k, ordered counter-clockwise) and ``tips`` (all of them).

    Parameters
    ----------
    n_arms : int
        Number of arms, >= 3.
    arm_length, arm_width : float
        Length of an arm beyond the palm and its width [length], > 0.
    palm : float, optional
        Circumradius of the palm polygon [length]; default the smallest, whose side is the arm
        width (arm_width / (2 sin(pi/n))).
    size : float, optional
        Target element size [length] (default arm_width / 4).
    backend : {"auto", "structured", "gmsh"}, optional
        Structured blocks (the arms n_along x 2m quads, the palm n kites), or Gmsh.
    angle0 : float, optional
        Direction of arm 0 [rad].
    save : str, optional
        Gmsh backend: keep its MSH 4.1 file (physical groups as the names above).

    Returns
    -------
    Mesh

    Example
    -------
    >>> m = star(4, 20.0, 6.0, size=2.0, backend="structured")
    >>> m.n_elements, len(m.regions["finger_0"]), len(m.node_set("tip_0")), sorted(m.regions)[:2]
    (176, 40, 5, ['finger_0', 'finger_1'])
    >>> round(float(m.X[m.node_set("tip_0"), 0].max()), 12)            # palm apothem 3 + arm 20
    23.0
    """
    if not (isinstance(n_arms, (int, np.integer)) and n_arms >= 3):
        raise MeshError(f"a star needs an integer n_arms >= 3, got {n_arms!r}")
    if not (arm_length > 0 and arm_width > 0):
        raise MeshError(f"star needs arm_length > 0 and arm_width > 0, got {arm_length}, {arm_width}")
    n = int(n_arms)
    warn_angle(angle0, "star: angle0", path=False)
    r_min = arm_width / (2 * math.sin(math.pi / n))
    R = r_min if palm is None else float(palm)
    if R < r_min * (1 - 1e-12):
        raise MeshError(f"palm circumradius {R:g} is too small for {n} arms of width {arm_width:g}: the "
                        f"palm side must be at least the arm width (palm >= {r_min:.6g})")
    size = arm_width / 4 if size is None else float(size)
    if not size > 0:
        raise MeshError(f"element size must be positive, got {size}")
    side, apo = 2 * R * math.sin(math.pi / n), R * math.cos(math.pi / n)
    phis = angle0 + 2 * np.pi * np.arange(n) / n
    e = np.stack([np.cos(phis), np.sin(phis), np.zeros(n)], -1)
    t = np.stack([-np.sin(phis), np.cos(phis), np.zeros(n)], -1)
    tol = 1e-7 * (apo + arm_length)

    def tip_pred(k):
        return lambda x: abs(x @ e[k] - apo - arm_length) < tol and abs(x @ t[k]) <= arm_width / 2 + tol

    if resolve_backend(backend) == "gmsh":
        def build(occ):
            verts = _regular(n, R, angle0)
            pts = [occ.addPoint(*v) for v in verts]
            loop = occ.addCurveLoop([occ.addLine(pts[i], pts[(i + 1) % n]) for i in range(n)])
            out = {"palm": [occ.addPlaneSurface([loop])]}
            arms = []
            for k in range(n):
                c = [apo * e[k] - arm_width / 2 * t[k], (apo + arm_length) * e[k] - arm_width / 2 * t[k],
                     (apo + arm_length) * e[k] + arm_width / 2 * t[k], apo * e[k] + arm_width / 2 * t[k]]
                cp = [occ.addPoint(*x) for x in c]
                lp = occ.addCurveLoop([occ.addLine(cp[i], cp[(i + 1) % 4]) for i in range(4)])
                arms.append(occ.addPlaneSurface([lp]))
                out[f"finger_{k}"] = [arms[-1]]
            out["fingers"] = arms
            return out
        curves = {f"tip_{k}": tip_pred(k) for k in range(n)}
        curves["tips"] = lambda x: any(tip_pred(k)(x) for k in range(n))
        m = mesh_surfaces(build, size, curves=curves, save=save)
        for k in range(n):
            m.edges[f"tip_{k}"] = _along(m.X, m.edges[f"tip_{k}"], t[k])
        return m
    mh = _n(arm_width / 2, size)
    p = _n((side - arm_width) / 2, size) if side - arm_width > 1e-9 * side else 0
    blocks = _fan_blocks(np.zeros(3), _regular(n, R, angle0), arm_width, mh, p, ["palm"])
    na = _n(arm_length, size)
    for k in range(n):
        a0, a1 = apo * e[k] - arm_width / 2 * t[k], apo * e[k] + arm_width / 2 * t[k]
        b0, b1 = a0 + arm_length * e[k], a1 + arm_length * e[k]
        s = np.linspace(0, 1, 2 * mh + 1)
        r = np.linspace(0, 1, na + 1)
        blocks.append((_coons(_line(a0, a1, s), _line(a1, b1, r), _line(b0, b1, s), _line(a0, b0, r)),
                       [f"finger_{k}", "fingers"]))

    def edges_of(X):
        out = {}
        for k in range(n):
            out[f"tip_{k}"] = _along(X, [i for i in range(len(X)) if tip_pred(k)(X[i])], t[k])
        out["tips"] = np.concatenate([out[f"tip_{k}"] for k in range(n)])
        return out
    return _assemble(blocks, edges_of, apo + arm_length)


def polygon(n_sides, radius, size=None, backend="auto", angle0=0.0, save=None):
    """Flat regular polygon of circumradius ``radius``, side k centred at angle0 + 2 pi k / n.

    Region ``polygon``; node sets ``side_k`` (ordered counter-clockwise) and ``boundary``
    (all boundary nodes).

    Parameters
    ----------
    n_sides : int
        Number of sides, >= 3.
    radius : float
        Circumradius [length], > 0.
    size : float, optional
        Target element size [length] (default radius / 4).
    backend, angle0, save
        As for :func:`star`.

    Returns
    -------
    Mesh

    Example
    -------
    >>> m = polygon(6, 2.0, size=0.5, backend="structured")
    >>> m.n_elements, len(m.node_set("side_0"))
    (24, 5)
    """
    if not (isinstance(n_sides, (int, np.integer)) and n_sides >= 3) or not radius > 0:
        raise MeshError(f"polygon needs an integer n_sides >= 3 and radius > 0, got {n_sides!r}, {radius!r}")
    n = int(n_sides)
    warn_angle(angle0, "polygon: angle0", path=False)
    size = radius / 4 if size is None else float(size)
    verts = _regular(n, radius, angle0)
    apo = radius * math.cos(math.pi / n)
    phis = angle0 + 2 * np.pi * np.arange(n) / n
    e = np.stack([np.cos(phis), np.sin(phis), np.zeros(n)], -1)
    t = np.stack([-np.sin(phis), np.cos(phis), np.zeros(n)], -1)
    tol = 1e-7 * radius
    on = lambda k: (lambda x: abs(x @ e[k] - apo) < tol)
    if resolve_backend(backend) == "gmsh":
        def build(occ):
            pts = [occ.addPoint(*v) for v in verts]
            loop = occ.addCurveLoop([occ.addLine(pts[i], pts[(i + 1) % n]) for i in range(n)])
            return {"polygon": [occ.addPlaneSurface([loop])]}
        curves = {f"side_{k}": on(k) for k in range(n)}
        curves["boundary"] = lambda x: True
        m = mesh_surfaces(build, size, curves=curves, save=save)
    else:
        half = radius * math.sin(math.pi / n)
        m = _assemble(_fan_blocks(np.zeros(3), verts, 2 * half, _n(half, size), 0, ["polygon"]),
                      lambda X: {}, radius)
        for k in range(n):
            m.edges[f"side_{k}"] = np.nonzero([on(k)(x) for x in m.X])[0]
        m.edges["boundary"] = np.unique(np.concatenate([m.edges[f"side_{k}"] for k in range(n)]))
    for k in range(n):
        m.edges[f"side_{k}"] = _along(m.X, m.edges[f"side_{k}"], t[k])
    return m


def rounded_rectangle(length, width, radius=0.0, size=None, backend="auto", save=None, _names=None):
    """Flat rectangle ``length`` x ``width`` centred at the origin with corners rounded to
    ``radius`` (0: sharp; min(length, width) / 2 with length = width: a disk).

    Region ``plate``; node sets ``x0``, ``x1`` (the straight parts of the sides x = -+length/2,
    ordered along y), ``y0``, ``y1`` (y = -+width/2, along x) and ``boundary``.  Structured: an
    O-grid (an inner rectangle and four blocks out to the outline).

    Parameters
    ----------
    length, width : float
        Extent along x and y [length], > 0.
    radius : float, optional
        Corner radius [length], 0 <= radius <= min(length, width) / 2.
    size : float, optional
        Target element size [length] (default min(length, width) / 8).
    backend, save
        As for :func:`star`.

    Returns
    -------
    Mesh

    Example
    -------
    >>> m = rounded_rectangle(4.0, 2.0, 0.5, size=0.5, backend="structured")
    >>> sorted(m.edges), m.n_elements
    (['boundary', 'x0', 'x1', 'y0', 'y1'], 56)
    """
    if not (length > 0 and width > 0 and 0 <= radius <= min(length, width) / 2 * (1 + 1e-12)):
        raise MeshError("rounded_rectangle needs length, width > 0 and 0 <= radius <= min(length, width)/2, "
                        f"got {length}, {width}, {radius}")
    region, names = _names or ("plate", {})
    size = min(length, width) / 8 if size is None else float(size)
    a, b, r = length / 2, width / 2, min(float(radius), min(length, width) / 2)
    tol = 1e-7 * max(a, b)
    side_pred = {"x0": lambda x: abs(x[0] + a) < tol and abs(x[1]) <= b - r + tol,
                 "x1": lambda x: abs(x[0] - a) < tol and abs(x[1]) <= b - r + tol,
                 "y0": lambda x: abs(x[1] + b) < tol and abs(x[0]) <= a - r + tol,
                 "y1": lambda x: abs(x[1] - b) < tol and abs(x[0]) <= a - r + tol}

    def boundary_pred(x):
        dx, dy = max(abs(x[0]) - (a - r), 0.0), max(abs(x[1]) - (b - r), 0.0)
        on_side = abs(abs(x[0]) - a) < tol or abs(abs(x[1]) - b) < tol
        return (dx > 0 and dy > 0 and abs(math.hypot(dx, dy) - r) < tol) or (on_side and (dx == 0 or dy == 0))

    if resolve_backend(backend) == "gmsh":
        def build(occ):
            return {region: [occ.addRectangle(-a, -b, 0, 2 * a, 2 * b, roundedRadius=r if r > 0 else 0.0)]
                    if r < min(a, b) * (1 - 1e-12) or a != b else [occ.addDisk(0, 0, 0, a, a)]}
        curves = {names.get(k, k): p for k, p in side_pred.items()} if r < min(a, b) * (1 - 1e-12) else {}
        curves[names.get("boundary", "boundary")] = lambda x: True
        m = mesh_surfaces(build, size, curves=curves, save=save)
    else:
        nx, ny = _n(2 * a, size), _n(2 * b, size)
        nr = _n(min(a, b) / 2, size)

        corners = [np.array([a, -b]), np.array([a, b]), np.array([-a, b]), np.array([-a, -b])]
        centres = [np.array([a - r, -(b - r)]), np.array([a - r, b - r]), np.array([-(a - r), b - r]),
                   np.array([-(a - r), -(b - r)])]
        diag = [c + r * (k - c) / max(np.linalg.norm(k - c), 1e-300) if r > 0 else k
                for k, c in zip(corners, centres)]
        blocks = []
        inner = [np.array([0.5 * a, -0.5 * b]), np.array([0.5 * a, 0.5 * b]), np.array([-0.5 * a, 0.5 * b]),
                 np.array([-0.5 * a, -0.5 * b])]
        counts = [ny, nx, ny, nx]                        # right, top, left, bottom outer blocks
        for q in range(4):
            c0, c1, cnt = q, (q + 1) % 4, counts[q]
            outer = np.c_[_outline(centres[c0], centres[c1], diag[c0], diag[c1], r, corners[c0], corners[c1], cnt),
                          np.zeros(cnt + 1)]
            inn = np.c_[_line(inner[c0], inner[c1], np.linspace(0, 1, cnt + 1)), np.zeros(cnt + 1)]
            left = _line(np.r_[inner[c0], 0], np.r_[diag[c0], 0], np.linspace(0, 1, nr + 1))
            right = _line(np.r_[inner[c1], 0], np.r_[diag[c1], 0], np.linspace(0, 1, nr + 1))
            blocks.append((_coons(inn, right, outer, left), [region]))
        xs, ys = np.linspace(-0.5 * a, 0.5 * a, nx + 1), np.linspace(-0.5 * b, 0.5 * b, ny + 1)
        XX, YY = np.meshgrid(xs, ys)
        blocks.append((np.stack([XX, YY, np.zeros_like(XX)], -1), [region]))

        def edges_of(X):
            out = {names.get(k, k): np.nonzero([p(x) for x in X])[0] for k, p in side_pred.items()}
            if r >= min(a, b) * (1 - 1e-12):
                out = {}
            out[names.get("boundary", "boundary")] = np.nonzero([boundary_pred(x) for x in X])[0]
            return out
        m = _assemble(blocks, edges_of, max(a, b))
    for k, d in (("x0", [0, 1, 0]), ("x1", [0, 1, 0]), ("y0", [1, 0, 0]), ("y1", [1, 0, 0])):
        if names.get(k, k) in m.edges:
            m.edges[names.get(k, k)] = _along(m.X, m.edges[names.get(k, k)], d)
    return m


def _outline(c0, c1, d0, d1, r, k0, k1, n):
    """n + 1 points evenly spaced in arc length on the outline from the diagonal point d0 of
    corner 0 to d1 of corner 1: the rest of arc 0, the straight side, the first half of arc 1
    (exactly on the arcs)."""
    if r <= 0:
        return _line(d0, d1, np.linspace(0, 1, n + 1))
    normal = math.atan2(*((k1 - k0) / np.linalg.norm(k1 - k0))[::-1]) - math.pi / 2   # outward side normal
    a0 = math.atan2(*(d0 - c0)[::-1])
    da0 = _wrap(normal - a0)
    da1 = _wrap(math.atan2(*(d1 - c1)[::-1]) - normal)
    p0, p1 = c0 + r * np.array([math.cos(normal), math.sin(normal)]), c1 + r * np.array([math.cos(normal), math.sin(normal)])
    l0, ls, l1 = r * abs(da0), float(np.linalg.norm(p1 - p0)), r * abs(da1)
    out = []
    for x in np.linspace(0, l0 + ls + l1, n + 1):
        if x <= l0:
            th = a0 + da0 * (x / l0 if l0 else 1.0)
            out.append(c0 + r * np.array([math.cos(th), math.sin(th)]))
        elif x <= l0 + ls:
            out.append(p0 + (x - l0) / ls * (p1 - p0))
        else:
            th = normal + da1 * min((x - l0 - ls) / l1, 1.0)
            out.append(c1 + r * np.array([math.cos(th), math.sin(th)]))
    return np.array(out)


def _wrap(x):
    return (x + math.pi) % (2 * math.pi) - math.pi


def disk(radius, size=None, backend="auto", save=None):
    """Flat disk of ``radius`` centred at the origin.  Region ``disk``; node set ``rim``.

    Parameters
    ----------
    radius : float
        [length], > 0.
    size : float, optional
        Target element size [length] (default radius / 4).
    backend, save
        As for :func:`star`.

    Returns
    -------
    Mesh

    Example
    -------
    >>> import numpy as np
    >>> m = disk(1.0, size=0.25, backend="structured")
    >>> bool(np.allclose(np.linalg.norm(m.X[m.node_set("rim")], axis=1), 1.0)), sorted(m.regions)
    (True, ['disk'])
    """
    if not radius > 0:
        raise MeshError(f"disk needs radius > 0, got {radius}")
    return rounded_rectangle(2 * radius, 2 * radius, radius, size=radius / 4 if size is None else size,
                             backend=backend, save=save, _names=("disk", {"boundary": "rim"}))


def annulus_sector(r_in, r_out, angle, size=None, backend="auto", theta0=0.0, save=None):
    """Flat annulus sector r_in <= r <= r_out, theta0 <= theta <= theta0 + angle (< 2 pi).

    Region ``sector``; node sets ``inner``, ``outer`` (the arcs, counter-clockwise), ``start``
    and ``end`` (the radial edges, outward).

    Parameters
    ----------
    r_in, r_out : float
        Radii [length], 0 < r_in < r_out.
    angle : float
        Opening [rad], 0 < angle < 2 pi.
    size : float, optional
        Target element size [length] (default (r_out - r_in) / 4).
    backend, save
        As for :func:`star`; ``theta0``: start angle [rad].

    Returns
    -------
    Mesh

    Example
    -------
    >>> m = annulus_sector(1.0, 2.0, 1.5, size=0.25, backend="structured")
    >>> m.n_elements, len(m.node_set("outer")), sorted(m.edges)
    (36, 10, ['end', 'inner', 'outer', 'start'])
    """
    if not (0 < r_in < r_out and 0 < angle < 2 * np.pi):
        raise MeshError("annulus_sector needs 0 < r_in < r_out and 0 < angle < 2 pi, got "
                        f"{r_in}, {r_out}, {angle}")
    warn_angle(theta0, "annulus_sector: theta0", path=False)
    size = (r_out - r_in) / 4 if size is None else float(size)
    tol = 1e-7 * r_out
    th1 = theta0 + angle
    radial = lambda th: np.array([math.cos(th), math.sin(th), 0.0])
    preds = {"inner": lambda x: abs(np.hypot(x[0], x[1]) - r_in) < tol,
             "outer": lambda x: abs(np.hypot(x[0], x[1]) - r_out) < tol,
             "start": lambda x: abs(x @ np.array([-math.sin(theta0), math.cos(theta0), 0])) < tol and x @ radial(theta0) > 0,
             "end": lambda x: abs(x @ np.array([-math.sin(th1), math.cos(th1), 0])) < tol and x @ radial(th1) > 0}
    if resolve_backend(backend) == "gmsh":
        def build(occ):
            c = occ.addPoint(0, 0, 0)
            p = [occ.addPoint(*(r * radial(t))) for r, t in ((r_in, theta0), (r_out, theta0), (r_out, th1), (r_in, th1))]
            curves = [occ.addLine(p[0], p[1]), occ.addCircleArc(p[1], c, p[2]), occ.addLine(p[2], p[3]),
                      occ.addCircleArc(p[3], c, p[0])]
            s = occ.addPlaneSurface([occ.addCurveLoop(curves)])
            occ.remove([(0, c)])
            return {"sector": [s]}
        m = mesh_surfaces(build, size, curves=preds, save=save)
    else:
        nr, nt = _n(r_out - r_in, size), _n(angle * (r_in + r_out) / 2, size)
        Rr, T = np.meshgrid(np.linspace(r_in, r_out, nr + 1), np.linspace(theta0, th1, nt + 1))
        P = np.stack([Rr * np.cos(T), Rr * np.sin(T), np.zeros_like(T)], -1)
        m = _assemble([(P, ["sector"])], lambda X: {k: np.nonzero([p(x) for x in X])[0] for k, p in preds.items()},
                      r_out)
    for k in ("inner", "outer"):
        ids = m.edges[k]
        m.edges[k] = ids[np.argsort(_wrap(np.arctan2(m.X[ids, 1], m.X[ids, 0]) - theta0) % (2 * np.pi))]
    for k in ("start", "end"):
        ids = m.edges[k]
        m.edges[k] = ids[np.argsort(np.hypot(m.X[ids, 0], m.X[ids, 1]))]
    return m
