"""Applied magnetic fields B^a(x, lam) [T] with their first and second gradients.

A field gives, at lab points x (k, 3) and load factor lam,

    value     B_i                    (k, 3)        [T]
    gradient  G_ij = dB_i / dx_j     (k, 3, 3)     [T / length]
    hessian   H_ijl = d2 B_i / dx_j dx_l  (k, 3, 3, 3)  [T / length^2]

The magnetic body force (B^r . grad) B^a = G B^r and its tangent (through H) need the
gradients; a ``uniform`` field skips them.  In the region of the body the applied field must be
curl- and divergence-free (a field of magnets and coils outside the body): G symmetric and
traceless.  The built-in sources are checked (``GradientField`` at construction; the dipole
is so by construction, asserted by the tests); for a ``UserField`` this is the user's
responsibility, and ``check_field`` tests it at sample points.

Load-factor programme: each field is multiplied by ``scale(lam)`` (default ``lam``: the field
ramps up with the load factor); a ``UniformField`` may also turn, its direction following
``direction(lam)`` (e.g. a field rotating in a plane as the load factor grows).
"""
from __future__ import annotations

from dataclasses import dataclass
from math import pi
from typing import Callable

import numpy as np

from .. import lie
from ..errors import LoadError, warn_angle
from ..registry import Kind, Registry
from .base import Param, finite_vector

__all__ = ["MU0", "B_MAX", "tesla_units", "Field", "UniformField", "GradientField", "DipoleField", "UserField",
           "Superposition", "rotating_direction", "check_field", "field_vanishes", "field_defect", "FIELD_DEFECT_TOL", "FieldKind", "FIELDS",
           "register_field", "field_kind"]

MU0 = 4e-7 * pi
"""Vacuum permeability [N/A^2] for SI stresses (Pa).  For N-mm-MPa models a magnet's mu0
(``Problem.add_magnetic``: loads h B^r x B^a / mu0 in N/mm) is MU0 * 1e6, but a
``DipoleField``'s (B = mu0 m / (4 pi r^3) in T with m in A mm^2, r in mm) is MU0 * 1e3, as a
scenario's units = "N-mm-MPa" sets them."""

B_MAX = 2.0
"""The largest plausible flux density [T]: NdFeB magnets reach about 1.4 T (a residual B^r),
lab electromagnets about 2 T (an applied B^a).  A B^r or B^a above it was most likely given in
mT (or a magnetisation M in A/m as B^r): a scenario's plausibility check and
``Problem.add_magnetic`` (with a mu0 of tesla units, :func:`tesla_units`) say so."""


def tesla_units(mu0):
    """Is ``mu0`` the vacuum permeability of a unit system whose flux density is in tesla, i.e.
    MU0 times a power of ten (SI: MU0; N-mm-MPa: MU0 * 1e6)?  Own consistent units (mu0 = 1,
    say) are not checked against B_MAX.

    Example
    -------
    >>> tesla_units(MU0), tesla_units(MU0 * 1e6), tesla_units(1.0)
    (True, True, False)
    """
    k = np.log10(float(mu0) / MU0)
    return bool(np.isfinite(k) and abs(k - round(k)) < 1e-9)




def _scale_fn(scale):
    if scale is None:
        return lambda lam: lam
    if not callable(scale):
        raise LoadError(f"scale must be a function of the load factor, got {scale!r}")
    return scale


def _finite_scale(s, lam):
    s = float(s)
    if not np.isfinite(s):
        raise LoadError(f"field scale at load factor {lam} is not finite ({s})")
    return s


class Field:
    """Base class of applied fields: subclasses implement ``_value``, ``_gradient`` and
    ``_hessian`` at scale 1 (x (k, 3) -> (k, 3), (k, 3, 3), (k, 3, 3, 3)); ``value``,
    ``gradient`` and ``hessian`` multiply them by ``scale(lam)``.  ``uniform = True`` skips the
    gradients (no magnetic body force); ``approximate_hessian = True`` flags a finite-difference
    Hessian (the tangent of the body force is then approximate).

    Parameters
    ----------
    scale : callable, optional
        The load-factor programme s(lam) (default s = lam); a non-finite value raises LoadError.

    Example
    -------
    >>> import numpy as np
    >>> class Ramp(Field):                      # B = (0, 0, b x) is not curl-free: test only
    ...     def _value(self, x, lam): return np.c_[0 * x[:, :2], x[:, 0]]
    ...     def _gradient(self, x, lam): return np.broadcast_to([[0, 0, 0], [0, 0, 0], [1.0, 0, 0]], x.shape + (3,))
    ...     def _hessian(self, x, lam): return np.zeros(x.shape + (3, 3))
    >>> Ramp().value(np.array([[2.0, 0, 0]]), 0.5).tolist()
    [[0.0, 0.0, 1.0]]
    """

    uniform = False
    approximate_hessian = False

    def __init__(self, scale=None):
        self.scale = _scale_fn(scale)

    def scale_at(self, lam):
        """The finite scale factor s(lam) (LoadError when it is not finite)."""
        return _finite_scale(self.scale(lam), lam)

    def value(self, x, lam):
        return _finite_scale(self.scale(lam), lam) * self._value(np.asarray(x, float), lam)

    def unscaled(self, x, lam):
        """The field at scale 1 (value = scale(lam) * unscaled): its direction and profile,
        which turn with lam only for a rotating field (a scale through zero reverses the field
        without turning it)."""
        return self._value(np.asarray(x, float), lam)

    def gradient(self, x, lam):
        x = np.asarray(x, float)
        if self.uniform:
            return np.zeros(x.shape[:-1] + (3, 3))
        return _finite_scale(self.scale(lam), lam) * self._gradient(x, lam)

    def hessian(self, x, lam):
        x = np.asarray(x, float)
        if self.uniform:
            return np.zeros(x.shape[:-1] + (3, 3, 3))
        return _finite_scale(self.scale(lam), lam) * self._hessian(x, lam)


class UniformField(Field):
    """B^a = scale(lam) * B, or scale(lam) * |B| * direction(lam) if ``direction`` is given.

    Parameters: B (3,) flux density [T] at scale 1; scale s(lam) (default lam); direction
    lam -> (3,) (normalised, e.g. :func:`rotating_direction`): then only |B| is used.

    Example
    -------
    >>> import numpy as np
    >>> f = UniformField((0.0, 0.0, 0.01))
    >>> f.value(np.zeros((2, 3)), 0.5).tolist(), f.uniform, float(np.abs(f.gradient(np.zeros((2, 3)), 0.5)).max())
    ([[0.0, 0.0, 0.005], [0.0, 0.0, 0.005]], True, 0.0)
    """

    uniform = True

    def __init__(self, B, scale=None, direction=None):
        super().__init__(scale)
        self.B = finite_vector(B, "uniform field B")
        if direction is not None and not callable(direction):
            raise LoadError("direction must be a function of the load factor returning a unit 3-vector")
        self.direction = direction

    def _value(self, x, lam):
        if self.direction is None:
            b = self.B
        else:
            d = finite_vector(self.direction(lam), f"field direction at load factor {lam}")
            nd = np.linalg.norm(d)
            if nd == 0:
                raise LoadError(f"field direction at load factor {lam} is the zero vector")
            b = np.linalg.norm(self.B) * d / nd
        return np.broadcast_to(b, x.shape[:-1] + (3,)).copy()


def rotating_direction(axis, start, turns_per_unit=1.0, lam0=0.0, lam1=None):
    """direction(lam): the unit vector ``start`` turned about ``axis`` by the angle
    2 pi turns_per_unit (lam - lam0); with ``lam1`` the turn is held outside [lam0, lam1]
    (lam clipped to that interval).

    Parameters: axis, start (3,) (normalised here); turns_per_unit: turns per unit load factor;
    lam0 < lam1: where the turn starts and ends.  Returns: lam -> (3,) unit vector.

    Example
    -------
    >>> import numpy as np
    >>> d = rotating_direction((0, 0, 1), (1, 0, 0), turns_per_unit=0.25)
    >>> np.round(d(1.0), 12).tolist()
    [0.0, 1.0, 0.0]
    """
    axis = finite_vector(axis, "rotation axis")
    start = finite_vector(start, "start direction")
    for v, what in ((axis, "rotation axis"), (start, "start direction")):
        if not np.any(v):
            raise LoadError(f"rotating_direction: the {what} is the zero vector (a NaN field direction at every "
                            "load factor); give a non-zero 3-vector")
    if not (np.isfinite(turns_per_unit) and np.isfinite(lam0)):
        raise LoadError(f"rotating_direction: turns_per_unit and lam0 must be finite, got {turns_per_unit}, {lam0}")
    a = axis / np.linalg.norm(axis)
    s = start / np.linalg.norm(start)
    angle = 2 * pi * turns_per_unit
    if lam1 is None:
        return lambda lam: lie.exp_so3(angle * (lam - lam0) * a) @ s
    if not lam1 > lam0:
        raise LoadError(f"a rotating field needs lam1 > lam0, got {lam0}, {lam1}")
    return lambda lam: lie.exp_so3(angle * (min(max(lam, lam0), lam1) - lam0) * a) @ s


class GradientField(Field):
    """Uniform-gradient field B^a = scale(lam) (B0 + G (x - x0)); G symmetric and traceless.

    Parameters: B0 (3,) flux density [T] at x0 (3,) [length]; G (3, 3) gradient dB_i/dx_j
    [T/length], symmetric (no curl) and traceless (no divergence) to ``tol``, else LoadError.

    Example
    -------
    >>> import numpy as np
    >>> GradientField((0, 0, 0.1), np.diag([1.0, -1.0, 0.0])).value([[1.0, 2.0, 0.0]], 1.0).tolist()
    [[1.0, -2.0, 0.1]]
    >>> GradientField((0, 0, 0), np.eye(3))
    Traceback (most recent call last):
    ...
    core_se3.errors.LoadError: field gradient G has trace 3: div B must vanish
    """

    def __init__(self, B0, G, x0=(0.0, 0.0, 0.0), scale=None, tol=1e-12):
        super().__init__(scale)
        self.B0 = finite_vector(B0, "field B0")
        self.G = np.asarray(G, float)
        self.x0 = finite_vector(x0, "field origin x0")
        if self.G.shape != (3, 3) or not np.all(np.isfinite(self.G)):
            raise LoadError(f"field gradient G must be a finite 3x3 matrix, got {G!r}")
        g = max(np.abs(self.G).max(), 1e-300)
        if np.abs(self.G - self.G.T).max() > tol * g:
            raise LoadError("field gradient G is not symmetric: the field would have a curl "
                            "(currents) inside the body")
        if abs(np.trace(self.G)) > tol * g:
            raise LoadError(f"field gradient G has trace {np.trace(self.G):.3g}: div B must vanish")

    def _value(self, x, lam):
        return self.B0 + (x - self.x0) @ self.G.T

    def _gradient(self, x, lam):
        return np.broadcast_to(self.G, x.shape[:-1] + (3, 3)).copy()

    def _hessian(self, x, lam):
        return np.zeros(x.shape[:-1] + (3, 3, 3))


class DipoleField(Field):
    """Point dipole of moment m [A m^2] at x0:  B = mu0/(4 pi) (3 r (r.m)/|r|^5 - m/|r|^3).

    Curl- and divergence-free everywhere except at x0, which must lie outside the body.
    The Hessian is the complex-step derivative of the closed-form gradient (exact to round-off).
    ``mu0`` must match the model's length unit: MU0 (SI) for m in A m^2 and lengths in m,
    MU0 * 1e3 for m in A mm^2 and lengths in mm (not the magnets' MU0 * 1e6 of N-mm-MPa: that
    would make the field 1000 times too strong).

    Parameters: m (3,) moment [A length^2] at x0 (3,) [length]; scale s(lam); mu0 (default SI).

    Example
    -------
    >>> import numpy as np
    >>> d = DipoleField((0, 0, 1.0), (0, 0, 0), mu0=4 * np.pi)      # on the axis: B = 2 m / r^3
    >>> d.value([[0.0, 0.0, 2.0]], 1.0).tolist()
    [[0.0, 0.0, 0.25]]
    """

    def __init__(self, m, x0, scale=None, mu0=MU0):
        super().__init__(scale)
        self.m = finite_vector(m, "dipole moment m")
        self.x0 = finite_vector(x0, "dipole position x0")
        # a negative mu0 reversed the field (a magnet pulled the wrong way, converged and silent),
        # zero took it away, NaN made every residual NaN
        if (isinstance(mu0, (str, bytes, bool, np.bool_)) or np.ndim(mu0) != 0
                or np.asarray(mu0).dtype.kind not in "iuf" or not (np.isfinite(mu0) and mu0 > 0)):
            raise LoadError(f"dipole mu0 must be a positive number (fields.MU0 for lengths in m, MU0 * 1e3 for "
                            f"mm), got {mu0!r}")
        self.k = mu0 / (4 * pi)

    def _r(self, x):
        r = x - self.x0
        r2 = np.einsum("...i,...i->...", r, r)
        on = np.abs(r2) == 0
        if np.any(on):
            k = np.unravel_index(int(np.argmax(on)), on.shape)
            raise LoadError(f"point {k[0] if len(k) == 1 else tuple(map(int, k))} (at {np.real(x[k]).tolist()}) lies on "
                            f"the dipole at x0 = {self.x0.tolist()}: the field is singular there")
        return r, r2

    def _value(self, x, lam):
        r, r2 = self._r(x)
        rm = r @ self.m
        return self.k * (3 * r * (rm / r2 ** 2.5)[..., None] - self.m / (r2 ** 1.5)[..., None])

    def _gradient(self, x, lam):
        r, r2 = self._r(x)
        rm = r @ self.m
        I = np.eye(3)
        a = (3 / r2 ** 2.5)[..., None, None]
        # dB_i/dx_l = k [3 (d_il (r.m) + r_i m_l + m_i r_l)/r^5 - 15 r_i r_l (r.m)/r^7]
        return self.k * (a * (I * rm[..., None, None] + r[..., :, None] * self.m + self.m[:, None] * r[..., None, :])
                         - (15 * rm / r2 ** 3.5)[..., None, None] * r[..., :, None] * r[..., None, :])

    def _hessian(self, x, lam, h=1e-30):
        x = np.asarray(x, float)
        self._r(x)                   # a point on the dipole: the complex step (r2 = -h^2) would miss it
        out = np.empty(x.shape[:-1] + (3, 3, 3))
        for k in range(3):
            xc = x.astype(complex)
            xc[..., k] += 1j * h * max(1.0, np.abs(x).max())
            out[..., k] = self._gradient(xc, lam).imag / (h * max(1.0, np.abs(x).max()))
        return out


class UserField(Field):
    """A user field: value(x) -> (k,3) [T], gradient(x) -> (k,3,3) dB_i/dx_j, optional
    hessian(x) -> (k,3,3,3).  Without a Hessian the force tangent is taken by central finite
    differences of the gradient and flagged as approximate (``approximate_hessian``).
    The field must be curl- and divergence-free in the body's region (``check_field``).

    Parameters: value, gradient, hessian as above (checked for shape and finiteness); scale
    s(lam); fd_step: the finite-difference step [length] (default 1e-6 max |x| over the points
    evaluated together, the magnetised nodes: relative to the body's size or its distance from
    the origin, so that the same field in other length units gets the same relative accuracy --
    1e-6 max(1, |x|) before, an absolute 1e-6 below one length unit, took a dipole's Hessian
    to 8.8e-7 (relative) for a body of a few mm written in metres and 8.8e-5 ten times smaller,
    against 4e-11 in mm: ``tests/test_fields.py``).

    Example
    -------
    >>> import numpy as np
    >>> G = np.diag([1.0, -1.0, 0.0])
    >>> f = UserField(lambda x: x @ G, lambda x: np.broadcast_to(G, x.shape + (3,)))
    >>> f.approximate_hessian, float(np.abs(f.hessian(np.array([[1.0, 2.0, 3.0]]), 1.0)).max())
    (True, 0.0)
    """

    def __init__(self, value, gradient, hessian=None, scale=None, fd_step=None):
        super().__init__(scale)
        if not callable(value) or not callable(gradient):
            raise LoadError("UserField needs callables value(x) and gradient(x)")
        self._v, self._g, self._h = value, gradient, hessian
        self.approximate_hessian = hessian is None
        self.fd_step = fd_step

    def _call(self, fn, x, shape, what):
        got = fn(x)
        try:
            out = np.asarray(got, float)
        except (TypeError, ValueError):
            raise LoadError(f"user field {what} must return numbers of shape {x.shape[:-1] + shape}, got "
                            f"{type(got).__name__} {str(got)[:60]!r}") from None
        if out.shape != x.shape[:-1] + shape:
            raise LoadError(f"user field {what} returned shape {out.shape}, expected {x.shape[:-1] + shape}")
        if not np.all(np.isfinite(out)):
            raise LoadError(f"user field {what} is not finite at some points")
        return out

    def _value(self, x, lam):
        return self._call(self._v, x, (3,), "value")

    def _gradient(self, x, lam):
        return self._call(self._g, x, (3, 3), "gradient")

    def _hessian(self, x, lam):
        if self._h is not None:
            return self._call(self._h, x, (3, 3, 3), "hessian")
        h = self.fd_step or 1e-6 * (float(np.abs(x).max()) or 1.0)   # (all points at the origin: 1e-6)
        out = np.empty(x.shape[:-1] + (3, 3, 3))
        for k in range(3):
            e = np.zeros(3)
            e[k] = h
            out[..., k] = (self._gradient(x + e, lam) - self._gradient(x - e, lam)) / (2 * h)
        return out


class Superposition(Field):
    """The sum of several fields (e.g. a uniform field plus a magnet's dipole), each with its own
    load-factor programme.

    Parameters: *fields, one or more Field; the sum is uniform only if all of them are.

    Example
    -------
    >>> import numpy as np
    >>> s = Superposition(UniformField((0, 0, 1.0)), GradientField((0, 0, 0.1), np.diag([1.0, -1.0, 0.0])))
    >>> s.uniform, s.value([[1.0, 2.0, 0.0]], 1.0).tolist()
    (False, [[1.0, -2.0, 1.1]])
    """

    def __init__(self, *fields):
        super().__init__(lambda lam: 1.0)
        if not fields or not all(isinstance(f, Field) for f in fields):
            raise LoadError("Superposition needs one or more core_se3.fields.Field objects")
        self.fields = fields
        self.uniform = all(f.uniform for f in fields)
        self.approximate_hessian = any(f.approximate_hessian for f in fields)

    def _value(self, x, lam):
        return sum(f.value(x, lam) for f in self.fields)

    def _gradient(self, x, lam):
        return sum(f.gradient(x, lam) for f in self.fields)

    def _hessian(self, x, lam):
        return sum(f.hessian(x, lam) for f in self.fields)


def check_field(field, x, lam=1.0, rtol=1e-8):
    """(max |curl B|, max |div B|) relative to max |grad B| at points x; raises LoadError above rtol.

    Parameters: field; x (k, 3) sample points in the body's region [length]; lam; rtol.
    Returns: (relative curl, relative divergence), both <= rtol.

    Example
    -------
    >>> import numpy as np
    >>> f = UserField(lambda x: np.c_[0 * x[:, :2], x[:, 0]], lambda x: np.broadcast_to([[0, 0, 0], [0, 0, 0], [1.0, 0, 0]], x.shape + (3,)))
    >>> check_field(f, np.zeros((1, 3)))
    Traceback (most recent call last):
    ...
    core_se3.errors.LoadError: applied field is not curl- and divergence-free in the body: relative |curl B| 1.00e+00, |div B| 0.00e+00
    """
    G = field.gradient(np.asarray(x, float), lam)
    g = max(np.abs(G).max(), 1e-300)
    curl = np.abs(G - np.swapaxes(G, -1, -2)).max() / g
    div = np.abs(np.trace(G, axis1=-2, axis2=-1)).max() / g
    if curl > rtol or div > rtol:
        raise LoadError(f"applied field is not curl- and divergence-free in the body: relative "
                        f"|curl B| {curl:.2e}, |div B| {div:.2e}")
    return curl, div


#: the relative curl or divergence of an applied field in the body above which add_magnetic warns
FIELD_DEFECT_TOL = 1e-6


def field_defect(field, x, lams=(0.5, 1.0)):
    """(relative |curl B|, relative |div B|): the largest at the points x (k, 3) over the load
    factors ``lams``, relative to the largest |grad B| there (0 for a uniform field or where the
    gradient vanishes).  The magnets' loads assume both zero: the couple and the force
    (B^r . grad) B^a are those of a field without currents or sources in the body, and a user
    field with a curl gives converged answers that miss the m x curl B part of the force
    (``Problem.add_magnetic`` warns above ``FIELD_DEFECT_TOL``; ``check_field`` raises).

    Example
    -------
    >>> import numpy as np
    >>> f = UserField(lambda x: np.c_[0 * x[:, :2], x[:, 0]], lambda x: np.broadcast_to([[0, 0, 0], [0, 0, 0], [1.0, 0, 0]], x.shape + (3,)))
    >>> field_defect(f, np.zeros((2, 3)))
    (1.0, 0.0)
    """
    x = np.asarray(x, float).reshape(-1, 3)
    curl = div = 0.0
    if field.uniform or not len(x):
        return curl, div
    for lam in lams:
        G = field.gradient(x, lam)
        g = np.abs(G).max()
        if g > 0:
            curl = max(curl, float(np.abs(G - np.swapaxes(G, -1, -2)).max() / g))
            div = max(div, float(np.abs(np.trace(G, axis1=-2, axis2=-1)).max() / g))
    return curl, div


def field_vanishes(field, x, lams=(0.5, 1.0)):
    """True if the field at scale 1 (``Field.unscaled``) and its gradient are zero at every point
    x (k, 3) at each load factor of ``lams``: a magnet there takes no couple h/mu0 B^r x B^a and
    no force h/mu0 (B^r . grad) B^a at any scale (a B of zeros; a scale that is zero is the other
    way to a field that acts nowhere).  False where there are no points or the field cannot be
    evaluated there (its own error comes with the load).

    Example
    -------
    >>> import numpy as np
    >>> x = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    >>> field_vanishes(UniformField((0.0, 0.0, 0.0)), x), field_vanishes(UniformField((0.0, 0.0, 1e-9)), x)
    (True, False)
    >>> field_vanishes(GradientField((0.0, 0.0, 0.0), np.diag([1.0, -1.0, 0.0])), x)    # zero at x = 0 only
    False
    """
    x = np.asarray(x, float).reshape(-1, 3)
    if not len(x):
        return False
    try:
        for lam in lams:
            if np.any(field.unscaled(x, lam) != 0) or (not field.uniform and np.any(field._gradient(x, lam) != 0)):
                return False
    except LoadError:
        return False
    return True


# ------------------------------------------------------------------ registry -------------
@dataclass(frozen=True)
class FieldKind(Kind):
    """A field kind of scenario files: ``params`` (the keys besides type and scale) and
    ``build(values, scale, mu0) -> Field`` (mu0: the model's vacuum permeability).

    Attributes: name, params (tuple of Param), build, check ((values, given) -> (key, message)
    or None, optional) and doc, as for :class:`~core_se3.model.LoadKind`.

    Example
    -------
    >>> [p.name for p in field_kind("dipole").params], type(field_kind("uniform").build({"B": (0, 0, 1.0), "rotate": None}, None, MU0)).__name__
    (['m', 'x0', 'mu0'], 'UniformField')
    """
    name: str
    params: tuple
    build: Callable
    check: Callable | None = None
    doc: str = ""


FIELDS = Registry("field kind", FieldKind, reserved=("scale",))


def register_field(kind: FieldKind):
    """Add a field kind to the registry (its name must be new); returns it.

    Parameters: kind (FieldKind).  Returns: kind; TypeError for anything else, ValueError for a
    name that is already registered.

    Example
    -------
    >>> register_field(field_kind("dipole"))
    Traceback (most recent call last):
    ...
    ValueError: field kind 'dipole' is registered twice
    """
    return FIELDS.add(kind)


def field_kind(name) -> FieldKind:
    """The registered field kind ``name``; an OptionError naming the closest one otherwise.

    Parameters: name (str, a key of ``FIELDS``).  Returns: FieldKind.

    Example
    -------
    >>> field_kind("unifrom")
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: unknown field kind 'unifrom'; did you mean 'uniform'?; registered: dipole, gradient, uniform
    """
    return FIELDS.lookup(name)


def _uniform(values, scale, mu0):
    rot = values.get("rotate")
    direction = None
    if rot is not None:
        # the angle over [start, end] of the load factor, held outside
        warn_angle(rot["angle"], "a rotating field's rotate.angle")
        direction = rotating_direction(rot["axis"], values["B"],
                                       turns_per_unit=rot["angle"] / (2 * pi * (rot["end"] - rot["start"])),
                                       lam0=rot["start"], lam1=rot["end"])
    return UniformField(values["B"], scale=scale, direction=direction)


def _uniform_check(values, given):
    rot = values.get("rotate")
    if rot is not None:
        if rot["end"] <= rot["start"]:
            return "rotate.end", f"expected end > start ({rot['start']:g}), got {rot['end']:g}"
        if not any(values["B"]):
            return "B", "a rotating field needs a non-zero B (its initial direction)"
    return None


register_field(FieldKind("uniform", (
    Param("B", "vector", doc="flux density [T] at scale 1"),
    Param("rotate", "table", None, doc="turn the field: axis, angle [rad], start, end (load factors)",
          fields=(Param("axis", "vector", nonzero=True), Param("angle", "number"),
                  Param("start", "number", 0.0), Param("end", "number", 1.0)))),
    _uniform, _uniform_check, doc="a uniform field, optionally turning with the load factor"))
register_field(FieldKind("gradient", (
    Param("B", "vector", doc="flux density [T] at x0"),
    Param("G", "matrix3", doc="gradient dB_i/dx_j [T/length], symmetric and traceless"),
    Param("x0", "vector", (0.0, 0.0, 0.0), doc="reference point")),
    lambda v, scale, mu0: GradientField(v["B"], v["G"], x0=v["x0"], scale=scale),
    doc="a field of uniform gradient"))
register_field(FieldKind("dipole", (
    Param("m", "vector", nonzero=True, doc="dipole moment [A length^2]"),
    Param("x0", "vector", doc="dipole position (outside the body)"),
    Param("mu0", "number", None, lo=0.0, lo_open=True,
          doc="vacuum permeability in the model's units (default SI)")),
    lambda v, scale, mu0: DipoleField(v["m"], v["x0"], scale=scale,
                                      **({} if v["mu0"] is None else {"mu0": v["mu0"]})),
    doc="a point dipole"))
