"""Structured shell meshes with named edges (node sets) and regions (element sets).

Every generator returns a :class:`~core_se3.mesh.Mesh` whose nodal frames have d3 = the surface
normal.  Parametrised patches (``rectangle``, ``cylinder_arch``, ``cylinder_panel``, ``annulus``,
``hemisphere_quarter``) name their four boundary lines ``x0``, ``x1`` (first parameter at its
start and end) and ``y0``, ``y1`` (second parameter), and take ``grade``: the elements along
named lines made narrower, their widths growing geometrically away from them (:func:`spacing`),
to resolve the layers in which a thin shell bends along a free or supported edge
(docs/ELEMENTS.md, "The coarse thin roof"); ``cross`` (a four-arm gripper) names its palm, arms
and arm tips.
"""
from __future__ import annotations

import numbers
import warnings

import numpy as np

from ..errors import MeshError, MeshWarning
from .core import Mesh, frames_from

__all__ = ["rectangle", "cylinder_arch", "cylinder_panel", "annulus", "hemisphere_quarter", "cross", "spacing",
           "GRADE_EDGES", "MAX_GROWTH"]

#: the growth ratio of a graded side above which ``spacing`` warns (errors.MeshWarning)
MAX_GROWTH = 2.0

#: the lines a parametric patch's ``grade`` may name: (parameter axis, end)
GRADE_EDGES = {"x0": (0, 0), "x1": (0, 1), "y0": (1, 0), "y1": (1, 1)}


def _counts(nx, ny):
    """(nx, ny) as ints, or a MeshError: whole numbers >= 1."""
    whole = all(isinstance(k, numbers.Real) and not isinstance(k, bool) and float(k).is_integer()
                for k in (nx, ny))
    if not whole:
        raise MeshError(f"element counts must be whole numbers, got {nx!r} x {ny!r}")
    if nx < 1 or ny < 1:
        raise MeshError(f"mesh needs at least 1x1 elements, got {nx}x{ny}")
    return int(nx), int(ny)


def spacing(lo, hi, n, first=None, last=None):
    """n + 1 nodes from lo to hi: uniform, or graded toward either end.

    With ``first`` (``last``) the first (last) element spans that fraction of hi - lo and the
    widths grow geometrically away from that end, w_i = first q^i; with both, the smaller of the
    two progressions, w_i = min(first q^i, last q^(n-1-i)), and one ratio q > 0 makes the widths
    add up to hi - lo (found by bisection on log q: the sum grows with q).

    Parameters
    ----------
    lo, hi : float
        The ends (any order of magnitude; hi != lo).
    n : int
        Elements, >= 1.
    first, last : float, optional
        Fractions in (0, 1) of the whole span.

    Returns
    -------
    ndarray (n + 1,)
        Nodes, from lo to hi.

    Raises
    ------
    MeshError
        A fraction outside (0, 1), or no ratio q in [1e-6, 1e6] meets them (one element, two
        elements graded from both ends, or fractions that add to 1 or more), or with both ends
        graded one end's progression does not reach that end (its element would get another
        width than the fraction given).

    Warns
    -----
    MeshWarning
        Neighbouring widths differ by more than ``MAX_GROWTH`` (2).

    Example
    -------
    >>> x = spacing(0.0, 1.0, 4, last=0.1)
    >>> round(float(x[-1] - x[-2]), 12), bool(np.all(np.diff(np.diff(x)) < 0))
    (0.1, True)
    """
    given = {k: v for k, v in (("first", first), ("last", last)) if v is not None}
    for k, v in given.items():
        if isinstance(v, bool) or not (isinstance(v, numbers.Real) and 0.0 < v < 1.0):
            raise MeshError(f"grading: the {k} element's fraction of its side must lie in (0, 1), got {v!r}")
    if not given:
        return np.linspace(lo, hi, n + 1)
    i = np.arange(n)

    def widths(logq):
        from_first = first * np.exp(logq * i) if first is not None else np.inf
        from_last = last * np.exp(logq * (n - 1 - i)) if last is not None else np.inf
        return np.minimum(from_first, from_last)
    a, b = np.log(1e-6), np.log(1e6)
    if not widths(a).sum() <= 1.0 <= widths(b).sum():
        raise MeshError(f"grading: no geometric growth of {n} element(s) meets first = {first}, last = {last} "
                        f"(fractions of the side): give more elements or smaller fractions")
    for _ in range(200):                       # bisection on log q to round-off
        c = 0.5 * (a + b)
        a, b = (c, b) if widths(c).sum() < 1.0 else (a, c)
    w = widths(0.5 * (a + b))
    # with both ends graded the widths are the smaller of the two progressions: where one end's
    # progression stays below the other's even at that end (q < 1: fractions above the uniform
    # width 1/n; or one fraction far larger than the other), that end's element is the other
    # progression's and the fraction asked for would be silently replaced (first = last = 0.3 of
    # 8 elements gave end elements of 0.096; first 0.05, last 0.5 of 6 gave a last one of 0.36)
    for k, v, got in (("first", first, w[0]), ("last", last, w[-1])):
        if v is not None and abs(got / w.sum() - v) > 1e-9 * v:
            raise MeshError(f"grading: no geometric growth from both ends of {n} element(s) gives the {k} element "
                            f"the fraction {v} asked for (it would get {got / w.sum():.3g}; first = {first}, "
                            f"last = {last}): grade one end only, or give fractions below the uniform width "
                            f"1/{n} = {1.0 / n:.3g} whose progressions meet inside the side")
    growth = float(np.max(np.maximum(w[1:] / w[:-1], w[:-1] / w[1:]), initial=1.0))
    if growth > MAX_GROWTH:
        warnings.warn(MeshWarning(
            f"grading: neighbouring elements differ {growth:.3g}-fold in width ({n} element(s), first = {first}, "
            f"last = {last}); above about {MAX_GROWTH:g} a coarse element next to a fine one cannot carry what the fine "
            f"one resolves (the thin roof graded toward its free edge: erratic beyond 2, right up to 1.7). Give the "
            f"side more elements or a larger fraction."), stacklevel=3)
    x = lo + (hi - lo) * np.concatenate([[0.0], np.cumsum(w / w.sum())])
    x[-1] = hi
    return x


def _axes(grade, a, b, na, nb):
    """The two parameter grids of a patch on [a0, a1] x [b0, b1] with ``grade`` ({edge: fraction},
    :data:`GRADE_EDGES`; None values ignored)."""
    grade = {k: v for k, v in (grade or {}).items() if v is not None}
    unknown = sorted(set(grade) - set(GRADE_EDGES))
    if unknown:
        raise MeshError(f"grade: unknown edge(s) {unknown}; a parametric patch grades toward "
                        f"{', '.join(GRADE_EDGES)}")
    ends = [[None, None], [None, None]]
    for name, v in grade.items():
        axis, end = GRADE_EDGES[name]
        ends[axis][end] = v
    return (spacing(a[0], a[1], na, *ends[0]), spacing(b[0], b[1], nb, *ends[1]))


def _structured(nx, ny):
    nx, ny = _counts(nx, ny)
    ids = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)   # ids[j, i]
    quads = np.stack([ids[:-1, :-1], ids[:-1, 1:], ids[1:, 1:], ids[1:, :-1]], -1).reshape(-1, 4)
    edges = {"x0": ids[:, 0], "x1": ids[:, -1], "y0": ids[0, :], "y1": ids[-1, :]}
    return ids, quads, edges


def _patch(a, b, surface):
    """A structured patch on the parameter grid a (nx + 1,) x b (ny + 1,): surface(A, B) of the
    flattened grid (A varies fastest) gives the positions X and the directors d1, d3."""
    nx, ny = len(a) - 1, len(b) - 1
    ids, quads, edges = _structured(nx, ny)
    AA, BB = np.meshgrid(a, b)
    X, d1, d3 = surface(AA.ravel(), BB.ravel())
    return Mesh(frames_from(X, d1, d3), quads, edges, shape=(nx, ny))


def _flat(X):
    n = X.shape[0]
    return X, np.tile([1.0, 0, 0], (n, 1)), np.tile([0, 0, 1.0], (n, 1))


def _one_turn(generator, what, angle):
    """A MeshError unless 0 < angle <= 2 pi: the angles of the generators are radians, and an
    angle of more than a turn (180 meant as degrees: 28.6 turns) wound the surface over itself
    -- a mesh that solves, its elements overlapping in space."""
    if not 0 < angle <= 2 * np.pi + 1e-12:
        hint = f" ({np.radians(angle):.6g} if {angle:g} is in degrees)" if 30 <= angle <= 360 else ""
        raise MeshError(f"{generator}: {what} must be in (0, 2 pi] [rad], got {angle:g}{hint}: a larger angle "
                        "winds the surface over itself")


def rectangle(L, width, nx, ny, x0=0.0, grade=None):
    """Flat strip [x0, x0+L] x [-width/2, width/2] in the x-y plane, frames = identity.

    Parameters
    ----------
    L, width : float
        Length along x and width along y [length], > 0.
    nx, ny : int
        Elements along x and along y, >= 1.
    x0 : float, optional
        x of the edge ``x0`` [length].
    grade : dict, optional
        {edge: fraction}: the elements along that edge (``x0``, ``x1``, ``y0``, ``y1``) span that
        fraction of the side across it, the others growing geometrically (:func:`spacing`).

    Returns
    -------
    Mesh
        (nx + 1)(ny + 1) nodes, edges ``x0``, ``x1`` (ordered along y) and ``y0``, ``y1``
        (ordered along x); ``shape`` = (nx, ny).

    Example
    -------
    >>> m = rectangle(10.0, 1.0, 16, 1)
    >>> m.n_elements, m.X[m.node_set("x1")][:, 0].tolist()
    (16, [10.0, 10.0])
    """
    if not (L > 0 and width > 0):
        raise MeshError(f"rectangle needs L > 0 and width > 0, got {L}, {width}")
    nx, ny = _counts(nx, ny)
    xs, ys = _axes(grade, (0.0, L), (-width / 2, width / 2), nx, ny)
    return _patch(x0 + xs, ys, lambda X, Y: _flat(np.stack([X, Y, np.zeros(X.size)], -1)))


def cylinder_arch(R, angle, width, nx, ny, grade=None):
    """Cylindrical panel of radius R bent in the x-z plane over ``angle`` [rad].

    The arc starts at the origin with tangent +x; the centre of curvature is (0, 0, R); the
    width runs along y.  Frames: d1 = tangent, d2 = +y, d3 = d1 x d2 (toward the centre).

    Parameters
    ----------
    R : float
        Radius of the mid-surface [length].
    angle : float
        Opening angle of the arc [rad] (pi: a half circle).
    width : float
        Width along y [length].
    nx, ny : int
        Elements along the arc and across the width.
    grade : dict, optional
        {edge: fraction}: the elements along that edge (``x0``, ``x1``, ``y0``, ``y1``) span that
        fraction of the side across it, the others growing geometrically (:func:`spacing`).

    Returns
    -------
    Mesh
        Edges ``x0`` (the start of the arc), ``x1`` (its end), ``y0``, ``y1`` (the sides).

    Example
    -------
    >>> import numpy as np
    >>> m = cylinder_arch(1.0, np.pi, 0.1, 8, 1)
    >>> np.allclose(m.X[m.node_set("x1")][:, [0, 2]], [[0.0, 2.0], [0.0, 2.0]])
    True
    """
    if not (R > 0 and angle > 0 and width > 0):
        raise MeshError("cylinder_arch needs R, angle, width > 0")
    _one_turn("cylinder_arch", "angle", angle)
    nx, ny = _counts(nx, ny)
    return _patch(*_axes(grade, (0.0, angle), (-width / 2, width / 2), nx, ny),
                  lambda S, Y: (np.stack([R * np.sin(S), Y, R * (1 - np.cos(S))], -1),
                                np.stack([np.cos(S), 0 * S, np.sin(S)], -1),
                                np.stack([-np.sin(S), 0 * S, np.cos(S)], -1)))


def cylinder_panel(R, length, theta0, theta1, nt, nl, grade=None):
    """Cylindrical panel phi0 = (R sin t, s, R cos t), t in [theta0, theta1], s in [0, length].

    The axis is the global y axis.  xi1 = t (edges 'x0' at theta0, 'x1' at theta1), xi2 = s
    (edges 'y0' at s = 0, 'y1' at s = length).  Frames: d1 circumferential, d2 = +y,
    d3 = d1 x d2 = the outward normal (sin t, 0, cos t).  With theta in [-pi/2, pi/2] this is
    the semi-cylinder of Sze et al. 2004, s3.7.

    Parameters
    ----------
    R, length : float
        Radius and axial length [length].
    theta0, theta1 : float
        Angular range [rad], theta1 > theta0 (measured from +z toward +x).
    nt, nl : int
        Elements around and along the axis.
    grade : dict, optional
        {edge: fraction}: the elements along that edge (``x0``, ``x1``, ``y0``, ``y1``) span that
        fraction of the side across it, the others growing geometrically (:func:`spacing`).

    Returns
    -------
    Mesh

    Example
    -------
    >>> import numpy as np
    >>> m = cylinder_panel(1.0, 2.0, -np.pi / 2, np.pi / 2, 4, 2)
    >>> np.allclose(np.linalg.norm(m.X[:, [0, 2]], axis=1), 1.0)
    True
    """
    if not (R > 0 and length > 0 and theta1 > theta0):
        raise MeshError("cylinder_panel needs R > 0, length > 0 and theta1 > theta0")
    _one_turn("cylinder_panel", "theta1 - theta0", theta1 - theta0)
    nt, nl = _counts(nt, nl)
    return _patch(*_axes(grade, (theta0, theta1), (0.0, length), nt, nl),
                  lambda T, S: (np.stack([R * np.sin(T), S, R * np.cos(T)], -1),
                                np.stack([np.cos(T), 0 * T, -np.sin(T)], -1),
                                np.stack([np.sin(T), 0 * T, np.cos(T)], -1)))


def annulus(r_in, r_out, angle, nr, nt, grade=None):
    """Annular sector in the x-y plane, radius r_in..r_out, polar angle 0..angle (2 pi: slit).

    Parameter xi1 runs along the radius, xi2 around; edges 'x0' (inner), 'x1' (outer),
    'y0' (angle 0), 'y1' (angle ``angle``).  Frames: d1 radial, d3 = +z.

    Parameters
    ----------
    r_in, r_out : float
        Inner and outer radius [length], 0 < r_in < r_out.
    angle : float
        Polar angle of the sector [rad], in (0, 2 pi]; at 2 pi the edges y0 and y1 coincide in
        space but are not joined (a slit ring, Sze et al. 2004).
    nr, nt : int
        Elements along the radius and around.
    grade : dict, optional
        {edge: fraction}: the elements along that edge (``x0``, ``x1``, ``y0``, ``y1``) span that
        fraction of the side across it, the others growing geometrically (:func:`spacing`).

    Returns
    -------
    Mesh

    Example
    -------
    >>> import numpy as np
    >>> m = annulus(6.0, 10.0, 2 * np.pi, 2, 8)
    >>> len(m.node_set("y0")), m.n_elements
    (3, 16)
    """
    if not 0 < r_in < r_out:
        raise MeshError(f"annulus needs 0 < r_in < r_out, got {r_in}, {r_out}")
    _one_turn("annulus", "angle", angle)
    nr, nt = _counts(nr, nt)
    r, t = _axes(grade, (r_in, r_out), (0.0, angle), nr, nt)
    if np.diff(t).max() >= np.pi * (1 - 1e-12):     # its four corners on one line through the centre
        raise MeshError(f"annulus: nt = {nt} element(s) around {angle:g} rad span {np.degrees(np.diff(t).max()):.4g} "
                        f"degrees each, too few: an element of half a turn or more has its corners on one line "
                        f"(zero area); give at least nt = {int(angle // np.pi) + 1} elements around (the second "
                        "count of a mesh NRxNT)")
    return _patch(r, t, lambda Rr, T: (np.stack([Rr * np.cos(T), Rr * np.sin(T), 0 * T], -1),
                                 np.stack([np.cos(T), np.sin(T), 0 * T], -1),
                                 np.tile([0, 0, 1.0], (T.size, 1))))


def hemisphere_quarter(R, hole_deg, nt, nf, grade=None):
    """Quarter of a hemisphere of radius R with a polar hole of half-angle ``hole_deg`` [deg].

    phi0 = R (sin t cos f, sin t sin f, cos t), polar angle t in [t_hole, pi/2], azimuth f in
    [0, pi/2].  xi1 = t (edges 'x0' = the hole, 'x1' = the equator), xi2 = f ('y0' on the plane
    y = 0, 'y1' on the plane x = 0).  Frames: d1 = e_t (meridian, toward the equator),
    d2 = e_f, d3 = d1 x d2 = the outward normal e_r (Sze et al. 2004, s3.4).

    Parameters
    ----------
    R : float
        Radius [length].
    hole_deg : float
        Half-angle of the polar hole [deg], in (0, 90).
    nt, nf : int
        Elements along the meridian and around the quarter.
    grade : dict, optional
        {edge: fraction}: the elements along that edge (``x0``, ``x1``, ``y0``, ``y1``) span that
        fraction of the side across it, the others growing geometrically (:func:`spacing`).

    Returns
    -------
    Mesh

    Example
    -------
    >>> import numpy as np
    >>> m = hemisphere_quarter(10.0, 18.0, 4, 4)
    >>> np.allclose(np.linalg.norm(m.X, axis=1), 10.0)
    True
    """
    if not (R > 0 and 0 < hole_deg < 90):
        raise MeshError("hemisphere_quarter needs R > 0 and 0 < hole_deg < 90")
    nt, nf = _counts(nt, nf)

    def surface(T, F):
        X = R * np.stack([np.sin(T) * np.cos(F), np.sin(T) * np.sin(F), np.cos(T)], -1)
        return X, np.stack([np.cos(T) * np.cos(F), np.cos(T) * np.sin(F), -np.sin(T)], -1), X / R
    return _patch(*_axes(grade, (np.radians(hole_deg), np.pi / 2), (0.0, np.pi / 2), nt, nf), surface)


ARMS = {"px": (0, 1.0), "mx": (0, -1.0), "py": (1, 1.0), "my": (1, -1.0)}


def cross(arm_length, arm_width, n_along, n_across):
    """Flat cross-shaped (four-arm) gripper in the x-y plane: a square palm of side ``arm_width``
    at the origin and four arms of length ``arm_length`` along +x, -x, +y, -y (normal +z).

    Regions: ``palm``, ``finger_px``, ``finger_mx``, ``finger_py``, ``finger_my``.  Node sets:
    ``palm`` (the palm's nodes), ``tips`` (all arm-tip nodes) and the ordered tip lines
    ``tip_px``, ``tip_mx``, ``tip_py``, ``tip_my``.

    Parameters
    ----------
    arm_length, arm_width : float
        Length of each arm beyond the palm and width of the arms (= side of the palm) [length].
    n_along, n_across : int
        Elements along an arm and across its width.

    Returns
    -------
    Mesh
        Unstructured (``shape`` None): 4 n_along n_across + n_across^2 quads.

    Example
    -------
    >>> m = cross(20.0, 6.0, 10, 3)
    >>> m.n_elements, len(m.regions["finger_px"]), len(m.node_set("tip_px"))
    (129, 30, 4)
    """
    if not (arm_length > 0 and arm_width > 0) or n_along < 1 or n_across < 1:
        raise MeshError("cross needs arm_length, arm_width > 0 and at least one element each way")
    w, a = arm_width / 2, arm_width / 2 + arm_length
    t = np.concatenate([np.linspace(-a, -w, n_along + 1)[:-1], np.linspace(-w, w, n_across + 1),
                        np.linspace(w, a, n_along + 1)[1:]])
    k = len(t)
    ids = np.arange(k * k).reshape(k, k)                           # ids[j, i]: y_j, x_i
    quads = np.stack([ids[:-1, :-1], ids[:-1, 1:], ids[1:, 1:], ids[1:, :-1]], -1).reshape(-1, 4)
    XX, YY = np.meshgrid(t, t)
    X = np.stack([XX.ravel(), YY.ravel(), np.zeros(XX.size)], -1)
    c = X[quads].mean(1)
    keep = (np.abs(c[:, 0]) < w) | (np.abs(c[:, 1]) < w)
    quads = quads[keep]
    used = np.unique(quads)
    new = -np.ones(k * k, np.int64)
    new[used] = np.arange(len(used))
    X = X[used]
    quads = new[quads]
    n = len(X)
    g0 = frames_from(X, np.tile([1.0, 0, 0], (n, 1)), np.tile([0, 0, 1.0], (n, 1)))
    tol = 1e-9 * a
    edges = {"palm": np.nonzero((np.abs(X[:, 0]) <= w + tol) & (np.abs(X[:, 1]) <= w + tol))[0],
             "tips": np.nonzero(np.max(np.abs(X[:, :2]), axis=1) >= a - tol)[0]}
    c = X[quads].mean(1)
    regions = {"palm": np.nonzero((np.abs(c[:, 0]) < w) & (np.abs(c[:, 1]) < w))[0]}
    for name, (axis, sign) in ARMS.items():
        on = np.nonzero(np.abs(X[:, axis] - sign * a) < tol)[0]
        edges[f"tip_{name}"] = on[np.argsort(X[on, 1 - axis])]
        regions[f"finger_{name}"] = np.nonzero(sign * c[:, axis] > w)[0]
    return Mesh(g0, quads, edges, regions=regions)
