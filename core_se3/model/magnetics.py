"""Hard-magnetic loads: body couple and body force on magnetised shell material.

Material.  The residual flux density B^r_0 [T] (magnetisation M = B^r/mu0) is given in the lab
frame of the reference configuration; the particles are fixed to the material, so it rotates
with the frames: B^r_t = R_t R_0^T B^r_0 (seed eq. E48).  It is a property per unit *volume*;
the thickness h turns it into loads per unit reference area (the seed states the field per unit
surface, E47-E49):

    couple  c = h (1/mu0) B^r_t x B^a(phi)             [N m / m^2]   (seed E49)
    force   f = h (1/mu0) (B^r_t . grad) B^a(phi)       [N / m^2]     (zero in a uniform field)

Discretisation.  Both are linear in B^r_t, so the magnetised material is lumped into point
dipoles at the nodes (nodal quadrature of the surface integrals), each fixed in its node's frame:

    mu_i = (h/mu0) R_0i^T  sum_e int_e N_i B^r_0(X) dA_0         [A m^2, body components]

and node i receives the lab couple (R_i mu_i) x B^a(phi_i) and force G(phi_i) R_i mu_i with
G = grad B^a.  dA_0 is the element's own area element on curved elements (the default
element's exact-arc j0, as the area loads take it: ``loads.curved_area``), so the lumping is
exact for the total dipole moment of the body, second-order accurate in the mesh size,
objective, and keeps the load stiffness in 6x6 nodal blocks.  Only magnetised nodes are evaluated.

Generalised forces (left trivialisation, seed E32) and their load stiffness along
g <- g exp(eta), with a = R^T B^a, A = R^T G R (body components):

    f_v = A mu,            f_w = mu x a                                       (seed E50)
    d f_w = hat(mu) hat(a) eta_w + hat(mu) A eta_v                            (seed E80 + grad B^a)
    d f_v = (hat(A mu) - A hat(mu)) eta_w + R^T (H . R mu) R eta_v           (H = grad grad B^a)

and the blocks returned are -d f / d eta, as for every load (loads.py).
"""
from __future__ import annotations

from contextlib import contextmanager

import numpy as np

from .. import lie
from ..errors import LoadError, MeshError
from ..fem.quadrature import shape_functions, surface_jacobian
from .base import Load, LoadEvaluation
from .fields import MU0, Field
from .loads import curved_area

__all__ = ["Magnetisation", "MagneticLoad", "table_kind", "br_numbers", "MU0", "compiled_magnets", "magnets_force", "magnets_output",
           "dipole_resolution", "DIPOLE_RESOLUTION", "dipole_sources", "on_dipole"]


def table_kind(shape, m, n_nodes, per=None):
    """'element' or 'node': which table a ``Br`` of ``shape`` is, for m selected elements and
    n_nodes nodes (``per``: the caller's word); a LoadError for another shape, and for
    (m, 3) == (n_nodes, 3) without ``per`` (both fit: a closed mesh).

    Example
    -------
    >>> table_kind((4, 3), 4, 6), table_kind((6, 3), 6, 6, per="node")
    ('element', 'node')
    """
    fits = [k for k, n in (("element", m), ("node", n_nodes)) if tuple(shape) == (n, 3)]
    if per is not None and per not in fits:
        raise LoadError(f"magnetisation Br per {per} must have shape ({m if per == 'element' else n_nodes}, 3); "
                        f"got shape {tuple(shape)}")
    if per is None and len(fits) == 2:
        raise LoadError(f"magnetisation Br of shape {tuple(shape)} fits both one per selected element ({m}) and one "
                        f"per node ({n_nodes}, a closed mesh): say which with Br_per='element' or Br_per='node'")
    if not fits:
        raise LoadError(f"magnetisation Br must be a 3-vector, one per selected element ({m}, 3), one "
                        f"per node ({n_nodes}, 3) or a function of position; got shape {tuple(shape)}")
    return per or fits[0]


def br_numbers(Br):
    """``Br`` as an array of floats, or a LoadError naming it (not NumPy's ValueError on 'x').

    Example
    -------
    >>> br_numbers([0, 0, 1]).tolist()
    [0.0, 0.0, 1.0]
    """
    try:
        return np.asarray(Br, float)
    except (TypeError, ValueError):
        raise LoadError(f"magnetisation Br must be numbers [T]: a 3-vector, a table (k, 3) or a function of "
                        f"position, got {Br!r}") from None


class Magnetisation:
    """Nodal dipole moments of magnetised material on a set of elements.

    Br: residual flux density [T], lab components in the reference configuration: a 3-vector
    (uniform), an (m_sel, 3) array (per selected element), an (n_nodes, 3) array (per node,
    interpolated bilinearly), or a callable X (k, 3) -> (k, 3) (function of reference position,
    evaluated at the 2x2 Gauss points).

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The mesh.
    Br : array_like or callable
        As above [T].
    h : float
        Thickness [length] (B^r is per unit volume).
    elements : array_like of int, optional
        The magnetised elements (default all).
    mu0 : float, optional
        Vacuum permeability in the model's units (default ``MU0``, SI).
    Br_per : {None, 'element', 'node'}, optional
        Which table an (k, 3) ``Br`` is; None: told by its shape, and a LoadError when the
        selection has as many elements as the mesh has nodes (a closed mesh), where both fit.
    j0 : (m, 4) array_like, optional
        The element's own area element at the 2x2 Gauss points of the selected elements
        (``loads.element_area``: the default element's, of its exact-arc geometry), taken on
        the curved elements as the area loads take it (``loads.curved_area``); default the
        bilinear quads' (over the chords of a curved element the dipoles were low by
        sin(dth/2)/(dth/2): 0.17 % at 0.2 rad per element).  ``Problem.add_magnetic`` gives it.

    Attributes
    ----------
    nodes : (k,) ndarray
        The magnetised nodes; ``mu`` (k, 3): their dipoles [A length^2] in the body frames,
        (h/mu0) R_0^T int N_i B^r_0 dA.
    total_lab : (3,) ndarray
        int B^r_0 dV [T length^3] (exact for the lumped dipoles).
    br_max : float
        The largest |B^r_0| [T] at the Gauss points of the selection (a plausibility check's).

    Example
    -------
    >>> from core_se3 import mesh
    >>> mag = Magnetisation(mesh.rectangle(2.0, 1.0, 2, 1), (0.1, 0.0, 0.0), h=0.5, mu0=1.0)
    >>> mag.total_lab.round(12).tolist()                        # int Br dV = Br h A
    [0.1, 0.0, 0.0]
    >>> mag.mu[:3, 0].round(12).tolist()                        # corner, mid-edge, corner node
    [0.0125, 0.025, 0.0125]
    """

    def __init__(self, mesh, Br, h, elements=None, mu0=MU0, Br_per=None, j0=None):
        if Br_per not in (None, "element", "node"):
            raise LoadError(f"Br_per must be 'element', 'node' or None (told by Br's shape), got {Br_per!r}")
        self.Br_per = Br_per
        if not (_real(h) and np.isfinite(h) and h > 0):
            raise LoadError(f"thickness for the magnetisation must be a positive number, got {h!r}")
        if not (_real(mu0) and np.isfinite(mu0) and mu0 > 0):
            raise LoadError(f"mu0 must be a positive number (fields.MU0 in SI), got {mu0!r}")
        self.mesh = mesh
        self.mu0 = float(mu0)
        self.h = float(h)
        try:
            el = mesh.elements(elements)             # ids once each, or a mask (MeshError otherwise)
        except MeshError as exc:
            raise LoadError(f"magnetised elements: {exc}") from None
        self.elements = el
        quads = mesh.quads[el]                                       # (m,4)
        N, dN = shape_functions()                                     # (q,4), (q,2,4)
        X = mesh.X[quads]                                             # (m,4,3)
        j0, _ = curved_area(surface_jacobian(X, dN), j0, "magnetisation")   # (m,q)
        Brq = self._at_gauss(Br, N, X, quads)                         # (m,q,3) lab
        if not np.all(np.isfinite(Brq)):
            raise LoadError("magnetisation Br has non-finite values")
        self.br_max = float(np.linalg.norm(Brq, axis=2).max()) if Brq.size else 0.0    # [T]
        lab = np.einsum("qi,mq,mqk->mik", N, j0, Brq)                 # int N_i Br dA, (m,4,3)
        n = mesh.n_nodes
        mom = np.stack([np.bincount(quads.ravel(), weights=lab[..., k].ravel(), minlength=n)
                        for k in range(3)], -1)                       # lab, (n,3)
        area = np.bincount(quads.ravel(), weights=np.einsum("qi,mq->mi", N, j0).ravel(), minlength=n)
        R0 = mesh.g0[:, :3, :3]
        body = np.einsum("nji,nj->ni", R0, mom) * (self.h / self.mu0)  # R0^T, [A m^2]
        keep = np.linalg.norm(mom, axis=1) > 0
        self.nodes = np.nonzero(keep)[0]
        self.mu = body[self.nodes]                                    # (k,3) body-frame dipoles
        self.area = area[self.nodes]                                  # nodal reference area share
        self.node_area = area                                         # (n,) of the selection
        self.element_area = np.einsum("qi,mq->mi", N, j0)             # (m,4) int_e N_i dA
        self.total_lab = mom.sum(0) * self.h                          # int Br dV [T m^3]

    def _at_gauss(self, Br, N, X, quads):
        m = len(quads)
        if callable(Br):
            xq = np.einsum("qi,mik->mqk", N, X)
            out = np.asarray(Br(xq.reshape(-1, 3)), float)
            if out.shape != (m * N.shape[0], 3):
                raise LoadError(f"magnetisation function returned shape {out.shape}, expected {(m * N.shape[0], 3)}")
            return out.reshape(m, -1, 3)
        B = br_numbers(Br)
        if B.shape == (3,):
            return np.broadcast_to(B, (m, N.shape[0], 3))
        per = table_kind(B.shape, m, self.mesh.n_nodes, self.Br_per)
        if per == "element":
            return np.broadcast_to(B[:, None, :], (m, N.shape[0], 3))
        return np.einsum("qi,mik->mqk", N, B[quads])

    def current(self, g):
        """Lab dipole moments R_i mu_i (k,3) of the magnetised nodes."""
        return np.einsum("nij,nj->ni", g[self.nodes, :3, :3], self.mu)


class MagneticLoad(Load):
    """Couple and force of the applied field ``field`` on the magnetisation ``mag``.

    Parameters
    ----------
    mag : Magnetisation
        The magnetised material (nodal dipoles).
    field : core_se3.model.Field
        The applied field B^a(x, lam); its ``approximate_hessian`` makes the load's tangent
        approximate.
    name : str, optional
        For reports.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> from core_se3.model.fields import UniformField
    >>> m = mesh.rectangle(2.0, 1.0, 2, 1)
    >>> ld = MagneticLoad(Magnetisation(m, (1.0, 0, 0), h=1.0, mu0=1.0), UniformField((0, 0, 1.0)))
    >>> ld.evaluate(m.g0, 1.0).f[:, 3:].sum(0).round(12).tolist()   # couple h/mu0 Br x Ba, area 2
    [0.0, -2.0, 0.0]
    """

    def __init__(self, mag, field, name="magnetic"):
        if not isinstance(field, Field):
            raise LoadError(f"the applied field must be a core_se3.model.Field, got {type(field).__name__}")
        self.mag = mag
        self.field = field
        self.name = name
        self.approximate_tangent = bool(field.approximate_hessian)
        self.translation_invariant = bool(field.uniform)     # a field that varies in space reads x
        self.conservative = True      # the potential -m . B^a(x, lam) of dipoles turning with the body in a lab field

    def direction_turn(self, g, lam0, lam1, samples=16):
        """The largest angle [rad] the applied field turns through at the magnetised nodes of
        the state g between load factors lam0 and lam1: the path length of the direction of
        ``Field.unscaled`` (a ramp through zero reverses the field without turning it), sampled
        at ``samples`` sub-steps (a whole turn in one step counts 2 pi, not 0); where the field
        vanishes it does not count.

        A sample turns at most pi as measured (the angle between two directions), so a field
        that turns by a whole number of turns between samples would measure 0: the path is
        sampled again at 23/16 of the samples (a coprime count) and then twice as finely until
        two estimates agree to 1 % (or 4096 samples are reached), and the largest estimate is
        returned (sampling can only miss turning).

        Example
        -------
        >>> import numpy as np
        >>> from core_se3 import mesh
        >>> from core_se3.model.fields import UniformField, rotating_direction
        >>> m = mesh.rectangle(2.0, 1.0, 2, 1)
        >>> turn = rotating_direction((0, 1, 0), (0, 0, 1), turns_per_unit=1.0)   # a turn for lam 0 -> 1
        >>> ld = MagneticLoad(Magnetisation(m, (1.0, 0, 0), h=1.0, mu0=1.0),
        ...                   UniformField((0, 0, 1.0), scale=lambda lam: 1.0, direction=turn))
        >>> round(ld.direction_turn(m.g0, 0.0, 0.25), 6), round(ld.direction_turn(m.g0, 0.0, 1.0), 6)
        (1.570796, 6.283185)
        >>> round(ld.direction_turn(m.g0, 0.0, 16.0), 6)                  # 16 turns: one a sample at 16
        100.530965
        """
        x = g[self.mag.nodes, :3, 3]
        best = self._turn(x, lam0, lam1, samples)
        n = max(1, (23 * samples) // 16)
        last = self._turn(x, lam0, lam1, n)
        while abs(last - best) > 0.01 * max(last, best) + 1e-9 and n < 4096:
            best = max(best, last)
            n *= 2
            last = self._turn(x, lam0, lam1, n)
        return max(best, last)

    def _turn(self, x, lam0, lam1, samples):
        """The turn of :meth:`direction_turn` at the points x (k, 3), sampled at ``samples``
        sub-steps."""
        prev = self.field.unscaled(x, lam0)
        total = np.zeros(len(x))
        for t in np.linspace(lam0, lam1, samples + 1)[1:]:
            cur = self.field.unscaled(x, t)
            n = np.linalg.norm(prev, axis=1) * np.linalg.norm(cur, axis=1)
            ok = n > 0
            # the angle by atan2(|a x b|, a . b): exact 0 for equal directions (arccos of a
            # rounded cosine gives 1e-8), so an unturned field measures 0 at every count
            total[ok] += np.arctan2(np.linalg.norm(np.cross(prev[ok], cur[ok]), axis=1),
                                    np.einsum("ki,ki->k", prev[ok], cur[ok]))
            prev = cur
        return float(total.max()) if len(total) else 0.0

    def nodal(self, g, lam):
        """Lab couple and force (k,3) on the magnetised nodes, and their node ids."""
        nodes = self.mag.nodes
        m = self.mag.current(g)
        x = g[nodes, :3, 3]
        with _dipole_nodes(self.field, x, nodes):
            B = self.field.value(x, lam)
            f = None if self.field.uniform else np.einsum("kij,kj->ki", self.field.gradient(x, lam), m)
        c = np.cross(m, B)
        return nodes, c, np.zeros_like(c) if f is None else f

    def evaluate(self, g, lam, tangent=True):
        if not tangent:
            return LoadEvaluation(magnets_force([self], g, lam))
        n = self.mag.mesh.n_nodes
        nodes = self.mag.nodes
        mu = self.mag.mu
        R = g[nodes, :3, :3]
        Rt = np.swapaxes(R, 1, 2)
        x = g[nodes, :3, 3]
        with _dipole_nodes(self.field, x, nodes):
            a = np.einsum("kij,kj->ki", Rt, self.field.value(x, lam))            # R^T B
        Mb = np.cross(mu, a)
        f = np.zeros((n, 6))
        f[nodes, 3:] = Mb                                   # nodes are unique: plain assignment
        blk = np.zeros((len(nodes), 6, 6))
        mhat = lie.hat3(mu)
        blk[:, 3:, 3:] = -mhat @ lie.hat3(a)
        if not self.field.uniform:
            A = Rt @ self.field.gradient(x, lam) @ R                          # body gradient
            Fb = np.einsum("kij,kj->ki", A, mu)
            f[nodes, :3] = Fb
            blk[:, 3:, :3] = -mhat @ A
            blk[:, :3, 3:] = -(lie.hat3(Fb) - A @ mhat)
            Hm = np.einsum("kabl,kb->kal", self.field.hessian(x, lam), np.einsum("kij,kj->ki", R, mu))
            blk[:, :3, :3] = -(Rt @ Hm @ R)
        Kn = np.zeros((n, 6, 6))
        Kn[nodes] = blk
        return LoadEvaluation(f, Kn)

    def compiled(self, pattern):
        """The numba kernel of this load (``kernels.loads.magnetic_load``); the field is
        evaluated by its own methods (a dipole by ``kernels.loads.dipole_field``)."""
        from ..kernels import loads as K
        from .fields import DipoleField
        nodes = np.ascontiguousarray(self.mag.nodes, dtype=np.int64)
        k = len(nodes)
        B, G, H = np.zeros((k, 3)), np.zeros((k, 3, 3)), np.zeros((k, 3, 3, 3))
        fld = self.field

        def add(g, lam, f, data, tangent):
            x = np.ascontiguousarray(g[nodes, :3, 3])
            if isinstance(fld, DipoleField):
                if K.dipole_field(x, fld.m, fld.x0, fld.k, fld.scale_at(lam), B, G, H):
                    raise on_dipole(fld, x, nodes)
            else:
                with _dipole_nodes(fld, x, nodes):                   # a dipole in a superposition
                    B[:] = fld.value(x, lam)
                    if not fld.uniform:
                        G[:] = fld.gradient(x, lam)
                        if tangent:
                            H[:] = fld.hessian(x, lam)
            # the dipoles are read at call time (a design loop may change the magnetisation)
            mu = np.ascontiguousarray(self.mag.mu, dtype=float)
            K.magnetic_load(g, nodes, mu, B, G, H, bool(fld.uniform), f, data, pattern.map, tangent)
        return add

    def output_fields(self, g, lam):
        """Point fields for VTU output (``magnets_output`` of this load alone)."""
        return magnets_output([self], g, lam)


def _real(x):
    """A real number (not a string, a bool or an array)."""
    return not isinstance(x, (str, bytes, bool, np.bool_)) and np.ndim(x) == 0 and np.asarray(x).dtype.kind in "iuf"


def compiled_magnets(loads, pattern):
    """One compiled evaluation of several MagneticLoads (``add(g, lam, f, data, tangent)``, as
    ``MagneticLoad.compiled``): their nodes and dipoles concatenated (grouped by field), each
    distinct field evaluated once at all its loads' nodes, and one call of the kernel
    ``kernels.loads.magnetic_load`` (nodes shared by two loads add up), instead of one field
    evaluation and one kernel call per load.  The sum equals the loads' own evaluations to
    round-off (the order of the additions at shared nodes differs).  The dipoles are read at
    call time (a design loop may change a magnetisation).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Material, Problem, mesh
    >>> from core_se3.model.fields import UniformField
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1.0, 0.3, 0.1))
    >>> B = UniformField((0.0, 0.0, 1.0))
    >>> a = p.add_magnetic((1.0, 0, 0), B, elements=[0], mu0=1.0)
    >>> b = p.add_magnetic((0, 1.0, 0), B, elements=[1], mu0=1.0)
    >>> f = np.zeros((p.mesh.n_nodes, 6))
    >>> compiled_magnets([a, b], p.assembler().pattern())(p.mesh.g0, 1.0, f, np.zeros(0), False)
    >>> bool(np.allclose(f, a.evaluate(p.mesh.g0, 1.0, False).f + b.evaluate(p.mesh.g0, 1.0, False).f))
    True
    """
    from ..kernels import loads as K
    from .fields import DipoleField
    fields = []                                   # distinct fields, in order of first use
    for ld in loads:
        if not any(ld.field is f for f in fields):
            fields.append(ld.field)
    groups = [[ld for ld in loads if ld.field is f] for f in fields]
    loads = [ld for grp in groups for ld in grp]
    nodes = np.ascontiguousarray(np.concatenate([ld.mag.nodes for ld in loads]), dtype=np.int64)
    ends = np.cumsum([0] + [sum(len(ld.mag.nodes) for ld in grp) for grp in groups])
    k = len(nodes)
    B, G, H = np.zeros((k, 3)), np.zeros((k, 3, 3)), np.zeros((k, 3, 3, 3))
    uniform = all(f.uniform for f in fields)      # else the uniform fields' G = H = 0 (exact)

    def add(g, lam, f, data, tangent):
        x = np.ascontiguousarray(g[nodes, :3, 3])
        for fld, lo, hi in zip(fields, ends[:-1], ends[1:]):
            if isinstance(fld, DipoleField):
                if K.dipole_field(x[lo:hi], fld.m, fld.x0, fld.k, fld.scale_at(lam), B[lo:hi], G[lo:hi], H[lo:hi]):
                    raise on_dipole(fld, x[lo:hi], nodes[lo:hi])
                continue
            with _dipole_nodes(fld, x[lo:hi], nodes[lo:hi]):         # a dipole in a superposition
                B[lo:hi] = fld.value(x[lo:hi], lam)
                if not fld.uniform:
                    G[lo:hi] = fld.gradient(x[lo:hi], lam)
                    if tangent:
                        H[lo:hi] = fld.hessian(x[lo:hi], lam)
        mu = np.concatenate([ld.mag.mu for ld in loads]) if len(loads) > 1 else \
            np.ascontiguousarray(loads[0].mag.mu, dtype=float)
        K.magnetic_load(g, nodes, mu, B, G, H, uniform, f, data, pattern.map, tangent)
    return add


def magnets_force(loads, g, lam):
    """The generalised force f (n, 6) of several MagneticLoads at (g, lam), without tangent, in
    one batch (the NumPy backend's residual: ``Problem.external``): their nodes and dipoles
    concatenated, each distinct field evaluated once at its loads' nodes, f_w = mu x R^T B and
    f_v = R^T G R mu (``MagneticLoad.evaluate``) for all at once, summed at shared nodes.  It
    equals the sum of the loads' own evaluations to round-off.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Material, Problem, mesh
    >>> from core_se3.model.fields import UniformField
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1.0, 0.3, 0.1))
    >>> B = UniformField((0.0, 0.0, 1.0))
    >>> a = p.add_magnetic((1.0, 0, 0), B, elements=[0], mu0=1.0)
    >>> b = p.add_magnetic((0, 1.0, 0), B, elements=[1], mu0=1.0)
    >>> f = magnets_force([a, b], p.mesh.g0, 1.0)
    >>> bool(np.allclose(f, a.evaluate(p.mesh.g0, 1.0, False).f + b.evaluate(p.mesh.g0, 1.0, False).f))
    True
    """
    fields, groups = [], []
    for ld in loads:
        for i, f in enumerate(fields):
            if ld.field is f:
                groups[i].append(ld)
                break
        else:
            fields.append(ld.field)
            groups.append([ld])
    n = loads[0].mag.mesh.n_nodes
    out = np.zeros((n, 6))
    for fld, grp in zip(fields, groups):
        nodes = np.concatenate([ld.mag.nodes for ld in grp])
        mu = np.concatenate([ld.mag.mu for ld in grp])
        R = g[nodes, :3, :3]
        Rt = np.swapaxes(R, 1, 2)
        x = g[nodes, :3, 3]
        with _dipole_nodes(fld, x, nodes):
            B, G = fld.value(x, lam), None if fld.uniform else fld.gradient(x, lam)
        a = np.einsum("kij,kj->ki", Rt, B)                                  # R^T B
        _add_at(out, 3, nodes, np.cross(mu, a), len(grp) == 1)
        if G is not None:
            _add_at(out, 0, nodes, np.einsum("kij,kj->ki", Rt @ G @ R, mu), len(grp) == 1)
    return out


def magnets_output(loads, g, lam):
    """Point fields of several MagneticLoads for VTU output (lab components): B^r_t [T] and the
    magnetic couple and force per unit reference area [N m/m^2, N/m^2] at every node, each the
    sum over the loads of its nodal integral (int N_i B^r_t dA, the nodal couple and force)
    divided by the node's share of the reference area of the magnetised elements (their union:
    two magnets of adjacent regions share the nodes between them, and a node's value is the
    area-weighted mean, not the sum of two means); 0 at nodes without magnetised elements.
    B^r is divided by the sum over the distinct fields of each field's magnetised area: one
    material put in two fields (a magnet per field on one region, ``examples/walker.toml``) shows
    its B^r, not twice it (before: 0.156 T for the walker's 0.078), and two magnets of one field
    on common elements add (superposed magnetisations).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Material, Problem, mesh
    >>> from core_se3.model.fields import UniformField
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1.0, 0.3, 0.1))
    >>> B = UniformField((0.0, 0.0, 1.0))
    >>> a = p.add_magnetic((1.0, 0, 0), B, elements=[0], mu0=1.0)
    >>> b = p.add_magnetic((1.0, 0, 0), B, elements=[1], mu0=1.0)
    >>> magnets_output([a, b], p.mesh.g0, 1.0)["magnetisation_Br"][:3, 0].tolist()   # the middle node too
    [1.0, 1.0, 1.0]
    """
    n = loads[0].mag.mesh.n_nodes
    area = _union_area(loads)
    Br, C, F = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
    fields = []                                   # distinct fields, in order of first use
    for ld in loads:
        if not any(ld.field is f for f in fields):
            fields.append(ld.field)
        nodes, c, fv = ld.nodal(g, lam)
        Br[nodes] += ld.mag.current(g) * (ld.mag.mu0 / ld.mag.h)        # int N_i B^r_t dA
        C[nodes] += c
        F[nodes] += fv
    # B^r: the magnets of each field over that field's magnetised area, so that a material put
    # in two fields (two magnets of one region, as examples/walker.toml) counts once
    area_br = sum(_union_area([ld for ld in loads if ld.field is f]) for f in fields)
    w = np.where(area > 0, area, 1.0)[:, None]
    return {"magnetisation_Br": Br / np.where(area_br > 0, area_br, 1.0)[:, None],
            "magnetic_couple": C / w, "magnetic_force": F / w}


def _union_area(loads):
    """(n,) the nodes' shares int N_i dA of the union of the loads' magnetised elements (an
    element of two loads counted once)."""
    mesh = loads[0].mag.mesh
    els = np.concatenate([ld.mag.elements for ld in loads])
    shares = np.concatenate([ld.mag.element_area for ld in loads])
    _, first = np.unique(els, return_index=True)              # every magnetised element once
    return np.bincount(mesh.quads[els[first]].ravel(), weights=shares[first].ravel(), minlength=mesh.n_nodes)


DIPOLE_RESOLUTION = 10.0
"""The distance from a dipole source to the magnetised material, in element sizes, below which
the nodal quadrature of its loads is reported (``dipole_resolution``): the error is about
(size / distance)^2, 1 % at 10 sizes.  Measured on a clamped strip 1 x 0.1 with a dipole 0.05
above its tip (0.07 from the nearest nodes): 12 % at 2.8 sizes (40 x 4 elements), 2.3 % at 5.7
(80 x 8); refined along the strip only (160 x 1, the width 0.1 one element) the tip deflection
converged to 3.89e-5 against 2.12e-5 (160 x 16): 83 % off."""


def on_dipole(field, x, nodes):
    """The LoadError of the first of ``nodes`` whose position (its row of x (k, 3)) is that of a
    point dipole of ``field`` (``dipole_sources``), naming the node, its position and the
    dipole's (before: 'a point lies on the dipole', no node, no position); a plain one if none
    is (the caller's field said so).

    Example
    -------
    >>> from core_se3.model.fields import DipoleField
    >>> str(on_dipole(DipoleField((0, 0, 1.0), (1.0, 0, 0)), np.array([[0.0, 0, 0], [1.0, 0, 0]]), [3, 7]))[:38]
    'magnetised node 7 (at [1.0, 0.0, 0.0])'
    """
    for d in dipole_sources(field):
        r = x - d.x0
        hit = np.nonzero(np.einsum("ki,ki->k", r, r) == 0)[0]
        if len(hit):
            k = int(hit[0])
            return LoadError(f"magnetised node {int(nodes[k])} (at {x[k].tolist()}) lies on the point dipole at "
                             f"x0 = {d.x0.tolist()}: the field is singular there; move the dipole off the body")
    return LoadError("a point lies on a dipole of the field: the field is singular there")


@contextmanager
def _dipole_nodes(field, x, nodes):
    """A LoadError of a point dipole of the field at the points x (the positions of ``nodes``)
    re-raised naming the node (:func:`on_dipole`)."""
    try:
        yield
    except LoadError as exc:
        if "lies on the dipole" not in str(exc):
            raise
        raise on_dipole(field, x, nodes) from exc


def dipole_sources(field):
    """The DipoleFields in ``field`` (itself, or the parts of a Superposition, nested ones too).

    Example
    -------
    >>> from core_se3.model.fields import DipoleField, Superposition, UniformField
    >>> d = DipoleField((0, 0, 1.0), (0, 0, 1.0))
    >>> [f is d for f in dipole_sources(Superposition(UniformField((0, 0, 1.0)), d))], dipole_sources(UniformField((0, 0, 1.0)))
    ([True], [])
    """
    from .fields import DipoleField, Superposition
    if isinstance(field, DipoleField):
        return [field]
    if isinstance(field, Superposition):
        return [d for f in field.fields for d in dipole_sources(f)]
    return []


def dipole_resolution(loads, g, lam):
    """The smallest distance from a point dipole of the loads' fields (at a non-zero scale at
    lam) to a magnetised node of the state g, in sizes of the node's largest magnetised element
    (its longest reference edge), with that node and the dipole's position; None without
    dipoles.

    Parameters
    ----------
    loads : sequence of MagneticLoad
        The magnets.
    g : (n, 4, 4) ndarray
        The state.
    lam : float
        The load factor (a dipole scaled to zero does not count).

    Returns
    -------
    tuple or None
        (distance / size, node id, dipole position x0).

    Example
    -------
    >>> from core_se3 import mesh
    >>> from core_se3.model.fields import DipoleField
    >>> m = mesh.rectangle(1.0, 0.1, 10, 1)
    >>> ld = MagneticLoad(Magnetisation(m, (1.0, 0, 0), h=0.01, mu0=1.0), DipoleField((0, 0, 1.0), (1.0, -0.05, 0.3)))
    >>> ratio, node, x0 = dipole_resolution([ld], m.g0, 1.0)
    >>> round(ratio, 6), node                               # 0.3 from the tip, elements 0.1 wide
    (3.0, 10)
    """
    worst = None
    for ld in loads:
        dips = [d for d in dipole_sources(ld.field) if d.scale_at(lam) != 0.0]
        if not dips:
            continue
        mesh = ld.mag.mesh
        X = mesh.X[mesh.quads[ld.mag.elements]]                            # (m, 4, 3)
        edge = np.linalg.norm(X - np.roll(X, -1, axis=1), axis=2).max(1)   # longest edge
        size = np.zeros(mesh.n_nodes)
        np.maximum.at(size, mesh.quads[ld.mag.elements], edge[:, None])
        x = g[ld.mag.nodes, :3, 3]
        for d in dips:
            ratio = np.linalg.norm(x - d.x0, axis=1) / size[ld.mag.nodes]
            k = int(np.argmin(ratio))
            if worst is None or ratio[k] < worst[0]:
                worst = (float(ratio[k]), int(ld.mag.nodes[k]), d.x0)
    return worst


def _add_at(out, col, nodes, v, unique):
    """out[nodes, col:col + 3] += v (k, 3), repeated nodes summed (by bincount unless unique)."""
    if unique:
        out[nodes, col:col + 3] += v
        return
    for c in range(3):
        out[:, col + c] += np.bincount(nodes, weights=v[:, c], minlength=len(out))
