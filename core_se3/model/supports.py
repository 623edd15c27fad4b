"""Supports: prescribed body-frame dofs (clamp, fix, prescribed motions) and supports on lab
directions written as penalty springs (e.g. a rigid diaphragm).

``Problem.clamp``/``Problem.fix``/``Problem.rotate_edge`` hold body-frame dofs (a
:class:`Prescribed` each, optionally following a target motion of the load factor).
``Problem.fix`` fixes body-frame dofs, which stay lab-fixed only while the node's frame does
not rotate about an axis that tilts the fixed direction.  A rigid diaphragm (radial and
circumferential displacement zero, axial displacement and rotations free) is such a case: the
end section bends about the circumferential axis.  ``LabSpring`` adds, at each selected node,
the force F = -k P (phi - X) with P the projector on the lab directions ``dirs``; its
generalised (body-frame) force is f = (R^T F, 0) and the load stiffness along g <- g exp(eta)

    -df/deta = [[k R^T P R, -hat(R^T F)], [0, 0]].

It does not depend on the load factor (so continuation's load direction q is unaffected).  The
constraint error is |F|/k: choose k a few decades above the element stiffness (E h).

``LabTiltSpring`` holds the normal d3 = R e3 of each selected node normal to a lab direction t
(c = d3 . t = 0), by the energy 1/2 k_r c^2.  For the rigid diaphragm (t = the circumferential
tangent) it is the classical theta_axis = 0 of MacNeal & Harder's pinched cylinder: the end
ring does not move in its plane, so the normal does not tilt circumferentially (Kirchhoff:
dw/ds = 0 along the ring), while it bends freely about t and drills about d3.  With
a = R^T t and b = e3 x a the body moment is m = -k_r c b and its stiffness along
g <- g exp(eta) is  -dm/domega = k_r (b b^T + c (a e3^T - c I)).

``RotationComponentSpring`` holds the component along a lab axis a of the node's *total*
rotation vector psi = log(R R0^T) (c = a . psi = 0), by the energy 1/2 k_r c^2.  This is how a
code with total-rotation-vector dofs (Abaqus' UR1..UR3 in a large-rotation step) applies
"theta_y = 0": the holonomic constraint on the rotation from the reference frame, not on its
increments.  With phi = log(R0^T R) = R0^T psi and b = R0^T a, c = b . phi, and along
g <- g exp(eta), phi(eta) = phi + J_r^-1(phi) eta + O(eta^2) (J_r the right Jacobian,
``lie.dexp_so3``), so the body moment is m = -k_r c J_r^-T b and

    -dm/deta = k_r [ (J_r^-T b)(J_r^-T b)^T + c D_phi(J_r^-T(phi) b) J_r^-1(phi) ],

the derivative D_phi taken by complex step of the closed form (exact to round-off).  psi is
the principal log, so the node's total rotation must stay below pi (the cut of log): beyond
MAX_TOTAL_ROTATION the spring raises ElementTooDistortedError, which the solvers treat as a
rejected step (cut back), and which names the limit if it persists.
"""
from __future__ import annotations

import numpy as np

from .. import lie
from ..errors import ElementTooDistortedError, SingularSystemError, SupportError
from .base import Load, LoadEvaluation, mesh_ids
from .prescribed import (DOF_NAMES, Prescribed, apply_prescribed, check_conflict, fixed_dofs,  # noqa: F401
                         prescribed_rotation, rigid_motion, rigid_rotation, select_nodes, support_kind)

__all__ = ["apply_prescribed", "prescribed_rotation", "Prescribed", "LabSpring", "LabTiltSpring", "RotationComponentSpring",
           "MAX_TOTAL_ROTATION", "check_rigid_motions", "fixed_dofs", "rigid_rotation", "select_nodes",
           "check_conflict", "support_kind", "DOF_NAMES", "rigid_motion", "mesh_parts", "node_directions",
           "lab_direction_sets", "DEPENDENT_DIRECTIONS"]


# The residual's floor is 1e3 eps x (round-off scale) (solvers.convergence: the element's scale
# sums many cancelling terms); a spring's force has the round-off eps k |P x| of one product, so
# its scale enters at 1e-2 of k |P X|: a floor ten times the spring's round-off.
SPRING_ROUND_OFF = 1e-2


def node_directions(v, k, what):
    """(k, 3) unit lab directions of ``v``, one for all k nodes ((3,) or (1, 3)) or one per node
    ((k, 3)), each row normalised; a SupportError naming ``what`` for another shape or a zero or
    non-finite row.  The compiled springs read row i for node i: a (1, 3) row kept as it was
    made them read past its end (a tilt spring on two nodes lost its stiffness at the second,
    1.4 % off the NumPy backend's deflection), and a row of length 2 quadrupled the penalty.

    Example
    -------
    >>> node_directions([[0.0, 2.0, 0.0]], 2, "t").tolist()
    [[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
    """
    v = np.asarray(v, float)
    if v.shape not in ((3,), (1, 3), (k, 3)):
        raise SupportError(f"{what} must be one lab direction (3,) for all {k} node(s) or one per node ({k}, 3), "
                           f"got shape {v.shape}")
    v = np.broadcast_to(v, (k, 3))
    norm = np.linalg.norm(v, axis=1)
    if not np.all(np.isfinite(norm)) or np.any(norm == 0):
        raise SupportError(f"{what} must be non-zero finite lab directions, got {v[~(np.isfinite(norm) & (norm > 0))][0].tolist()}")
    return np.ascontiguousarray(v / norm[:, None])


#: the smallest singular value of a set of unit lab directions below which it is dependent
DEPENDENT_DIRECTIONS = 1e-6


def lab_direction_sets(dirs, k):
    """(k, q, 3) unit lab directions of ``LabSpring``'s ``dirs``: a set (q, 3) or (1, q, 3) held
    at every one of k nodes ((3,): one direction), or a set per node (k, q, 3); a SupportError
    for (q, 3) with q == k > 1 and rows not all equal (a set at every node or one direction per
    node? (1, q, 3) or (k, 1, 3) says which), for another shape, for a set of more than 3 rows (q > 3 directions cannot be independent in 3-D: a user
    meaning one direction per node gives (k, 1, 3)), for rows that are linearly dependent
    (smallest singular value below ``DEPENDENT_DIRECTIONS``: the spring would hold their common
    direction twice), and for a zero or non-finite row.

    Example
    -------
    >>> lab_direction_sets([[0.0, 0.0, 2.0]], 2).tolist()
    [[[0.0, 0.0, 1.0]], [[0.0, 0.0, 1.0]]]
    >>> lab_direction_sets([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]], 4)     # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.SupportError: the lab support's dirs: 4 rows (shape (4, 3)) cannot be ...
    """
    D = np.asarray(dirs, float)
    D = D[None] if D.ndim == 1 else D
    if D.ndim == 2 and D.shape[-1] == 3 and 1 < len(D) == k <= 3 and np.ptp(D, axis=0).max() > 0:
        raise SupportError(f"the lab support's dirs {D.tolist()}: {k} rows for {k} selected nodes reads two ways, a "
                           f"set of {k} directions held at every node or one direction per node; say which: shape "
                           f"({k}, 1, 3) for one direction per node, (1, {k}, 3) for the set held at every node")
    if D.ndim == 3 and D.shape[0] == 1:               # (1, q, 3): the set held at every node, explicitly
        D = D[0]
    if D.ndim == 2 and D.shape[-1] == 3 and len(D) > 3:
        raise SupportError(f"the lab support's dirs: {len(D)} rows (shape {D.shape}) cannot be independent lab "
                           f"directions held at every node (at most 3 in 3-D); for directions per node give shape "
                           f"({k}, q, 3) (one direction per node: ({k}, 1, 3))")
    if D.ndim == 2:
        D = np.broadcast_to(D, (k,) + D.shape)
    if D.ndim != 3 or D.shape[0] != k or D.shape[2] != 3 or not 1 <= D.shape[1] <= 3:
        raise SupportError(f"the lab support's dirs must be (3,) or (q, 3) with q <= 3 (held at every node), or "
                           f"({k}, q, 3) (a set per node, for the {k} selected node(s)), got shape {np.shape(dirs)}")
    norm = np.linalg.norm(D, axis=2)
    bad = ~(np.isfinite(norm) & (norm > 0))
    if bad.any():
        raise SupportError(f"the lab support's dirs must be non-zero finite lab directions, got "
                           f"{D[bad][0].tolist()}")
    D = D / norm[..., None]
    smallest = np.linalg.svd(D, compute_uv=False)[:, -1]
    if np.any(smallest < DEPENDENT_DIRECTIONS):
        i = int(np.argmin(smallest))
        raise SupportError(f"the lab support's dirs {np.round(D[i], 6).tolist()} (at selected node {i}) are linearly "
                           f"dependent: the spring would hold their common direction twice (its stiffness "
                           f"doubled); give independent directions (for one direction per node: shape ({k}, 1, 3))")
    return np.ascontiguousarray(D)


class _Spring(Load):
    """A penalty support written as a load: it does not scale with the load factor, and its
    forces are support reactions (``support_force``), not applied loads, in the results, where
    ``support_name`` (None: ``loads[j]``, its index in ``Problem.loads``) names its own
    (``StepResult.support_reactions``)."""
    scales_with_load_factor = False
    support_force = True
    support_name = None
    conservative = True             # (a linear spring's potential)
    whole_nodes = None              # a rank's part (parallel.localize): the whole mesh's ids of ``nodes``

    @property
    def node_ids(self):
        """The mesh ids of the nodes, in messages (``nodes``; a rank's part names the whole mesh's)."""
        return self.nodes if self.whole_nodes is None else self.whole_nodes

    def _scatter(self, n, fb, blk, tangent):
        f = np.zeros((n, 6))
        np.add.at(f, self.nodes, fb)
        if not tangent:
            return LoadEvaluation(f)
        Kn = np.zeros((n, 6, 6))
        np.add.at(Kn, self.nodes, blk)
        return LoadEvaluation(f, Kn)


class LabSpring(_Spring):
    """Penalty on the lab displacement components ``dirs`` (the same set at every node, or a set
    per node).

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The mesh.
    nodes : array_like of int
        The supported nodes (k,).
    dirs : (3,), (q, 3) or (k, q, 3) array_like
        Lab directions: (q, 3) is a set of q <= 3 directions held at *every* node ((3,): one);
        (k, q, 3) is a set per node (one direction per node: (k, 1, 3)).  Each row is normalised;
        P is the projector on the span of a node's rows.  A SupportError for another shape, for
        more than 3 rows in a set (they cannot be independent: per-node directions are (k, q, 3)),
        and for rows that are linearly dependent (they would hold a direction twice, doubling
        its spring), or zero or not finite.
    k : float
        Spring stiffness [force/length] (module docstring: a few decades above E h).
    name : str, optional
        For reports.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(1.0, 1.0, 1, 1)
    >>> g = m.g0.copy(); g[0, :3, 3] += (0.1, 0.2, 0.3)
    >>> LabSpring(m, [0], [[0, 0, 1.0]], k=10.0).evaluate(g, 1.0).f[0, :3].tolist()
    [0.0, 0.0, -3.0]
    """

    holds_translations = True       # its nodes' edges are not free (Problem.free_edge_elements)

    def __init__(self, mesh, nodes, dirs, k, name="lab support"):
        self.n = mesh.n_nodes
        self.nodes = mesh_ids(nodes, self.n, f"support {name!r}: nodes", SupportError)
        self.D = lab_direction_sets(dirs, len(self.nodes))          # (k, q, 3) unit directions
        G = np.einsum("nai,nbi->nab", self.D, self.D)                # independent rows: G invertible
        self.P = np.einsum("nai,nab,nbj->nij", self.D, np.linalg.inv(G), self.D)   # (k, 3, 3) projectors
        self.X0 = mesh.X[self.nodes].copy()
        self.k = spring_stiffness(k, "k", name)
        self.name = name

    def restraint(self):
        """(nodes, lab directions (k, q, 3)) that this spring holds (for the support check)."""
        return self.nodes, self.D

    def round_off_scale(self, ell):
        """SPRING_ROUND_OFF k |P X| over the nodes: the held components of the positions carry
        round-off eps |P x| (their increments add to them), which the spring multiplies by k (a
        stiff spring far from the origin: 1e4 E h on a unit strip stalled at a residual of 4e-10 =
        eps k |P X| / |f|, above rtol 1e-10).  Nodes on the plane P X = 0 add nothing."""
        if getattr(self, "_held_norm", None) is None:        # |P X| is fixed: once, not per evaluation
            self._held_norm = float(np.linalg.norm(np.einsum("nij,nj->ni", self.P, self.X0)))
        return SPRING_ROUND_OFF * self.k * self._held_norm

    def compiled(self, pattern):
        """The numba kernel of this spring (``kernels.loads.lab_spring``)."""
        from ..kernels.loads import lab_spring
        nodes, P, X0 = (np.ascontiguousarray(a) for a in (self.nodes, self.P, self.X0))

        def add(g, lam, f, data, tangent):
            lab_spring(g, nodes, P, X0, self.k, f, data, pattern.map, tangent)
        return add

    def evaluate(self, g, lam, tangent=True):
        R = g[self.nodes, :3, :3]
        F = -self.k * np.einsum("nij,nj->ni", self.P, g[self.nodes, :3, 3] - self.X0)
        Fb = np.einsum("nji,nj->ni", R, F)
        blk = None
        if tangent:
            blk = np.zeros((len(self.nodes), 6, 6))
            blk[:, :3, :3] = self.k * np.einsum("nji,njk,nkl->nil", R, self.P, R)
            blk[:, :3, 3:] = -lie.hat3(Fb)
        return self._scatter(self.n, np.concatenate([Fb, np.zeros_like(Fb)], 1), blk, tangent)


class LabTiltSpring(_Spring):
    """Penalty c = d3 . t = 0 (the normal stays normal to the lab direction t, per node).

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The mesh.
    nodes : array_like of int
        The supported nodes (k,).
    t : (3,) or (k, 3) array_like
        Lab direction(s) the normal must stay normal to (normalised: ``node_directions``).
    k_rot : float
        Rotational stiffness [force x length] of the energy 1/2 k_rot c^2; ``name``: for reports.

    Example
    -------
    >>> from core_se3 import mesh, lie
    >>> m = mesh.rectangle(1.0, 1.0, 1, 1)
    >>> g = m.g0.copy(); g[0, :3, :3] = lie.exp_so3([0.1, 0.0, 0.0])   # tilted about x by 0.1
    >>> sp = LabTiltSpring(m, [0], (0.0, 1.0, 0.0), k_rot=10.0)
    >>> sp.tilt(g).round(6).tolist(), sp.evaluate(g, 1.0).f[0, 3:].round(6).tolist()   # c = -sin 0.1
    ([-0.099833], [-0.993347, 0.0, 0.0])
    """

    def __init__(self, mesh, nodes, t, k_rot, name="lab tilt support"):
        self.n = mesh.n_nodes
        self.nodes = mesh_ids(nodes, self.n, f"support {name!r}: nodes", SupportError)
        self.t = node_directions(t, len(self.nodes), "the lab tilt support's direction t")
        self.k = spring_stiffness(k_rot, "k_rot", name)
        self.name = name

    def round_off_scale(self, ell):
        """SPRING_ROUND_OFF k_rot sqrt(k) / ell: the held component (of order 1 rad at most) carries
        round-off eps, which the spring multiplies by k_rot (a moment; / ell: as a force)."""
        return SPRING_ROUND_OFF * self.k * np.sqrt(len(self.nodes)) / ell

    def compiled(self, pattern):
        """The numba kernel of this spring (``kernels.loads.lab_tilt_spring``)."""
        from ..kernels.loads import lab_tilt_spring
        nodes, t = np.ascontiguousarray(self.nodes), np.ascontiguousarray(self.t, dtype=float)

        def add(g, lam, f, data, tangent):
            lab_tilt_spring(g, nodes, t, self.k, f, data, pattern.map, tangent)
        return add

    def tilt(self, g):
        """c = d3 . t at the selected nodes (the constraint error, a sine)."""
        return np.einsum("ni,ni->n", g[self.nodes, :3, 2], self.t)

    def evaluate(self, g, lam, tangent=True):
        R = g[self.nodes, :3, :3]
        a = np.einsum("nji,nj->ni", R, self.t)                        # R^T t
        c = a[:, 2]
        e3 = np.array([0.0, 0.0, 1.0])
        b = np.cross(e3, a)
        blk = None
        if tangent:
            blk = np.zeros((len(self.nodes), 6, 6))
            blk[:, 3:, 3:] = self.k * (np.einsum("ni,nj->nij", b, b)
                                       + c[:, None, None] * (np.einsum("ni,j->nij", a, e3)
                                                             - c[:, None, None] * np.eye(3)))
        return self._scatter(self.n, np.concatenate([np.zeros_like(b), -self.k * c[:, None] * b], 1),
                             blk, tangent)


MAX_TOTAL_ROTATION = 0.95 * np.pi   # log's cut at pi is too close beyond this


class RotationComponentSpring(_Spring):
    """Penalty c = a . log(R R0^T) = 0 (total rotation vector's lab component a, per node).

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The mesh.
    nodes : array_like of int
        The supported nodes (k,).
    a : (3,) or (k, 3) array_like
        Lab axis (or one per node) of the held component (normalised: ``node_directions``).
    k_rot : float
        Rotational stiffness [force x length/rad^2]; ``name``: for reports.

    Example
    -------
    >>> from core_se3 import mesh, lie
    >>> m = mesh.rectangle(1.0, 1.0, 1, 1)
    >>> g = m.g0.copy(); g[0, :3, :3] = lie.exp_so3([0.0, 0.0, 0.2])   # node 0 turned about z
    >>> sp = RotationComponentSpring(m, [0], (0.0, 0.0, 1.0), k_rot=10.0)
    >>> sp.component(g).round(12).tolist(), (sp.evaluate(g, 1.0).f[0, 3:].round(12) + 0.0).tolist()
    ([0.2], [0.0, 0.0, -2.0])
    """

    def __init__(self, mesh, nodes, a, k_rot, name="rotation component support"):
        self.n = mesh.n_nodes
        self.nodes = mesh_ids(nodes, self.n, f"support {name!r}: nodes", SupportError)
        a = node_directions(a, len(self.nodes), "the rotation component support's axis a")
        self.R0 = mesh.g0[self.nodes, :3, :3].copy()
        self.b = np.einsum("nji,nj->ni", self.R0, a)                   # R0^T a (body frame)
        self.k = spring_stiffness(k_rot, "k_rot", name)
        self.name = name

    def round_off_scale(self, ell):
        """SPRING_ROUND_OFF k_rot sqrt(k) / ell: the held component (of order 1 rad at most) carries
        round-off eps, which the spring multiplies by k_rot (a moment; / ell: as a force)."""
        return SPRING_ROUND_OFF * self.k * np.sqrt(len(self.nodes)) / ell

    def compiled(self, pattern):
        """The numba kernel of this spring (``kernels.loads.rotation_component_spring``)."""
        from ..kernels.loads import rotation_component_spring
        nodes, R0, b = (np.ascontiguousarray(a) for a in (self.nodes, self.R0, self.b))

        def add(g, lam, f, data, tangent):
            flag, t = rotation_component_spring(g, nodes, R0, b, self.k, f, data, pattern.map, tangent)
            if flag:
                self.evaluate(g, lam, False)          # raises the NumPy path's named error
        return add

    def phi(self, g):
        """Body total rotation vectors log(R0^T R) at the selected nodes."""
        return lie.log_so3(np.einsum("nji,njk->nik", self.R0, g[self.nodes, :3, :3]))

    def component(self, g):
        """c = a . psi at the selected nodes (the constraint error, radians)."""
        return np.einsum("ni,ni->n", self.b, self.phi(g))

    def evaluate(self, g, lam, tangent=True, h=1e-30):
        phi = self.phi(g)
        turn = np.linalg.norm(phi, axis=-1)
        if np.any(turn > MAX_TOTAL_ROTATION):
            k = int(np.argmax(turn))
            raise ElementTooDistortedError(
                f"{self.name}: node {int(self.node_ids[k])} has turned by {turn[k]:.3f} rad from its "
                f"reference frame (> {MAX_TOTAL_ROTATION:.3f}); a held component of the total rotation "
                "vector is defined below pi only")
        c = np.einsum("ni,ni->n", self.b, phi)
        Jinv = lie.dexp_inv_so3(phi)                                   # J_r^-1(phi)
        gv = np.einsum("nji,nj->ni", Jinv, self.b)                     # J_r^-T b = dc/deta
        pc = np.repeat(phi[None].astype(complex), 3, axis=0)          # (3, k, 3)
        pc[np.arange(3), :, np.arange(3)] += 1j * h
        dg = np.einsum("mnji,nj->mni", lie.dexp_inv_so3(pc), self.b).imag / h   # (3, k, 3)
        D = np.transpose(dg, (1, 2, 0))                                # D[n, i, m] = d gv_i/d phi_m
        blk = np.zeros((len(self.nodes), 6, 6))
        blk[:, 3:, 3:] = self.k * (np.einsum("ni,nj->nij", gv, gv)
                                   + c[:, None, None] * np.einsum("nim,nmj->nij", D, Jinv))
        return self._scatter(self.n, np.concatenate([np.zeros_like(gv), -self.k * c[:, None] * gv], 1),
                             blk, tangent)


def spring_stiffness(k, what, name):
    """A spring support's stiffness as a float: a positive finite real number, else a SupportError
    naming it (a negative k pushed the nodes away from the held value -- a converged answer of a
    destabilised shell, silently --, NaN gave NaN residuals, "1" was read as 1.0)."""
    if isinstance(k, (str, bytes, bool, np.bool_)) or np.ndim(k) != 0 or np.asarray(k).dtype.kind not in "iuf" \
            or not (np.isfinite(k) and k > 0):
        raise SupportError(f"{name}: the stiffness {what} must be a positive number (the penalty that holds the "
                           f"support), got {k!r}")
    return float(k)


def mesh_parts(mesh):
    """The connected parts of a mesh (quads joined through shared nodes): (number of parts,
    (n,) part of every node, (m,) part of every element), parts numbered by their first node.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3.mesh import Mesh, rectangle
    >>> a = rectangle(1.0, 1.0, 1, 1); g = np.concatenate([a.g0, a.g0]); g[4:, 0, 3] += 3.0
    >>> k, nodes, elements = mesh_parts(Mesh(g, np.concatenate([a.quads, a.quads + 4])))
    >>> k, nodes.tolist(), elements.tolist()
    (2, [0, 0, 0, 0, 1, 1, 1, 1], [0, 1])
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    q = mesh.quads
    a, b = q[:, [0, 1, 2, 3]].ravel(), q[:, [1, 2, 3, 0]].ravel()
    adj = coo_matrix((np.ones(len(a)), (a, b)), shape=(mesh.n_nodes, mesh.n_nodes))
    k, labels = connected_components(adj, directed=False)
    return k, labels, labels[q[:, 0]]


def _describe_part(mesh, i, nodes, elements):
    ids = np.nonzero(elements == i)[0]
    x = mesh.X[nodes == i]
    return (f"part {i + 1} ({len(ids)} elements, ids {ids[0]}..{ids[-1]}, nodes "
            f"{np.nonzero(nodes == i)[0][:4].tolist()}..., between {np.round(x.min(0), 4).tolist()} and "
            f"{np.round(x.max(0), 4).tolist()})")


def _check_orphans(mesh, fixed):
    """SingularSystemError for nodes of no element that the supports do not hold in full: nothing
    gives them stiffness (a Mesh built by hand with a node no quad lists; the readers drop such
    nodes).  Before, the part check failed on them with a bare IndexError."""
    used = np.zeros(mesh.n_nodes, bool)
    used[mesh.quads.ravel()] = True
    loose = np.flatnonzero(~used & ~fixed.all(axis=1))
    if len(loose):
        raise SingularSystemError(
            f"node(s) {loose[:5].tolist()}{' ...' if len(loose) > 5 else ''} ({len(loose)} in all, the first at "
            f"{np.round(mesh.X[loose[0]], 4).tolist()}) belong to no element: nothing holds them and the tangent is "
            "singular; remove them from the mesh's g0 (renumbering the quads), or clamp them")


def check_rigid_motions(problem, g):
    """Raise SingularSystemError if the supports leave a rigid-body motion free (SupportError
    if they leave nothing free), part by part of a mesh of disconnected parts (naming the part).

    A superposed rigid motion h = exp(xi) moves every node by the body-frame increment
    eta_i = Ad_{g_i^-1} xi; the supports restrain all six rigid motions iff the fixed
    components of these increments (and the lab directions held by loads, e.g. springs)
    have rank 6 (checked by SVD, unit-scaled).  Each connected part of the mesh moves on its
    own, so the check is made for each.
    """
    fixed = problem.constraint_mask()
    if fixed.all():
        raise SupportError(f"the supports hold every degree of freedom of all {len(fixed)} nodes: there "
                           "is nothing to solve; select fewer nodes (e.g. clamp one edge)")
    _check_orphans(problem.mesh, fixed)
    k, nodes, elements = mesh_parts(problem.mesh)
    for i in range(k):
        what = _free_motion(problem, g, fixed, nodes == i)
        if what is None:
            continue
        if k == 1 and what.startswith("no supports"):
            raise SingularSystemError("no supports: the shell can move as a rigid body; clamp or fix some nodes")
        if k == 1:
            raise SingularSystemError("the supports leave a rigid-body motion free (" + what
                                      + "): the tangent is singular; add supports")
        raise SingularSystemError(
            f"the mesh has {k} disconnected parts, and the supports leave a rigid-body motion of "
            f"{_describe_part(problem.mesh, i, nodes, elements)} free ({what}): support that part too, or join "
            "it to the rest (shared nodes)")


def _free_motion(problem, g, fixed, part):
    """The rigid motion of the nodes ``part`` (mask) that the supports leave free, described
    ('rotation about ... through ...', 'translation along ...'), or None."""
    ell = problem.length_scale
    c = g[part, :3, 3].mean(0)
    # rigid motions about the part's centroid: Ad of (h g)^-1, h the translation by -c, the
    # positions differenced first (inv(g) @ inv(h) lost eps |x| of the lever arms: a pinned
    # edge's free rotation went unseen 1e8 from the origin)
    hg = np.array(g, float)
    hg[:, :3, 3] -= c
    modes = lie.Ad(lie.inv(hg))                     # (n, 6, 6): column k = mode k at node i
    # dimensionless: translations of the modes by ell, nodal translations over ell (rotations
    # as they are), so that every entry is O(1) whatever the mesh's size (a lever arm x - c of
    # a rotation mode scaled by ell^2 made a clamp of a 10^4-long strip look singular)
    scale = np.r_[np.full(3, ell), np.ones(3)]      # mode (v, w) = (ell v^, w^)
    dof = np.r_[np.full(3, 1.0 / ell), np.ones(3)]  # nodal increments (eta_v / ell, eta_w)
    rows = [(modes * scale[None, None, :] * dof[None, :, None])[fixed & part[:, None]]]   # (n_fixed, 6)
    # supports carried by loads (lab-direction springs): rows d^T R_i [I 0] Ad_{g_i^-1} xi / ell
    for load in problem.loads:
        restraint = load.restraint()
        if restraint is not None:
            nodes, D = restraint                      # (k,), (k, q, 3) lab unit directions
            keep = part[nodes]
            nodes, D = nodes[keep], np.asarray(D)[keep]
            lab = np.einsum("kij,kjl->kil", g[nodes, :3, :3], modes[nodes][:, :3, :] * scale) / ell
            rows.append(np.einsum("kqi,kil->kql", D, lab).reshape(-1, 6))
    B = np.concatenate(rows)
    if B.shape[0] == 0:
        return "no supports: it can move as a rigid body; clamp or fix some of its nodes"
    U, S, Vt = np.linalg.svd(B, full_matrices=True)
    S = np.r_[S, np.zeros(6 - len(S))]
    if S[-1] >= 1e-10 * S[0]:
        return None
    v = Vt[-1] * scale
    tr, rot = v[:3], v[3:]
    lead = rot if np.linalg.norm(rot) * ell > 1e-8 * np.linalg.norm(tr) else tr
    tr, rot = (tr, rot) if lead[np.argmax(np.abs(lead))] > 0 else (-tr, -rot)   # the SVD's sign: one spelling
    if np.linalg.norm(rot) * ell > 1e-8 * np.linalg.norm(tr):
        # twist (tr, rot) about the centroid c: screw axis through c + rot x tr / |rot|^2
        pt = c + np.cross(rot, tr) / (rot @ rot)
        # (+ 0.0: no '-0.0' of a component the sign turned)
        return (f"rotation about {(np.round(rot / np.linalg.norm(rot), 3) + 0.0).tolist()} through "
                f"{(np.round(pt, 4) + 0.0).tolist()}")
    return f"translation along {(np.round(tr / np.linalg.norm(tr), 3) + 0.0).tolist()}"


