"""Design variables: parameters p of the residual r(g, lam; p) that a design may change.

Every variable has a vector of values x (its free components), bounds, a typical size (the
optimisers work on x / scale), and two derivatives of the full residual r = r_int - f_ext
(n, 6) (left-trivialised, body frames) at a state (g, lam):

* ``dr_dp(problem, g, lam)`` -> (n, 6, size): the columns dr/dx (the direct method);
* ``vjp(problem, g, lam, mu)`` -> (size,): sum_i mu_i . dr_i/dx (the adjoint method).

How dr/dp is computed (no equilibrium is re-solved for it):

* applied field (uniform vector, in-plane polar form, uniform gradient), magnetisation per
  region (``design.magnetisation``: vector or magnitude + angle in a plane) and load
  magnitudes: **analytically**.  The
  magnetic load is bilinear in the dipoles mu_i and the field, f_w = mu x R^T B^a,
  f_v = R^T G R mu, so its derivatives are closed-form nodal 6x3 blocks, exact and as cheap
  as one load evaluation; a load is linear in its magnitude, df/dP = f at P = 1.
* E and h per region (``design.material``): by central differences of the **element residual only** at the fixed
  state g (the element is rebuilt with the perturbed law).  The residual is linear in E and
  a cubic polynomial in h (membrane and shear ~ h, bending and drilling ~ h^3), so the
  Richardson combination (4 D(d) - D(2d)) / 3 of two central differences is exact up to
  round-off; a complex step would need complex arithmetic through the element kernels.

Example
-------
>>> import numpy as np
>>> from core_se3 import Problem, Material, mesh
>>> from core_se3.model import UniformField
>>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.01))
>>> p.clamp("x0")
>>> f = UniformField((0.0, 0.0, 1.0)); _ = p.add_magnetic((1.0, 0.0, 0.0), f, mu0=1.0)
>>> v = FieldVariable(p, f, form="polar", free=("magnitude",))
>>> v.value().tolist(), v.labels
([1.0], ['field.B'])
>>> v.assign([2.0]); f.B.round(12).tolist()
[0.0, 0.0, 2.0]
"""
from __future__ import annotations

import numpy as np

from .. import lie
from ..errors import DesignError, did_you_mean
from ..model import GradientField, MagneticLoad, Superposition, UniformField

__all__ = ["Variable", "FieldVariable", "FieldGradientVariable", "LoadMagnitude", "magnetic_loads", "field_share",
           "polar_vector",
           "region_elements", "named_regions", "region_label", "field_at", "free_index", "plane_axes"]


def polar_vector(b, angle, e1, e2):
    """b (cos angle e1 + sin angle e2) and its derivatives by b and by the angle.

    Parameters: b (k,) magnitudes, angle (k,) [rad], e1, e2 (k, 3) orthonormal in-plane axes.
    Returns: (vectors (k, 3), d/db (k, 3), d/dangle (k, 3)).

    Example
    -------
    >>> import numpy as np
    >>> v, db, da = polar_vector(np.array([2.0]), np.array([np.pi / 2]), np.eye(3)[[0]], np.eye(3)[[2]])
    >>> v.round(12).tolist(), da.round(12).tolist()
    ([[0.0, 0.0, 2.0]], [[-2.0, 0.0, 0.0]])
    """
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    d = c * e1 + s * e2
    return np.asarray(b)[:, None] * d, d, np.asarray(b)[:, None] * (-s * e1 + c * e2)


def plane_axes(e1, e2, what):
    e1, e2 = np.asarray(e1, float), np.asarray(e2, float)
    if e1.shape != (3,) or e2.shape != (3,) or not np.all(np.isfinite(np.r_[e1, e2])):
        raise DesignError(f"{what}: the plane needs two finite 3-vectors e1, e2")
    n1 = np.linalg.norm(e1)
    e2 = e2 - (e2 @ e1) / max(n1 * n1, 1e-300) * e1
    if n1 == 0 or np.linalg.norm(e2) < 1e-12 * n1:
        raise DesignError(f"{what}: the plane axes e1, e2 must be non-zero and not parallel")
    return e1 / n1, e2 / np.linalg.norm(e2)


def region_elements(problem, r, what):
    """Element ids (sorted) of a region name or of ids; DesignError naming ``what`` otherwise.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> region_elements(p, [1, 0], "x").tolist()
    [0, 1]
    """
    if isinstance(r, str):
        try:
            return np.asarray(problem.mesh.elements(r), np.int64)
        except Exception as exc:              # MeshError: unknown region (with a suggestion)
            raise DesignError(f"{what}: {exc}") from None
    ids = np.unique(np.asarray(r, np.int64).ravel())
    if ids.size == 0 or ids.min() < 0 or ids.max() >= problem.mesh.n_elements:
        raise DesignError(f"{what}: element ids {np.asarray(r).ravel()[:5].tolist()} do not exist (the mesh has "
                          f"{problem.mesh.n_elements} elements)")
    return ids


def named_regions(regions):
    """(names, regions) of a variable's ``regions``: a mapping name -> region (a scenario's
    regions by name) or a sequence of region names or element ids; ``names[j]`` is region j's
    name, None for ids (its messages then name it by its index: :func:`region_label`).

    Example
    -------
    >>> named_regions({"root": [0], "tip": [1]})
    (['root', 'tip'], [[0], [1]])
    >>> named_regions(["tip", [0, 1]])[0]
    ['tip', None]
    """
    if isinstance(regions, dict):
        return list(regions), list(regions.values())
    regions = list(regions)
    return [r if isinstance(r, str) else None for r in regions], regions


def region_label(names, j):
    """How messages call region ``j``: by its name (``named_regions``) where known, else its index.

    Example
    -------
    >>> region_label(["root", None], 0), region_label(["root", None], 1)
    ("region 'root'", 'region 1')
    """
    return f"region {names[j]!r}" if names[j] is not None else f"region {j}"


def field_share(outer, field, lam):
    """d(value of ``outer``)/d(value of ``field``) at the load factor lam: 1 when ``outer`` is
    ``field``, its scale s(lam) times the sum of its parts' shares for a ``Superposition`` (a
    field that is a part of the sum, e.g. a uniform coil field beside a magnet's dipole), 0 when
    ``field`` does not enter ``outer``.

    Example
    -------
    >>> from core_se3.model import DipoleField, Superposition, UniformField
    >>> coil = UniformField((0.0, 0.0, 1.0))
    >>> both = Superposition(coil, DipoleField((0, 0, 1.0), (0, 0, 1.0)))
    >>> field_share(both, coil, 0.5), field_share(coil, UniformField((0, 0, 1.0)), 0.5)
    (1.0, 0.0)
    """
    if outer is field:
        return 1.0
    if isinstance(outer, Superposition):
        share = sum(field_share(f, field, lam) for f in outer.fields)
        return outer.scale_at(lam) * share if share else 0.0
    return 0.0


def _enters(outer, field):
    """True when ``field`` is ``outer`` or one of the parts of a Superposition ``outer``."""
    return outer is field or (isinstance(outer, Superposition) and any(_enters(f, field) for f in outer.fields))


def magnetic_loads(problem, field=None):
    """The MagneticLoads of ``problem`` (those in ``field`` if given: whose applied field is
    ``field`` or a ``Superposition`` with ``field`` among its parts).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import UniformField
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.01))
    >>> f = UniformField((0.0, 0.0, 1.0)); _ = p.add_magnetic((1.0, 0.0, 0.0), f)
    >>> len(magnetic_loads(p, f)), len(magnetic_loads(p, UniformField((0.0, 0.0, 1.0))))
    (1, 0)
    """
    return [ld for ld in problem.loads if isinstance(ld, MagneticLoad) and (field is None or _enters(ld.field, field))]


def field_at(ld, g, lam):
    """Per magnetised node of load ld: R (k,3,3), a = R^T B (k,3), A = R^T G R (k,3,3) or None."""
    nodes = ld.mag.nodes
    R = g[nodes, :3, :3]
    Rt = np.swapaxes(R, 1, 2)
    x = g[nodes, :3, 3]
    a = np.einsum("kij,kj->ki", Rt, ld.field.value(x, lam))
    A = None if ld.field.uniform else Rt @ ld.field.gradient(x, lam) @ R
    return R, a, A


class Variable:
    """Base class of design variables (module docstring).

    Attributes
    ----------
    name : str
        The variable's name; ``labels``: one name per component.
    size : int
        Number of components (the free ones).
    lower, upper : (size,) ndarray
        Bounds (+-inf: none).
    scale : (size,) ndarray
        Typical magnitudes (the optimisers work on x / scale).
    pose : int or None
        The pose the variable belongs to (None: shared by every pose, e.g. a magnetisation).
    norm_bounds : list of (component indices, maximum)
        Bounds on the Euclidean norm of groups of components (|B^a| <= B_max of a vector form).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> v = LoadMagnitude(p, p.loads[0])
    >>> isinstance(v, Variable), v.size, v.pose
    (True, 1, None)
    """

    name = "variable"
    pose = None

    def _setup(self, name, size, lower, upper, scale, labels, pose):
        self.name, self.size, self.pose = name, int(size), pose
        self.lower = np.broadcast_to(np.asarray(lower, float), (self.size,)).copy()
        self.upper = np.broadcast_to(np.asarray(upper, float), (self.size,)).copy()
        self.scale = np.broadcast_to(np.asarray(scale, float), (self.size,)).copy()
        self.scale[~(self.scale > 0)] = 1.0
        self.labels = list(labels)
        if not hasattr(self, "norm_bounds"):
            self.norm_bounds = []
        if np.any(self.lower > self.upper):
            raise DesignError(f"variable {name!r}: empty bounds (lower {self.lower.tolist()} > upper "
                              f"{self.upper.tolist()})")

    def value(self):
        """The current values (size,) in the problem."""
        raise NotImplementedError

    def assign(self, x):
        """Set the values x (size,) into the problem."""
        raise NotImplementedError

    def dr_dp(self, problem, g, lam):
        """d(r_int - f_ext)/dx (n, 6, size) at (g, lam)."""
        raise NotImplementedError

    def controls(self):
        """The parameters of the problem this variable sets (hashable keys: the field and its
        vector, a load's magnitude, a region's E, h or magnetisation per element).  Two variables
        of a design that both set one parameter in the same pose would overwrite each other --
        the state follows the later one, but both get a derivative -- so ``Design`` refuses them.

        Example
        -------
        >>> from core_se3 import Problem, Material, mesh
        >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.01))
        >>> p.add_edge_force("x1", (0.0, 0.0, 1.0))
        >>> LoadMagnitude(p, p.loads[0]).controls() == LoadMagnitude(p, p.loads[0]).controls()
        True
        """
        return {("variable", id(self))}

    def vjp(self, problem, g, lam, mu):
        """sum_i mu_i . dr_i/dx for nodal multipliers mu (n, 6) -> (size,), or a stack of them
        (k, n, 6) -> (k, size)."""
        return np.einsum("...ni,nik->...k", mu, self.dr_dp(problem, g, lam))

    def check_start(self):
        """DesignError when the current value lies outside the bounds (the start)."""
        x = self.value()
        bad = (x < self.lower - 1e-12 * np.abs(self.lower)) | (x > self.upper + 1e-12 * np.abs(self.upper))
        if np.any(bad):
            i = int(np.nonzero(bad)[0][0])
            raise DesignError(f"variable {self.labels[i]!r}: the start {x[i]:g} lies outside its bounds "
                              f"[{self.lower[i]:g}, {self.upper[i]:g}]")
        for idx, top in self.norm_bounds:
            n = float(np.linalg.norm(x[idx]))
            if n > top * (1 + 1e-12):
                raise DesignError(f"variable {self.name!r}: the start has norm {n:g} above the bound {top:g}")
        excess = self.start_excess()
        if excess:
            raise DesignError(f"variable {self.name!r}: {excess}")

    def start_excess(self):
        """What of the start, fixed components included, exceeds a bound of the variable that the
        free components' bounds do not hold (a polar form's magnitude kept fixed above B_max):
        a sentence, or None."""
        return None


def free_index(parts, free, what):
    if free is None:
        return np.arange(len(parts))
    free = [free] if isinstance(free, str) else list(free)
    bad = [f for f in free if f not in parts]
    if bad or not free:
        raise DesignError(f"{what}: unknown free component {bad[0] if bad else None!r}"
                          f"{did_you_mean(bad[0], parts) if bad else ''}; choose from {', '.join(parts)}")
    return np.array([parts.index(f) for f in free])


class FieldVariable(Variable):
    """The vector of a uniform field (``UniformField.B``, or ``GradientField.B0``) as a design
    variable: form 'vector' (Bx, By, Bz [T]) or 'polar' (magnitude B [T] and angle [rad] from e1
    toward e2 in the plane (e1, e2)); ``free`` picks the optimised components ('x', 'y', 'z' or
    'magnitude', 'angle'), the others stay at their current values.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem whose magnetic loads use ``field``.
    field : UniformField or GradientField
        The field (a UniformField with a turning ``direction`` is refused).
    form : str
        'vector' or 'polar'.
    plane : (e1, e2), optional
        The plane of the polar form (default x and z: a strip in the x-y plane bending in x-z).
    free : sequence of str, optional
        The free components (default all).
    B_max : float, optional
        |B^a| <= B_max [T]: a norm bound (vector form) or the upper bound of the magnitude.
    pose : int, optional
        The pose of the field (None: every pose).
    name : str
        Its name.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import UniformField
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.01))
    >>> f = UniformField((0.0, 0.0, 0.5)); _ = p.add_magnetic((1.0, 0.0, 0.0), f, mu0=1.0)
    >>> v = FieldVariable(p, f, form="polar")
    >>> np.round(v.value(), 6).tolist(), v.upper.tolist()
    ([0.5, 1.570796], [inf, inf])
    """

    def __init__(self, problem, field, form="vector", plane=((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)), free=None,
                 B_max=None, pose=None, name="field"):
        if isinstance(field, UniformField):
            if field.direction is not None:
                raise DesignError(f"field variable {name!r}: a turning uniform field (direction) cannot be designed")
            self._attr = "B"
        elif isinstance(field, GradientField):
            self._attr = "B0"
        else:
            raise DesignError(f"field variable {name!r}: a uniform or uniform-gradient field is needed, got "
                              f"{type(field).__name__}")
        if form not in ("vector", "polar"):
            raise DesignError(f"field variable {name!r}: form must be 'vector' or 'polar', got {form!r}")
        self.problem, self.field, self.form = problem, field, form
        B = np.asarray(getattr(field, self._attr), float)
        # the typical size of the components: |B|, the bound, or 1 T from a zero field (a floor
        # of 1e-300 made the optimisers' gradient 1e-300 x the true one: no step from B = 0)
        scale0 = max(float(np.linalg.norm(B)), float(B_max or 0.0)) or 1.0
        if form == "vector":
            self.parts = ["x", "y", "z"]
            self.full = B.copy()
            lo, hi, sc = np.full(3, -np.inf), np.full(3, np.inf), np.full(3, scale0)
        else:
            self.e1, self.e2 = plane_axes(*plane, f"field variable {name!r}")
            b1, b2 = B @ self.e1, B @ self.e2
            if np.linalg.norm(B - b1 * self.e1 - b2 * self.e2) > 1e-12 * scale0:
                raise DesignError(f"field variable {name!r}: the field {B.tolist()} is not in the plane of the polar form")
            self.parts = ["magnitude", "angle"]
            self.full = np.array([np.hypot(b1, b2), np.arctan2(b2, b1)])
            lo, hi, sc = np.array([0.0, -np.inf]), np.array([np.inf, np.inf]), np.array([scale0, 1.0])
            if B_max is not None:
                hi[0] = B_max
        self.free = free_index(self.parts, free, f"field variable {name!r}")
        if form == "polar" and 1 not in self.free and self.full[0] == 0:
            raise DesignError(f"field variable {name!r}: a polar form with its angle fixed needs a non-zero start field "
                              "(its direction): the field is zero, whose angle would be taken as 0 (along e1)")
        self.norm_bounds, self.B_max = [], B_max
        if B_max is not None and form == "vector":
            # |B|^2 = |free part|^2 + |fixed part|^2 <= B_max^2 (the fixed part as a constant)
            fixed = np.setdiff1d(np.arange(3), self.free)
            self.norm_bounds = [(np.arange(len(self.free)), float(np.sqrt(max(B_max ** 2 - B[fixed] @ B[fixed], 0.0))))]
        if not magnetic_loads(problem, field):
            # (a field object no magnet uses: every derivative 0, the variable ignored, silently)
            raise DesignError(f"field variable {name!r}: no magnet of the problem is in this field (an equal field "
                              "is not the same one); pass the field object given to Problem.add_magnetic")
        self._setup(name, len(self.free), lo[self.free], hi[self.free], sc[self.free],
                    [f"{name}.{'B' if p == 'magnitude' else p}" for p in np.array(self.parts)[self.free]], pose)

    def start_excess(self):
        """The start field's magnitude above B_max (the magnitude or components held fixed there:
        before, the design kept a fixed magnitude of 0.002 T with B_max = 0.001 and wrote it)."""
        m = float(np.linalg.norm(self.vector()))
        if self.B_max is not None and m > self.B_max * (1 + 1e-12):
            return (f"the start field has magnitude {m:g} above B_max = {self.B_max:g} (its fixed components keep "
                    "it there); lower the start field or raise B_max")
        return None

    def vector(self, full=None):
        """The field vector [T] of the full parameters (default the current ones)."""
        full = self.full if full is None else full
        if self.form == "vector":
            return np.array(full, float)
        return polar_vector(np.array([full[0]]), np.array([full[1]]), self.e1[None], self.e2[None])[0][0]

    def _dvec(self):
        """d(field vector)/d(full parameters) (3, nfull)."""
        if self.form == "vector":
            return np.eye(3)
        _, db, da = polar_vector(np.array([self.full[0]]), np.array([self.full[1]]), self.e1[None], self.e2[None])
        return np.stack([db[0], da[0]], 1)

    def value(self):
        return self.full[self.free].copy()

    def assign(self, x):
        self.full = self.full.copy()
        self.full[self.free] = np.asarray(x, float)
        setattr(self.field, self._attr, self.vector())

    def controls(self):
        return {("field", id(self.field), self._attr)}

    def dr_dB(self, problem, g, lam):
        """d(r_int - f_ext)/dB (n, 6, 3): the couple f_w = mu x R^T s B of every magnetised node
        (s: the field's scale times its share in the magnet's field, ``field_share``)."""
        out, loads = _field_derivative_setup(problem, self.field, lam, 3, f"field variable {self.name!r}")
        for ld, s in loads:
            R = g[ld.mag.nodes, :3, :3]
            out[ld.mag.nodes, 3:, :] -= s * lie.hat3(ld.mag.mu) @ np.swapaxes(R, 1, 2)
        return out

    def dr_dp(self, problem, g, lam):
        return self.dr_dB(problem, g, lam) @ self._dvec()[:, self.free]


def _field_derivative_setup(problem, field, lam, k, what):
    """(zeros (n, 6, k), [(magnetic load in ``field``, d B_load / d B_field-at-scale-1 = the
    field's scale at lam times its ``field_share`` in the load's field)]): the start of a field
    variable's dr/dp; DesignError when no magnet of the problem is in that field."""
    loads = magnetic_loads(problem, field)
    if not loads:
        raise DesignError(f"{what}: no magnet of the problem is in this field")
    s = field.scale_at(lam)
    return np.zeros((problem.mesh.n_nodes, 6, k)), [(ld, s * field_share(ld.field, field, lam)) for ld in loads]


# a basis of the symmetric traceless 3x3 matrices (the gradients of curl- and divergence-free fields)
_GBASIS = np.array([np.diag([1.0, -1.0, 0.0]), np.diag([0.0, 1.0, -1.0]),
                    [[0, 1.0, 0], [1.0, 0, 0], [0, 0, 0]], [[0, 0, 1.0], [0, 0, 0], [1.0, 0, 0]],
                    [[0, 0, 0], [0, 0, 1.0], [0, 1.0, 0]]])


class FieldGradientVariable(Variable):
    """The gradient G of a ``GradientField`` (B = s (B0 + G (x - x0))) as five coefficients c of a
    basis of the symmetric traceless matrices (diag(1,-1,0), diag(0,1,-1), sym xy, xz, yz)
    [T/length]: the field stays curl- and divergence-free for every value.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem whose magnetic loads use ``field``.
    field : GradientField
        The field.
    pose : int, optional
        Its pose; ``name``: its name; ``scale``: typical |c| (default |G| or 1).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import GradientField
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.01))
    >>> f = GradientField((0.0, 0.0, 1.0), np.diag([2.0, -2.0, 0.0])); _ = p.add_magnetic((1.0, 0, 0), f, mu0=1.0)
    >>> (FieldGradientVariable(p, f).value().round(12) + 0.0).tolist()
    [2.0, 0.0, 0.0, 0.0, 0.0]
    """

    def __init__(self, problem, field, pose=None, name="gradient", scale=None):
        if not isinstance(field, GradientField):
            raise DesignError(f"gradient variable {name!r}: needs a GradientField, got {type(field).__name__}")
        self.problem, self.field = problem, field
        c = np.linalg.lstsq(_GBASIS.reshape(5, 9).T, field.G.ravel(), rcond=None)[0]
        self.c = c
        sc = scale or max(float(np.abs(field.G).max()), 1.0)
        self._setup(name, 5, -np.inf, np.inf, sc, [f"{name}.{k}" for k in ("xx-yy", "yy-zz", "xy", "xz", "yz")], pose)

    def value(self):
        return self.c.copy()

    def controls(self):
        return {("field", id(self.field), "G")}

    def assign(self, x):
        self.c = np.asarray(x, float).copy()
        self.field.G = np.einsum("k,kij->ij", self.c, _GBASIS)

    def dr_dp(self, problem, g, lam):
        out, loads = _field_derivative_setup(problem, self.field, lam, 5, f"gradient variable {self.name!r}")
        for ld, s in loads:
            nodes, mu = ld.mag.nodes, ld.mag.mu
            R = g[nodes, :3, :3]
            Rt = np.swapaxes(R, 1, 2)
            dx = g[nodes, :3, 3] - self.field.x0
            Rmu = np.einsum("kij,kj->ki", R, mu)
            # f_v = s R^T E_k R mu,  f_w = mu x (s R^T E_k (x - x0))
            out[nodes, :3, :] -= s * np.einsum("kai,bij,kj->kab", Rt, _GBASIS, Rmu)
            out[nodes, 3:, :] -= s * np.einsum("kac,kci,bij,kj->kab", lie.hat3(mu), Rt, _GBASIS, dx)
        return out


class LoadMagnitude(Variable):
    """A multiplier P [-] of a load as it was built (its ``scale(lam)`` becomes P scale(lam)):
    the magnitude of a force, moment or pressure, dead or follower.  dr/dP = -f at P = 1.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem holding ``load``.
    load : core_se3.model.Load or sequence of them
        A load with a ``scale`` attribute (edge, nodal, surface loads), or the loads one input
        built (an edge load on a union of lines: one per line; gravity: one per density and
        thickness), all scaled by the one P.
    lower, upper : float, optional
        Bounds of P; ``pose``: its pose; ``name``: its name.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> v = LoadMagnitude(p, p.loads[0]); v.assign([3.0])
    >>> round(float(p.external(p.mesh.g0, 1.0)[0][:, 2].sum()), 12)
    3.0
    """

    def __init__(self, problem, load, lower=-np.inf, upper=np.inf, pose=None, name="load"):
        loads = list(load) if isinstance(load, (list, tuple)) else [load]
        if not loads or not all(any(ld is x for x in problem.loads) and callable(getattr(ld, "scale", None))
                                for ld in loads):
            raise DesignError(f"load variable {name!r}: the load is not one of the problem's scaled loads")
        self.problem, self.loads, self.P = problem, loads, 1.0
        self.load, self.bases = loads[0], [ld.scale for ld in loads]
        self.base = self.bases[0]
        self._setup(name, 1, lower, upper, 1.0, [name], pose)

    def value(self):
        return np.array([self.P])

    def controls(self):
        return {("load", id(ld)) for ld in self.loads}

    def assign(self, x):
        self.P = P = float(np.asarray(x, float).ravel()[0])
        for ld, base in zip(self.loads, self.bases):
            ld.scale = (lambda b: lambda lam: P * b(lam))(base)

    def dr_dp(self, problem, g, lam):
        cur = [ld.scale for ld in self.loads]
        f = 0.0
        try:
            for ld, base in zip(self.loads, self.bases):
                ld.scale = base
                f = f + ld.evaluate(g, lam, tangent=False).f
        finally:
            for ld, c in zip(self.loads, cur):
                ld.scale = c
        return -f[:, :, None]
