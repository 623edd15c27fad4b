"""The built-in obstacle kinds (registered: half_space, sphere, cylinder, box) and the user's SDF.

Smoothness.  The half-space, the sphere and the infinite cylinder are smooth away from their
centre or axis.  Boxes and capped cylinders have edges and corners: they are *rounded* by
default, i.e. the Minkowski sum of a smaller sharp body (half-sizes reduced by r) with a ball of
radius r.  Their SDF d = dist(y, inner body) - r is exactly the signed distance to the rounded
surface: C^1 outside the inner body (d > -r), with a Hessian bounded by 1/(d + r), so the
contact normal turns continuously round an edge and Newton sees no jump of it.  Inside the inner
body (a penetration deeper than r, which the augmented Lagrangian never reaches) d is the max of
the face distances.  ``rounding=0`` gives the sharp body: its Hessian (I - n n^T)/d is unbounded
at the edges.  Default r = 1 % of the smallest half-size (of min(radius, length/2)).

Example
-------
>>> import numpy as np
>>> b = Box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), rounding=0.1)
>>> d, n, H = b.evaluate([[2.0, 0.0, 0.0], [2.0, 2.0, 0.0]])
>>> np.round(d, 6).tolist(), np.round(n[1], 6).tolist()       # a face, then round an edge
([1.0, 1.455635], [0.707107, 0.707107, 0.0])
"""
from __future__ import annotations

import numpy as np

from .. import lie
from ..errors import warn_angle
from .base import Param
from .obstacles import Obstacle, ObstacleKind, contact_error, positive, register_obstacle, unit3, vector3

__all__ = ["HalfSpace", "Sphere", "Cylinder", "Box", "UserSDF"]


def rounded_box_sdf(q_abs, half, r):
    """SDF (k,), gradient (k, m) and Hessian (k, m, m) with respect to q_abs = |y| (k, m) of the
    box |y_i| <= half_i - r (m = 2 or 3 components) dilated by a ball of radius r."""
    q = q_abs - (half - r)
    pos = np.maximum(q, 0.0)
    D = np.linalg.norm(pos, axis=1)
    out = D > 0
    k, m = q.shape
    g, H, d = np.zeros((k, m)), np.zeros((k, m, m)), np.empty(k)
    Do = D[out]
    u = pos[out] / Do[:, None]
    g[out] = u
    act = (q[out] > 0).astype(float)
    H[out] = (act[:, :, None] * np.eye(m) - u[:, :, None] * u[:, None, :]) / Do[:, None, None]
    d[out] = Do - r
    j = np.argmax(q[~out], axis=1)
    d[~out] = q[~out][np.arange(len(j)), j] - r
    g[np.nonzero(~out)[0], j] = 1.0
    return d, g, H


def _grid(u, v, f):
    """Quad mesh of the parametric surface f(U, V) -> (..., 3) on the grid u x v."""
    U, V = np.meshgrid(u, v, indexing="ij")
    pts = f(U, V).reshape(-1, 3)
    nu, nv = len(u), len(v)
    i, j = np.meshgrid(np.arange(nu - 1), np.arange(nv - 1), indexing="ij")
    a = (i * nv + j).ravel()
    return pts, np.stack([a, a + nv, a + nv + 1, a + 1], 1)


def _frame(a):
    """Two unit vectors completing the unit vector a to a right-handed frame."""
    e = np.eye(3)[np.argmin(np.abs(a))]
    b = np.cross(a, e)
    b /= np.linalg.norm(b)
    return b, np.cross(a, b)


def _merge(*parts):
    pts, quads, off = [], [], 0
    for p, q in parts:
        pts.append(p)
        quads.append(q + off)
        off += len(p)
    return np.concatenate(pts), np.concatenate(quads)


class HalfSpace(Obstacle):
    """The solid {(x - point) . normal < 0}: a rigid plane, ``normal`` pointing to the free side.

    Parameters
    ----------
    point : (3,) array_like
        A point of the plane [length].
    normal : (3,) array_like
        Its normal toward the free side (normalised here).
    motion, name : optional
        As for :class:`~core_se3.model.obstacles.Obstacle`.

    Example
    -------
    >>> float(HalfSpace((0, 0, -0.5), (0, 0, 2.0)).distance([[1.0, 1.0, 0.0]])[0])
    0.5
    """

    kind = "half_space"
    flat = True                       # d is bilinear on a bilinear face: the nodes suffice
    position_attribute = "point"     # relocated() moves it

    def __init__(self, point, normal, motion=None, name=None):
        super().__init__(motion, name)
        self.point = vector3(point, "half-space point")
        self.normal = unit3(normal, "half-space normal")

    def local(self, y):
        k = len(y)
        return (y - self.point) @ self.normal, np.tile(self.normal, (k, 1)), np.zeros((k, 3, 3))

    def local_surface(self, bounds):
        c = 0.5 * (bounds[0] + bounds[1])
        c = c - ((c - self.point) @ self.normal) * self.normal
        half = 0.6 * max(float(np.linalg.norm(bounds[1] - bounds[0])), 1e-12)
        b1, b2 = _frame(self.normal)
        s = np.linspace(-half, half, 9)
        return _grid(s, s, lambda U, V: c + U[..., None] * b1 + V[..., None] * b2)


class Sphere(Obstacle):
    """A solid ball of ``radius`` about ``centre`` (``inside=True``: a spherical cavity, the
    shell inside it).

    Example
    -------
    >>> d, n, H = Sphere((0, 0, 0), 1.0).evaluate([[0.0, 0.0, 2.0]])
    >>> float(d[0]), n[0].tolist(), H[0].diagonal().tolist()
    (1.0, [0.0, 0.0, 1.0], [0.5, 0.5, 0.0])
    """

    kind = "sphere"
    position_attribute = "centre"     # relocated() moves it

    def __init__(self, centre, radius, inside=False, motion=None, name=None):
        super().__init__(motion, name)
        self.centre = vector3(centre, "sphere centre")
        self.radius = positive(radius, "sphere radius")
        self.sign = -1.0 if inside else 1.0
        self.thickness = np.inf if inside else self.radius

    def local(self, y):
        r = y - self.centre
        rho = np.linalg.norm(r, axis=1)
        if np.any(rho < 1e-12 * self.radius):
            raise contact_error(f"obstacle {self.name!r}: a point is at the centre of the sphere (normal undefined)")
        e = r / rho[:, None]
        H = (np.eye(3) - e[:, :, None] * e[:, None, :]) / rho[:, None, None]
        s = self.sign
        return s * (rho - self.radius), s * e, s * H

    def local_distance(self, y):
        return self.sign * (np.linalg.norm(y - self.centre, axis=1) - self.radius)

    def local_surface(self, bounds):
        th, ph = np.linspace(0.0, np.pi, 13), np.linspace(0.0, 2 * np.pi, 25)
        return _grid(th, ph, lambda T, P: self.centre + self.radius * np.stack(
            [np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1))


class Cylinder(Obstacle):
    """A solid circular cylinder of ``radius`` about the line through ``point`` along ``axis``.

    ``length=None``: infinite.  Otherwise capped by end planes at +-length/2 from ``point``,
    the rims rounded with ``rounding`` (module docstring).  ``inside=True``: a bore (infinite only).

    Example
    -------
    >>> c = Cylinder((0, 0, 0), (0, 1, 0), 0.5, length=2.0, rounding=0.0)
    >>> np.round(c.distance([[0.0, 0.0, 1.0], [0.0, 1.5, 0.0]]), 12).tolist()     # side, cap
    [0.5, 0.5]
    """

    kind = "cylinder"
    position_attribute = "point"     # relocated() moves it

    def __init__(self, point, axis, radius, length=None, rounding=None, inside=False, motion=None,
                 name=None):
        if length is not None:
            self.kind = "capped cylinder"
        super().__init__(motion, name)
        self.point = vector3(point, "cylinder point")
        self.axis = unit3(axis, "cylinder axis")
        self.radius = positive(radius, "cylinder radius")
        self.length = None if length is None else positive(length, "cylinder length")
        if inside and self.length is not None:
            raise contact_error("inside = true is for infinite cylinders (a bore)", "inside")
        self.sign = -1.0 if inside else 1.0
        self.rounding = None
        self.thickness = np.inf if inside else min(self.radius, np.inf if self.length is None else self.length / 2)
        if self.length is not None:
            m = min(self.radius, self.length / 2)
            self.rounding = 0.01 * m if rounding is None else float(rounding)
            if not 0 <= self.rounding < m:
                raise contact_error(f"cylinder rounding must lie in [0, min(radius, length/2)) = [0, {m:g}), "
                                    f"got {self.rounding}", "rounding")

    def local(self, y):
        a = self.axis
        r = y - self.point
        z = r @ a
        rad = r - z[:, None] * a
        rho = np.linalg.norm(rad, axis=1)
        on_axis = rho < 1e-12 * self.radius
        if np.any(on_axis):
            if self.length is None:
                raise contact_error(f"obstacle {self.name!r}: a point is on the cylinder axis (normal undefined)")
            rad[on_axis] = _frame(a)[0]               # beyond a cap: the radial direction drops out
            rho = np.where(on_axis, 1.0, rho)
        e = rad / rho[:, None]
        Hrho = (np.eye(3) - np.outer(a, a) - e[:, :, None] * e[:, None, :]) / rho[:, None, None]
        if self.length is None:
            s = self.sign
            return s * (rho - self.radius), s * e, s * Hrho
        rho = np.where(on_axis, 0.0, rho)
        sz = np.where(z >= 0, 1.0, -1.0)
        d, gq, Hq = rounded_box_sdf(np.stack([rho, np.abs(z)], 1), np.array([self.radius, self.length / 2]),
                                    self.rounding)
        if np.any(gq[on_axis, 0] != 0):
            raise contact_error(f"obstacle {self.name!r}: a point is on the cylinder axis (normal undefined)")
        J = np.stack([e, sz[:, None] * a], 1)                     # d(rho, |z|)/dy, (k, 2, 3)
        n = np.einsum("kc,kci->ki", gq, J)
        H = gq[:, 0, None, None] * Hrho + np.einsum("kci,kcd,kdj->kij", J, Hq, J)
        return d, n, H

    def local_distance(self, y):
        if self.length is not None:
            return self.local(y)[0]
        r = y - self.point
        return self.sign * (np.linalg.norm(r - np.outer(r @ self.axis, self.axis), axis=1) - self.radius)

    def local_surface(self, bounds):
        b1, b2 = _frame(self.axis)
        if self.length is None:
            zc = (0.5 * (bounds[0] + bounds[1]) - self.point) @ self.axis
            half = 0.6 * max(float(np.linalg.norm(bounds[1] - bounds[0])), 1e-12)
            zs = np.linspace(zc - half, zc + half, 9)
        else:
            zs = np.linspace(-self.length / 2, self.length / 2, 5)
        ph = np.linspace(0.0, 2 * np.pi, 25)

        def ring(Z, P, R):
            return (self.point + Z[..., None] * self.axis
                    + R[..., None] * (np.cos(P)[..., None] * b1 + np.sin(P)[..., None] * b2))
        side = _grid(zs, ph, lambda Z, P: ring(Z, P, self.radius + 0 * Z))
        if self.length is None:
            return side
        rs = np.linspace(0.0, self.radius, 4)
        caps = [_grid(rs, ph, lambda R, P, z=z: ring(z + 0 * R, P, R)) for z in (-self.length / 2, self.length / 2)]
        return _merge(side, *caps)


class Box(Obstacle):
    """A solid box of ``half_sizes`` about ``centre``, its axes the columns of ``rotation`` (a
    proper orthonormal 3x3 matrix, or a rotation vector [rad]), edges and corners rounded with
    ``rounding`` (module docstring).

    Example
    -------
    >>> b = Box((0, 0, 0), (1.0, 2.0, 3.0), rotation=(0.0, 0.0, np.pi / 2), rounding=0.0)
    >>> np.round(b.distance([[3.0, 0.0, 0.0]]), 12).tolist()             # the long side now along x
    [1.0]
    """

    kind = "box"
    position_attribute = "centre"     # relocated() moves it

    def __init__(self, centre, half_sizes, rotation=None, rounding=None, motion=None, name=None):
        super().__init__(motion, name)
        self.centre = vector3(centre, "box centre")
        half = np.asarray(half_sizes, float)
        if half.shape != (3,):
            raise contact_error(f"box half_sizes must be 3 numbers, got {half_sizes!r}", "half_sizes")
        self.half = np.array([positive(v, "box half_sizes") for v in half])
        Q = np.eye(3) if rotation is None else np.asarray(rotation, float)
        if Q.shape == (3,):
            Q = vector3(Q, "box rotation")
            warn_angle(np.linalg.norm(Q), "box rotation vector's angle", path=False)
            Q = lie.exp_so3(Q)
        if Q.shape != (3, 3) or not np.all(np.isfinite(Q)) or np.abs(Q.T @ Q - np.eye(3)).max() > 1e-10 \
                or np.linalg.det(Q) < 0:
            raise contact_error("box rotation must be a rotation vector or a proper orthonormal 3x3 matrix",
                                "rotation")
        self.Qb = Q
        self.rounding = 0.01 * self.half.min() if rounding is None else float(rounding)
        self.thickness = float(self.half.min())
        if not 0 <= self.rounding < self.half.min():
            raise contact_error(f"box rounding must lie in [0, smallest half-size) = [0, {self.half.min():g}), "
                                f"got {self.rounding}", "rounding")

    def local(self, y):
        z = (y - self.centre) @ self.Qb
        s = np.where(z >= 0, 1.0, -1.0)
        d, gq, Hq = rounded_box_sdf(np.abs(z), self.half, self.rounding)
        Hz = Hq * s[:, :, None] * s[:, None, :]
        return d, (gq * s) @ self.Qb.T, np.einsum("ij,kjl,ml->kim", self.Qb, Hz, self.Qb)

    def local_surface(self, bounds):
        faces = []
        t = np.linspace(-1.0, 1.0, 3)
        for k in range(3):
            i, j = [m for m in range(3) if m != k]
            for s in (-1.0, 1.0):
                def f(U, V, i=i, j=j, k=k, s=s):
                    p = np.zeros(U.shape + (3,))
                    p[..., i], p[..., j], p[..., k] = U * self.half[i], V * self.half[j], s * self.half[k]
                    return self.centre + p @ self.Qb.T
                faces.append(_grid(t, t, f))
        return _merge(*faces)


class UserSDF(Obstacle):
    """The user's signed distance function at the placement: ``d(y) -> (k,)``, ``grad(y) ->
    (k, 3)`` and optionally ``hessian(y) -> (k, 3, 3)`` (y: (k, 3) points).  Without ``hessian``
    it is taken by central differences of ``grad`` (step ``fd_step`` [length], default 1e-6 of
    the largest |y| of the points evaluated, 1e-6 when all are at the placement's origin: the
    points' own length unit; a fixed 1e-6 was 1e-6 of a 1 m obstacle but a step of 1e-3 of a
    1 mm one written in metres, its Hessian off by 4.5e-7 instead of 4.6e-10) and
    ``approximate_hessian`` is set.  ``surface(bounds) -> (points, quads)``
    optionally draws it; ``thickness``: the solid's inradius where it is thin (default inf: only
    the nodes are checked for crossings over a step, ``model.contact_sweep``).

    Example
    -------
    >>> wavy = UserSDF(lambda y: y[:, 2] - 0.1 * np.sin(y[:, 0]),
    ...                lambda y: np.stack([-0.1 * np.cos(y[:, 0]), 0 * y[:, 0], 1 + 0 * y[:, 0]], 1))
    >>> d, n, H = wavy.evaluate([[0.0, 0.0, 1.0]])
    >>> float(d[0]), wavy.approximate_hessian, round(float(H[0, 0, 0]), 6)
    (1.0, True, 0.0)
    """

    kind = "user"

    def __init__(self, d, grad, hessian=None, fd_step=None, surface=None, motion=None, name=None,
                 thickness=np.inf):
        super().__init__(motion, name)
        self.thickness = np.inf if thickness is None or np.isinf(thickness) else positive(thickness, "thickness")
        if not (callable(d) and callable(grad)) or (hessian is not None and not callable(hessian)):
            raise contact_error("UserSDF needs callables d(y), grad(y) and optionally hessian(y)")
        self.d, self.grad, self.hessian, self.draw = d, grad, hessian, surface
        self.fd_step = None if fd_step is None else positive(fd_step, "fd_step")
        self.approximate_hessian = hessian is None

    def local(self, y):
        k = len(y)
        d = np.asarray(self.d(y), float).reshape(k)
        n = np.asarray(self.grad(y), float).reshape(k, 3)
        if self.hessian is not None:
            H = np.asarray(self.hessian(y), float).reshape(k, 3, 3)
        else:
            h = self.fd_step or 1e-6 * (float(np.abs(y).max(initial=0.0)) or 1.0)
            e = h * np.eye(3)
            H = np.stack([(np.asarray(self.grad(y + e[j]), float) - np.asarray(self.grad(y - e[j]), float))
                          / (2 * h) for j in range(3)], -1)
            H = 0.5 * (H + np.swapaxes(H, 1, 2))
        if not (np.all(np.isfinite(d)) and np.all(np.isfinite(n)) and np.all(np.isfinite(H))):
            raise contact_error(f"obstacle {self.name!r}: the user SDF returned non-finite values")
        return d, n, H

    def local_surface(self, bounds):
        return None if self.draw is None else self.draw(bounds)


_PLACE = Param("point", "vector", doc="a point of the plane / axis [length]")
register_obstacle(ObstacleKind(
    "half_space", (_PLACE, Param("normal", "vector", nonzero=True, doc="normal toward the free side")),
    lambda v, motion, name: HalfSpace(v["point"], v["normal"], motion, name),
    doc="the solid behind a plane (a floor, a wall, a table)"))
register_obstacle(ObstacleKind(
    "sphere", (Param("centre", "vector", doc="[length]"), Param("radius", "number", lo=0.0, lo_open=True),
               Param("inside", "bool", default=False, doc="a spherical cavity")),
    lambda v, motion, name: Sphere(v["centre"], v["radius"], v["inside"], motion, name),
    doc="a solid ball (or, inside = true, a cavity)"))
register_obstacle(ObstacleKind(
    "cylinder", (_PLACE, Param("axis", "vector", nonzero=True), Param("radius", "number", lo=0.0, lo_open=True),
                 Param("length", "number", default=None, lo=0.0, lo_open=True, doc="capped; default infinite"),
                 Param("rounding", "number", default=None, lo=0.0, doc="rim radius; default 1 %"),
                 Param("inside", "bool", default=False, doc="a bore (infinite only)")),
    lambda v, motion, name: Cylinder(v["point"], v["axis"], v["radius"], v["length"], v["rounding"],
                                     v["inside"], motion, name),
    doc="a solid circular cylinder, infinite or capped"))
register_obstacle(ObstacleKind(
    "box", (Param("centre", "vector"), Param("half_sizes", "vector", doc="[length], each > 0", frame=None),
            Param("rotation", "vector", default=[0.0, 0.0, 0.0], doc="rotation vector of its axes [rad]",
                  frame="rotation"),
            Param("rounding", "number", default=None, lo=0.0, doc="edge radius; default 1 %")),
    lambda v, motion, name: Box(v["centre"], v["half_sizes"], v["rotation"], v["rounding"], motion, name),
    doc="a solid box with rounded edges"))
