"""The obstacle extension point: rigid obstacles as signed distance functions (SDF) d(x, lam) with
gradient and Hessian, their rigid motions with the load factor, and the registry of obstacle kinds
(:data:`OBSTACLES`) that ``Problem.add_obstacle`` and scenario files (``[[obstacles]]``) read.

Convention.  d > 0 on the free side (where the shell may be), d = 0 on the obstacle's surface,
d < 0 inside it.  ``Obstacle.evaluate(x, lam)`` takes lab points x (k, 3) and returns

    d  (k,)        signed distance                          [length]
    n  (k, 3)      grad d (the outward unit normal)         [1]
    H  (k, 3, 3)   grad grad d (curvature of the level set) [1/length]

Motion.  An obstacle is described in lab coordinates at its *placement*; ``motion`` (a callable
lam -> 4x4 rigid transform T, default the identity) moves it rigidly: the obstacle at lam is T(lam)
applied to the placement, so with T = [[Q, t], [0, 1]] and y = Q^T (x - t)

    d(x, lam) = d0(y),   n = Q n0(y),   H = Q H0(y) Q^T.

:func:`translation`, :func:`rotation` and :func:`rigid_motion` build such callables: a pusher, a
rising floor or a closing jaw is a moving obstacle.  The load factor enters only through T.

A new kind is a subclass implementing ``local(y) -> (d, n, H)`` at the placement (and optionally
``local_surface(bounds)`` for pictures and ParaView) plus one ``register_obstacle(ObstacleKind(...))``
line: its ``params`` (``core_se3.model.Param``) are what a scenario file may give, validated with
no validator code.  The built-in kinds (``obstacle_kinds``): half_space, sphere, cylinder (infinite
or capped), box; :class:`~core_se3.model.obstacle_kinds.UserSDF` takes the user's functions.

Example
-------
>>> from core_se3.model import OBSTACLES, make_obstacle
>>> sorted(OBSTACLES)
['box', 'cylinder', 'half_space', 'sphere']
>>> floor = make_obstacle("half_space", point=(0.0, 0.0, -1.0), normal=(0.0, 0.0, 1.0))
>>> d, n, H = floor.evaluate([[0.3, 0.2, 0.5]])
>>> float(d[0]), n[0].tolist()
(1.5, [0.0, 0.0, 1.0])
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .. import lie
from ..errors import ContactError, did_you_mean, warn_angle
from ..registry import Kind, Registry

__all__ = ["Obstacle", "ObstacleKind", "OBSTACLES", "register_obstacle", "obstacle_kind",
           "make_obstacle", "rigid_transform", "translation", "rotation", "rigid_motion", "conjugated", "check_sdf"]


def contact_error(message, param=None):
    """A ContactError naming the offending key ``param`` (scenario files report it)."""
    exc = ContactError(message)
    exc.param = param
    return exc


def vector3(v, name):
    """A finite 3-vector, or a ContactError naming ``name``."""
    try:
        a = np.asarray(v, float)
    except (TypeError, ValueError):             # ('abc': a bare ValueError of NumPy before)
        a = np.full(1, np.nan)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise contact_error(f"{name} must be a finite 3-vector, got {v!r}", name.rsplit(" ", 1)[-1])
    return a


def unit3(v, name):
    """A non-zero finite 3-vector scaled to unit length, or a ContactError."""
    a = vector3(v, name)
    if not np.linalg.norm(a) > 0:
        raise contact_error(f"{name} must be non-zero", name.rsplit(" ", 1)[-1])
    return a / np.linalg.norm(a)


def positive(x, name):
    """A positive finite number, or a ContactError naming ``name``."""
    try:
        x = float(x)
    except (TypeError, ValueError):
        raise contact_error(f"{name} must be a number, got {x!r}", name.rsplit(" ", 1)[-1]) from None
    if not (np.isfinite(x) and x > 0):
        raise contact_error(f"{name} must be positive and finite, got {x}", name.rsplit(" ", 1)[-1])
    return x


# ----------------------------------------------------------------------------- motions
def rigid_transform(Q=None, t=(0.0, 0.0, 0.0)):
    """The 4x4 rigid transform [[Q, t], [0, 1]] (Q default the identity).

    Example
    -------
    >>> rigid_transform(t=(1.0, 2.0, 3.0))[:3, 3].tolist()
    [1.0, 2.0, 3.0]
    """
    T = np.eye(4)
    T[:3, :3] = np.eye(3) if Q is None else Q
    T[:3, 3] = t
    return T


def translation(vector, scale=None):
    """Motion lam -> translation by s(lam) * vector (s default lam) [length].

    Example
    -------
    >>> translation((0.0, 0.0, 2.0))(0.25)[:3, 3].tolist()
    [0.0, 0.0, 0.5]
    """
    v = vector3(vector, "translation vector")
    scale = _motion_scale(scale)
    return lambda lam: rigid_transform(None, scale(lam) * v)


def _motion_scale(scale):
    """The motion's programme s(lam) (None: s = lam), or a ContactError: a number was a bare
    TypeError ('float' object is not callable) at the first evaluation."""
    if scale is None:
        return lambda lam: lam
    if not callable(scale):
        raise contact_error(f"a motion's scale must be a function of the load factor (lam -> s; default s = lam), "
                            f"got {scale!r}", "scale")
    return scale


def rotation(axis, point, angle, scale=None):
    """Motion lam -> rotation by angle * s(lam) [rad] about ``axis`` through ``point``.

    Example
    -------
    >>> import numpy as np
    >>> T = rotation((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), np.pi)(1.0)
    >>> (np.round(T @ [0.0, 0.0, 0.0, 1.0], 12) + 0.0).tolist()           # the origin goes to x = 2
    [2.0, 0.0, 0.0, 1.0]
    """
    a = unit3(axis, "rotation axis")
    p = vector3(point, "rotation point")
    try:
        ok = not isinstance(angle, (bool, str, bytes)) and np.isfinite(float(angle))
    except (TypeError, ValueError):
        ok = False
    if not ok:                                  # ('abc': a bare ValueError of float() before)
        raise contact_error(f"a motion's angle must be a finite number [rad], got {angle!r}", "angle")
    angle = warn_angle(float(angle), "an obstacle motion's angle")
    scale = _motion_scale(scale)

    def T(lam):
        Q = lie.exp_so3(angle * scale(lam) * a)
        return rigid_transform(Q, p - Q @ p)
    return T


def rigid_motion(translate=None, axis=None, angle=0.0, point=(0.0, 0.0, 0.0), scale=None):
    """Motion lam -> the rotation by angle s(lam) about ``axis`` through ``point``, then the
    translation by s(lam) ``translate`` (either may be left out); None when neither is given.

    Example
    -------
    >>> T = rigid_motion(translate=(0.0, 0.0, 1.0), axis=(0.0, 1.0, 0.0), angle=0.0)(0.5)
    >>> T[:3, 3].tolist()
    [0.0, 0.0, 0.5]
    >>> rigid_motion() is None
    True
    >>> rigid_motion(translate=(0.0, 0.0, 1.0), angle=0.5)
    Traceback (most recent call last):
    ...
    core_se3.errors.ContactError: a motion's angle 0.5 needs its rotation axis (give axis = (ax, ay, az), and point on it)
    """
    if axis is None and angle != 0.0:
        raise contact_error(f"a motion's angle {angle:g} needs its rotation axis (give axis = (ax, ay, az), "
                            "and point on it)", "axis")
    parts = []
    if axis is not None and angle != 0.0:
        parts.append(rotation(axis, point, angle, scale))
    if translate is not None:
        parts.append(translation(translate, scale))
    if not parts:
        return None
    if len(parts) == 1:
        return parts[0]
    rot, tr = parts
    return lambda lam: tr(lam) @ rot(lam)


def conjugated(motion, c):
    """The motion ``motion`` seen in coordinates x' = x - c: lam -> S(-c) T(lam) S(c), S(v) the
    translation by v, i.e. [[Q, t + Q c - c], [0, 1]] (a translation keeps its t exactly: Q c - c
    = 0 for Q = I).

    Example
    -------
    >>> T = conjugated(rotation((0.0, 0.0, 1.0), (1e6 + 1.0, 0.0, 0.0), np.pi), (1e6, 0.0, 0.0))(1.0)
    >>> (np.round(T @ [0.0, 0.0, 0.0, 1.0], 9) + 0.0).tolist()     # about x' = 1: the origin goes to x' = 2
    [2.0, 0.0, 0.0, 1.0]
    """
    c = np.asarray(c, float)

    def T(lam):
        out = np.array(motion(lam), float)
        if out.shape == (4, 4):              # else left to Obstacle.transform's check, which names it
            out[:3, 3] += out[:3, :3] @ c - c
        return out
    return T


# ----------------------------------------------------------------------------- base class
class Obstacle:
    """Base class of rigid obstacles (module docstring for the conventions).

    Subclasses implement :meth:`local` (the SDF, its gradient and Hessian at the placement) and
    may implement :meth:`local_surface` (a quad mesh of the surface for pictures and ParaView).

    Parameters
    ----------
    motion : callable, optional
        lam -> (4, 4) proper rigid transform of the placement (default: fixed).
    name : str, optional
        For reports, output fields and the per-obstacle totals (default the kind).

    Attributes
    ----------
    approximate_hessian : bool
        True when H is a finite-difference approximation (the contact tangent then is too).
    thickness : float
        The inradius of the solid (the deepest a point can be inside it: a ball's radius, a box's
        smallest half size; inf for a half-space or a cavity) [length]: the continuous collision
        check over a step samples the faces at half of it (``model.contact_sweep``).

    Example
    -------
    >>> import numpy as np
    >>> class Slab(Obstacle):                 # the solid z < 0, written as a new kind
    ...     kind = "slab"
    ...     def local(self, y):
    ...         k = len(y)
    ...         return y[:, 2], np.tile([0.0, 0.0, 1.0], (k, 1)), np.zeros((k, 3, 3))
    >>> s = Slab(motion=translation((0.0, 0.0, 1.0)))
    >>> float(s.distance([[0.0, 0.0, 2.0]], lam=0.5)[0])
    1.5
    """

    kind = "obstacle"
    approximate_hessian = False
    thickness = np.inf
    flat = False
    position_attribute = None        # the attribute holding the placement's point (for relocated)

    def __init__(self, motion=None, name=None):
        if motion is not None and not callable(motion):
            raise contact_error("motion must be a callable lam -> 4x4 rigid transform", "motion")
        self.motion = motion
        self.name = name or self.kind

    def transform(self, lam):
        """T(lam) (4, 4); ContactError if the motion does not return a proper rigid transform."""
        if self.motion is None:
            return np.eye(4)
        T = np.asarray(self.motion(lam), float)
        ok = T.shape == (4, 4) and np.all(np.isfinite(T))
        Q = T[:3, :3] if ok else np.eye(3)
        if not ok or np.abs(Q.T @ Q - np.eye(3)).max() > 1e-10 or np.linalg.det(Q) < 0:
            raise contact_error(f"obstacle {self.name!r}: motion({lam}) is not a finite proper rigid "
                                "transform [[Q, t], [0, 1]]", "motion")
        return T

    def evaluate(self, x, lam=0.0):
        """(d (k,), n (k, 3), H (k, 3, 3)) at lab points x (k, 3) and load factor lam."""
        x = np.atleast_2d(np.asarray(x, float))
        T = self.transform(lam)
        Q, t = T[:3, :3], T[:3, 3]
        d, n, H = self.local((x - t) @ Q)                   # y = Q^T (x - t), row-wise
        if self.motion is None:
            return d, n, H
        return d, n @ Q.T, np.einsum("ij,kjl,ml->kim", Q, H, Q)

    def distance(self, x, lam=0.0):
        """d (k,) at lab points x (k, 3) [length] (:meth:`local_distance`: defined where the
        normal is not, e.g. at a ball's centre, which the sweep of a step may pass through)."""
        x = np.atleast_2d(np.asarray(x, float))
        T = self.transform(lam)
        return self.local_distance((x - T[:3, 3]) @ T[:3, :3])

    def relocated(self, c):
        """This obstacle in the coordinates x' = x - c of a part far from the origin (load
        stepping holds its iterate so, ``solvers.origin.relocation``): a copy with its placement
        point (the attribute ``position_attribute`` names) moved by -c and its motion
        :func:`conjugated`, so that the gaps of points near the part are taken without forming
        their absolute positions; None when the kind names no placement point (a ``UserSDF`` of
        absolute coordinates).

        Example
        -------
        >>> from core_se3.model import make_obstacle
        >>> ball = make_obstacle("sphere", centre=(1e6 + 0.5, 0.0, 0.0), radius=0.25)
        >>> near = ball.relocated((1e6, 0.0, 0.0))
        >>> near.centre.tolist(), float(near.distance([[0.5, 0.0, 0.3]])[0])
        ([0.5, 0.0, 0.0], 0.04999999999999999)
        """
        key = self.position_attribute
        if key is None:
            return None
        c = np.asarray(c, float)
        moved = copy.copy(self)
        setattr(moved, key, np.asarray(getattr(self, key), float) - c)
        if self.motion is not None:
            moved.motion = conjugated(self.motion, c)
        return moved

    def local(self, y):
        """(d, n, H) at points y (k, 3) in the placement's (lab) coordinates."""
        raise NotImplementedError(f"obstacle kind {self.kind!r} does not implement local(y)")

    def local_distance(self, y):
        """d (k,) at points y (k, 3) in the placement's coordinates: ``local(y)[0]``; a kind whose
        normal is undefined at points where d is not (a sphere's centre, a cylinder's axis)
        gives d there too (the crossing check of a step, ``model.contact_sweep``, samples the
        distance alone: a face point passing through a ball's centre stopped the run with "a
        point is at the centre of the sphere" instead of refusing the step)."""
        return self.local(y)[0]

    def local_surface(self, bounds):
        """(points (p, 3), quads (q, 4)) of the surface at the placement, covering ``bounds``
        ((2, 3) lower and upper corner of the region of interest, placement coordinates) where
        the surface is unbounded; None when the kind cannot draw itself."""
        return None

    def surface(self, lam=0.0, bounds=None):
        """(points (p, 3), quads (q, 4)) of the surface at lam in lab coordinates (for pictures
        and ParaView), or None.  ``bounds`` (2, 3): the lab region an unbounded surface (a plane,
        an infinite cylinder) is cut to (default the unit cube about the origin)."""
        b = np.array([[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]]) if bounds is None else np.asarray(bounds, float)
        T = self.transform(lam)
        Q, t = T[:3, :3], T[:3, 3]
        corners = np.array(np.meshgrid(*b.T)).reshape(3, -1).T          # (8, 3) lab corners
        loc = (corners - t) @ Q
        out = self.local_surface(np.array([loc.min(0), loc.max(0)]))
        if out is None:
            return None
        pts, quads = out
        return pts @ Q.T + t, np.asarray(quads, np.int64)


def check_sdf(obstacle, x, lam=0.0, h=1e-6):
    """Max errors of n against central differences of d and of H against those of n (relative
    to max(1, |H|)) at points x (k, 3): the test of a new obstacle kind.

    Example
    -------
    >>> from core_se3.model import make_obstacle
    >>> errs = check_sdf(make_obstacle("sphere", centre=(0.0, 0.0, 0.0), radius=1.0), [[0.3, 1.2, -0.4]])
    >>> [bool(e < 1e-7) for e in errs]
    [True, True]
    """
    x = np.atleast_2d(np.asarray(x, float))
    d, n, H = obstacle.evaluate(x, lam)
    nfd, Hfd = np.zeros_like(n), np.zeros_like(H)
    for j in range(3):
        dx = np.zeros(3)
        dx[j] = h
        dp, n_p, _ = obstacle.evaluate(x + dx, lam)
        dm, n_m, _ = obstacle.evaluate(x - dx, lam)
        nfd[:, j] = (dp - dm) / (2 * h)
        Hfd[:, :, j] = (n_p - n_m) / (2 * h)
    return float(np.abs(n - nfd).max()), float(np.abs(H - Hfd).max() / max(1.0, np.abs(H).max()))


# ----------------------------------------------------------------------------- registry
@dataclass(frozen=True)
class ObstacleKind(Kind):
    """A registered obstacle kind.

    build(values, motion, name) -> Obstacle makes it from the values of its ``params``
    (``core_se3.model.Param``: what a scenario file's ``[[obstacles]]`` entry may give, defaults
    filled in), its motion (None or lam -> T) and its name.

    Attributes
    ----------
    name : str
        The kind (``Problem.add_obstacle(name, ...)``, ``[[obstacles]] type = name``).
    params : tuple of Param
        Its keys; ``build``: as above; ``doc``: one line for the docs.

    Example
    -------
    >>> k = obstacle_kind("sphere")
    >>> [p.name for p in k.params], k.build(dict(centre=[0, 0, 0], radius=2.0, inside=False), None, "ball").radius
    (['centre', 'radius', 'inside'], 2.0)
    """
    name: str
    params: tuple
    build: Callable
    doc: str = ""
    extra: dict = field(default_factory=dict)


OBSTACLES = Registry("obstacle kind", ObstacleKind)


def register_obstacle(kind: ObstacleKind):
    """Add an obstacle kind to the registry (its name must be new); returns it.

    Example
    -------
    >>> register_obstacle(obstacle_kind("box"))
    Traceback (most recent call last):
    ...
    ValueError: obstacle kind 'box' is registered twice
    """
    if not isinstance(kind, ObstacleKind):
        raise TypeError("register_obstacle needs an ObstacleKind")
    return OBSTACLES.register(kind.name, kind)


def obstacle_kind(name) -> ObstacleKind:
    """The registered kind ``name``; an OptionError naming the closest kind otherwise.

    Example
    -------
    >>> obstacle_kind("sphre")
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: unknown obstacle kind 'sphre'; did you mean 'sphere'?; registered: box, cylinder, half_space, sphere
    """
    return OBSTACLES.lookup(name)


def make_obstacle(kind, motion=None, name=None, **values):
    """An obstacle of a registered kind from its parameters (ContactError for an unknown or
    missing key, naming it; the kind's classes check the values).

    Parameters
    ----------
    kind : str
        A key of :data:`OBSTACLES`.
    motion : callable, optional
        lam -> (4, 4) rigid transform (:func:`rigid_motion`).
    name : str, optional
        Default the kind.
    **values
        The kind's parameters (``obstacle_kind(kind).params``).

    Returns
    -------
    Obstacle

    Example
    -------
    >>> make_obstacle("cylinder", point=(0, 0, 0), axis=(0, 1, 0), radius=0.5, length=2.0).kind
    'capped cylinder'
    >>> make_obstacle("sphere", centre=(0, 0, 0), radius=-1.0)
    Traceback (most recent call last):
    ...
    core_se3.errors.ContactError: sphere radius must be positive and finite, got -1.0
    """
    try:
        k = OBSTACLES.lookup(kind)
    except Exception as exc:
        raise contact_error(str(exc), "type") from None
    names = [p.name for p in k.params]
    for key in values:
        if key not in names:
            raise contact_error(f"obstacle kind {kind!r} has no parameter {key!r}{did_you_mean(key, names)}; "
                                f"its parameters: {', '.join(names)}", key)
    for p in k.params:
        if p.required and p.name not in values:
            raise contact_error(f"obstacle kind {kind!r} needs {p.name!r}", p.name)
    full = {p.name: values.get(p.name, p.default) for p in k.params}
    return k.build(full, motion, name or kind)
