"""Mechanical loads and their load stiffness (registered kinds: edge_force, edge_moment, nodal,
pressure, body_force, gravity).

Virtual work in the left trivialisation: a lab force F at a node does F . delta phi =
(R^T F) . kappa_phi, a lab moment M does (R^T M) . kappa_R (seed eq. E32).  So

* dead nodal force/moment (fixed lab vector): generalised force (R^T F, R^T M), whose
  derivative along g <- g exp(eta) is [[0, hat(R^T F)], [0, hat(R^T M)]];
* follower nodal force/moment (fixed components in the node's frame d1, d2, d3): constant
  generalised force, no load stiffness in this formulation;
* dead surface load q per unit reference area (pressure of fixed direction, gravity-type body
  force): consistent nodal forces int N_i q dA, then as dead nodal forces;
* follower pressure p per unit *current* area along the current normal, f = p a_1 x a_2 per
  unit parameter area (bilinear positions): nodal forces int N_i p a_1 x a_2 dxi, with load
  stiffness from the rotation of R^T and from the change of a_1 x a_2.

Curved elements.  The bilinear quad between the nodes is a chord of a curved element: its area
element |a_1 x a_2| and its normal are not the element's (the default element's edges are exact
arcs, helicoidal, and its area element j0 = |A_1 x A_2| of the tied reference tangents is exact on
a cylinder).  Integrated over the chords, a cylinder's pressure gave the hoop force p R
sin(dtheta)/dtheta (6.65e-3 low at 0.2 rad per element) and a curved panel's weight was low by
sin(dtheta/2)/(dtheta/2).  Given the element's j0 (``SurfaceLoad(j0=...)``, the registered kinds
pass ``DefaultElement.j0``), a dead load's nodal weights are int N_i j0 dxi (the total load is q
times the element's area), and a follower pressure's body-frame nodal force of corner i is turned
and scaled by a constant C_i (3, 3) that takes its reference value R_i^T int N_i a_1 x a_2 dxi onto
(int N_i j0 dxi) d3_i, the element's area share along its normal (the frame's d3): a uniform
pressure on a cylinder gives p R exactly, at any element size.  Flat elements (whose j0 agrees
with the bilinear one to round-off, 6e-16) keep the bilinear weights, so flat meshes are unchanged
to the bit.

Every load is scaled by a function of the load factor (``scale(lam)``, linear by default).
"""
from __future__ import annotations

import warnings

import numpy as np

from .. import lie
from ..errors import LoadError, LoadWarning
from ..fem import ELEMENTS
from ..fem.quadrature import shape_functions, surface_jacobian
from .base import (Load, LoadEvaluation, LoadKind, Param, finite_vector, linear_scale, mesh_ids, param_error,
                   register_load)

__all__ = ["NodalLoad", "SurfaceLoad", "edge_weights", "line_shares", "element_area", "curved_area"]


def _scale_at(load, lam):
    """The load's scale(lam) as a finite float, else a LoadError naming the load (a NaN from a
    user's programme would otherwise surface as a non-finite residual and a storm of cut-backs)."""
    try:
        s = float(load.scale(lam))
    except (TypeError, ValueError):
        raise LoadError(f"load {load.name!r}: its scale(lam) must return one number, got "
                        f"{load.scale(lam)!r} at load factor {lam:.6g}") from None
    if not np.isfinite(s):
        raise LoadError(f"load {load.name!r}: its scale(lam) is {s} at load factor {lam:.6g}; the "
                        "load-factor programme must return finite numbers")
    return s


def edge_weights(mesh, nodes):
    """Consistent weights (summing to 1) of a uniform line load along the set's element edges.

    The line is the element edges both of whose ends are in ``nodes`` (whatever their order):
    each node gets half the length of each such edge it ends (the consistent load of linear
    shape functions along the line), normalised by the total length.  A set listed along one
    line gets the load of that line; a closed loop (a hole's edge) also its closing edge; a set
    of several lines (a Gmsh curve of two pieces) each line's share by length.  Before, the
    consecutive nodes of the list were taken as the segments: a closed loop lost its closing
    edge, and a set of two lines (listed by sorted id) got "segments" jumping between them.

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The mesh (for the reference positions and the element edges).
    nodes : sequence of int
        Node ids (one node: the whole load on it).

    Returns
    -------
    (k,) ndarray
        Weights in the order of ``nodes``; total force F on the line puts w_i F on node i.

    Raises
    ------
    LoadError
        A node of the set is on none of its element edges (an isolated point: give a nodal
        load, a force per node, for points), or on more than two (a patch of nodes).

    Example
    -------
    >>> from core_se3 import mesh
    >>> edge_weights(mesh.rectangle(1.0, 1.0, 1, 2), [0, 2, 4]).tolist()
    [0.25, 0.5, 0.25]
    >>> edge_weights(mesh.rectangle(1.0, 1.0, 1, 2), [4, 0, 2]).tolist()     # any order
    [0.25, 0.25, 0.5]
    """
    w = _edge_lengths(mesh, np.asarray(nodes))
    return w / w.sum()


def _edge_lengths(mesh, nodes):
    """Half the length of each element edge of the set that a node ends, summed per node (the
    unnormalised weights of :func:`edge_weights`; one node: 1)."""
    if len(nodes) == 1:
        return np.ones(1)
    where = np.full(mesh.n_nodes, -1)
    where[nodes] = np.arange(len(nodes))
    E = where[mesh.edge_nodes]
    E = E[(E >= 0).all(1)]                                   # the set's own element edges
    degree = np.bincount(E.ravel(), minlength=len(nodes))
    if np.any(degree > 2):                                   # a patch (or lines that cross): no line
        k = int(np.argmax(degree))
        raise LoadError(f"an edge load (a total along a line) on a set that is not a line of element edges: node "
                        f"{int(nodes[k])} joins {int(degree[k])} others of the set (a patch of nodes, or lines that "
                        "meet); select a line, or give a nodal load (a force per node) or a surface load")
    seg = np.linalg.norm(mesh.X[nodes[E[:, 1]]] - mesh.X[nodes[E[:, 0]]], axis=1)
    w = np.zeros(len(nodes))
    np.add.at(w, E[:, 0], seg / 2)
    np.add.at(w, E[:, 1], seg / 2)
    if np.any(w == 0):
        lone = nodes[w == 0]
        raise LoadError(f"an edge load (a total along a line) on nodes that no element edge of the set joins: "
                        f"{lone[:5].tolist()}{' ...' if len(lone) > 5 else ''} of {len(nodes)}; select a line of "
                        "nodes joined by element edges, or give a nodal load (a force per node) for points")
    return w


def line_shares(mesh, names):
    """The share of each named line of a union in a total along them all: its length over theirs.

    A union of lines given as one node set is a line of its own element edges: both ends of a
    strip one element long joined by its sides into a closed loop, and the load spread onto the
    sides.  Named one by one, each line keeps its own element edges.

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The mesh (its named node sets).
    names : sequence of str
        Names of node sets, each a line of element edges (:func:`edge_weights`).

    Returns
    -------
    (k,) ndarray
        The shares, summing to 1.  LoadError for a name given twice, or lines sharing an
        element edge (its part of the load would count twice).

    Example
    -------
    >>> from core_se3 import mesh
    >>> line_shares(mesh.rectangle(2.0, 1.0, 1, 1), ["x0", "y0"]).tolist()
    [0.3333333333333333, 0.6666666666666666]
    """
    names = list(names)
    if len(set(names)) < len(names):
        raise LoadError(f"a union of lines {names} names a line twice: its load would count twice; name each once")
    sets = [np.asarray(mesh.node_set(n)) for n in names]
    own = [np.isin(mesh.edge_nodes, nodes).all(1) for nodes in sets]          # each line's element edges
    shared = np.nonzero(np.sum(own, 0) > 1)[0]
    if len(shared):
        a, b = [n for n, o in zip(names, own) if o[shared[0]]][:2]
        raise LoadError(f"lines {a!r} and {b!r} share the element edge {mesh.edge_nodes[shared[0]].tolist()}: its "
                        "part of the load would count twice; name lines that meet at most at a node")
    lone = [n for n, nodes in zip(names, sets) if len(nodes) < 2]
    if lone:
        raise LoadError(f"node set {lone[0]!r} of a union of lines is one node, no line: give points a nodal load")
    lengths = np.array([_edge_lengths(mesh, nodes).sum() for nodes in sets])
    return lengths / lengths.sum()


class NodalLoad(Load):
    """Force and moment on nodes, split by ``weights``; dead (lab) or follower (body frame).

    A dead load has the generalised force (R^T F, R^T M) and the load stiffness of the module
    docstring; a follower load has constant components in the node's frame and no stiffness.

    Parameters
    ----------
    n_nodes : int
        Number of nodes of the mesh.
    nodes : sequence of int
        The loaded nodes; ``weights`` (same length): the share of each.
    force, moment : (3,) array_like, optional
        The total force [force] and moment [force x length] at scale 1: lab vectors (dead) or
        d1, d2, d3 components (``follower=True``).
    scale : callable, optional
        The load-factor programme s(lam) (default lam); ``name``: for reports.

    Example
    -------
    >>> import numpy as np
    >>> ld = NodalLoad(3, [2], [1.0], force=(0, 0, 2.0))
    >>> ld.evaluate(np.broadcast_to(np.eye(4), (3, 4, 4)), 0.5).f[2].tolist()
    [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    >>> [v.tolist() for v in ld.total(0.5)]
    [[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]
    """

    translation_invariant = True          # forces from the frames' rotations and relative positions

    def __init__(self, n_nodes, nodes, weights, force=(0, 0, 0), moment=(0, 0, 0), follower=False,
                 scale=None, name="nodal"):
        self.n = int(n_nodes)
        self.nodes = mesh_ids(nodes, self.n, f"load {name!r}: nodes")
        self.weights = np.asarray(weights, float)
        self.force = finite_vector(force, "force")
        self.moment = finite_vector(moment, "moment")
        self.follower = bool(follower)
        self.scale = scale or linear_scale
        self.name = name
        # a follower's work depends on the path, and so does a dead moment's on finite 3-D rotations
        self.conservative = not self.follower and not np.any(self.moment)
        if self.weights.shape != self.nodes.shape or not np.all(np.isfinite(self.weights)):
            raise LoadError(f"load {name}: weights must be finite, one per node")

    def evaluate(self, g, lam, tangent=True):
        n = self.n
        s = _scale_at(self, lam)
        f = np.zeros((n, 6))
        w = self.weights[:, None] * s
        if self.follower:
            np.add.at(f, self.nodes, np.concatenate([w * self.force, w * self.moment], 1))
            return LoadEvaluation(f)
        Rt = np.swapaxes(g[self.nodes, :3, :3], 1, 2)
        Fb = w * (Rt @ self.force)
        Mb = w * (Rt @ self.moment)
        np.add.at(f, self.nodes, np.concatenate([Fb, Mb], 1))
        if not tangent:
            return LoadEvaluation(f)
        Kn = np.zeros((n, 6, 6))
        blk = np.zeros((len(self.nodes), 6, 6))
        blk[:, :3, 3:] = -lie.hat3(Fb)
        blk[:, 3:, 3:] = -lie.hat3(Mb)
        np.add.at(Kn, self.nodes, blk)
        return LoadEvaluation(f, Kn)

    def compiled(self, pattern):
        """The numba kernel of this load (``kernels.loads.nodal_load``)."""
        from ..kernels.loads import nodal_load
        nodes, w = np.ascontiguousarray(self.nodes), np.ascontiguousarray(self.weights)

        def add(g, lam, f, data, tangent):
            nodal_load(g, nodes, w, self.force, self.moment, _scale_at(self, lam), self.follower, f, data,
                       pattern.map, tangent)
        return add

    def total(self, lam):
        """Resultant (force, moment) vectors at lam: lab vectors if dead, frame components if
        follower."""
        s = _scale_at(self, lam)
        return s * self.weights.sum() * self.force, s * self.weights.sum() * self.moment


class SurfaceLoad(Load):
    """Distributed load over the elements ``elements`` (default: all).

    dead: ``q`` is a lab vector per unit reference area (fixed-direction pressure, gravity).
    follower: ``q`` is a scalar pressure per unit current area along the current normal
    a_1 x a_2 (positive toward the frames' +d3 side).

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The mesh.
    q : (3,) array_like or float
        Dead: force per unit reference area [force/length^2] (lab vector).  Follower: the
        pressure [force/length^2].
    follower : bool, optional
        Pressure along the current normal (with its load stiffness, element blocks).
    elements : array_like of int, optional
        The loaded elements (default all).
    scale : callable, optional
        s(lam), default lam; ``name``: for reports.
    j0 : (k, 4) array_like, optional
        The element's own area element at the 2x2 Gauss points of the k loaded elements (the
        default element's ``j0``, from its exact-arc geometry); default the bilinear quads'.
        On curved elements the loads use it (module docstring, "Curved elements").

    Example
    -------
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(2.0, 1.0, 2, 1)
    >>> ld = SurfaceLoad(m, (0.0, 0.0, -3.0))
    >>> round(float(ld.evaluate(m.g0, 1.0).f[:, 2].sum()), 12)        # q times the area
    -6.0
    >>> round(float(SurfaceLoad(m, 3.0, follower=True).evaluate(m.g0, 1.0).f[:, 2].sum()), 12)
    6.0
    """

    translation_invariant = True          # forces from the frames' rotations and relative positions

    def __init__(self, mesh, q, follower=False, elements=None, scale=None, name="surface", j0=None):
        self.mesh = mesh
        self.follower = bool(follower)
        self.conservative = not self.follower        # a dead pressure or weight; a follower's work depends on the path
        self.scale = scale or linear_scale
        self.name = name
        self.elements = (np.arange(mesh.n_elements) if elements is None else
                         mesh_ids(elements, mesh.n_elements, f"load {name!r}: elements"))
        self.N, self.dN = shape_functions()
        self.j0 = None if j0 is None else np.asarray(j0, float)
        jw, curved = self._area_element(mesh)
        if self.follower:
            q = float(q)
            if not np.isfinite(q):
                raise LoadError(f"load {name}: pressure must be finite, got {q}")
            self.p = q
            self.turns = _corner_turns(mesh.g0[mesh.quads[self.elements]], self.N, self.dN, jw, curved, self.elements)
        else:
            self.q = finite_vector(q, "surface load")
            self.node_w = np.einsum("qi,mq->mi", self.N, jw)           # int N_i dA, (m,4)

    def _area_element(self, mesh):
        """The area element (k, 4) the load integrates with and the curved mask (k,):
        :func:`curved_area` of the bilinear quads' and the element's ``j0``."""
        return curved_area(surface_jacobian(mesh.X[mesh.quads[self.elements]], self.dN), self.j0, f"load {self.name!r}")

    def compiled(self, pattern):
        """The numba kernels of this load (``kernels.loads.surface_load_*``; the follower
        pressure's elements in the mesh colouring, so that the parallel driver is race-free)."""
        from ..kernels import loads as K
        quads = np.ascontiguousarray(self.mesh.quads, dtype=np.int64)
        el = np.ascontiguousarray(self.elements, dtype=np.int64)
        cptr, order = pattern.group_elements(el)
        if not self.follower:
            node_w = np.ascontiguousarray(self.node_w)

            def add(g, lam, f, data, tangent):
                K.surface_load_dead(g, quads, el, cptr, order, node_w, self.q, _scale_at(self, lam), f, data,
                                    pattern.map, tangent)
            return add
        run = K.surface_load_follower_par if len(el) >= 1500 else K.surface_load_follower
        turned = self.turns is not None
        turns = np.ascontiguousarray(self.turns if turned else np.zeros((1, 4, 3, 3)))

        def add(g, lam, f, data, tangent):
            run(g, quads, el, cptr, order, _scale_at(self, lam) * self.p, turns, turned, f, data, pattern.map,
                tangent)
        return add

    def evaluate(self, g, lam, tangent=True):
        s = _scale_at(self, lam)
        quads = self.mesh.quads[self.elements]
        n = self.mesh.n_nodes
        f = np.zeros((n, 6))
        if not self.follower:
            F = s * self.node_w[..., None] * self.q                      # (m,4,3) lab
            Rt = np.swapaxes(g[quads, :3, :3], -1, -2)
            Fb = np.einsum("maij,maj->mai", Rt, F)
            for k in range(3):
                f[:, k] += np.bincount(quads.ravel(), weights=Fb[..., k].ravel(), minlength=n)
            if not tangent:
                return LoadEvaluation(f)
            Kn = np.zeros((n, 6, 6))
            blk = -lie.hat3(Fb)                                          # (m,4,3,3)
            for i in range(3):
                for j in range(3):
                    Kn[:, i, 3 + j] += np.bincount(quads.ravel(), weights=blk[..., i, j].ravel(), minlength=n)
            return LoadEvaluation(f, Kn)
        p = s * self.p
        phi = g[quads, :3, 3]                                            # (m,4,3)
        R = g[quads, :3, :3]
        # tangents from the corners relative to the first (exact differences: a far part's
        # eps |x| / h stays out of the normal, as in fem.quadrature.surface_jacobian)
        a = np.einsum("qai,mij->mqaj", self.dN, phi - phi[:, :1])         # (m,q,2,3)
        nrm = np.cross(a[:, :, 0], a[:, :, 1])                          # (m,q,3)
        F = p * np.einsum("qi,mqk->mik", self.N, nrm)                    # (m,4,3) lab
        Fb = np.einsum("maji,maj->mai", R, F)                            # R^T F
        C = self.turns
        Fc = Fb if C is None else np.einsum("makl,mal->mak", C, Fb)     # curved elements: C_i R^T F
        for k in range(3):
            f[:, k] += np.bincount(quads.ravel(), weights=Fc[..., k].ravel(), minlength=n)
        if not tangent:
            return LoadEvaluation(f)
        # load stiffness: -d(R_i^T F_i)/d eta; rotation part on node i, position part couples i, j
        m = len(quads)
        Ke = np.zeros((m, 4, 4, 6, 6))
        idx = np.arange(4)
        Ke[:, idx, idx, :3, 3:] = -lie.hat3(Fb)
        A1, A2 = lie.hat3(a[:, :, 0]), lie.hat3(a[:, :, 1])               # (m,q,3,3)
        # dF_i/dphi_j = p int N_i (-dN_j/dx hat(a2) + dN_j/dy hat(a1)) dxi
        dF = p * (np.einsum("qi,qj,mqkl->mijkl", self.N, -self.dN[:, 0], A2)
                  + np.einsum("qi,qj,mqkl->mijkl", self.N, self.dN[:, 1], A1))
        Ke[..., :3, :3] = -np.einsum("miak,mijab,mjbc->mijkc", R, dF, R)
        if C is not None:
            Ke[..., :3, :] = np.einsum("mikl,mijlc->mijkc", C, Ke[..., :3, :])
        return LoadEvaluation(f, None, (self.elements, Ke))


def _corner_turns(g0, N, dN, jw, curved, elements):
    """C (k, 4, 3, 3) of a follower pressure's corners (module docstring, "Curved elements"), or
    None where no element is curved: the turn of the reference body-frame force per unit
    pressure b_i = R_i^T int N_i a_1 x a_2 dxi onto d3 (e3 of the frame), times
    (int N_i jw dxi) / |b_i|; the identity on flat elements (``elements``: the ids, for the error)."""
    if not curved.any():
        return None
    phi, R = g0[..., :3, 3], g0[..., :3, :3]
    a = np.einsum("qai,mij->mqaj", dN, phi - phi[:, :1])
    b = np.einsum("maji,maj->mai", R, np.einsum("qi,mqk->mik", N, np.cross(a[:, :, 0], a[:, :, 1])))
    nb = np.linalg.norm(b, axis=-1)
    u = b / nb[..., None]
    v = np.cross(u, [0.0, 0.0, 1.0])                                   # sin(angle) x axis
    c = u[..., 2]
    if np.any(c <= 0.0):
        e = int(elements[np.argmax((c <= 0.0).any(axis=1))])
        raise LoadError(f"follower pressure on curved element {e}: a corner's frame d3 is 90 degrees or more off "
                        "the normal of the quad of its corners; check the mesh's frames (d3 the shell's normal)")
    V = lie.hat3(v)
    Q = np.eye(3) + V + np.einsum("...ij,...jk->...ik", V, V) / (1.0 + c)[..., None, None]   # Rodrigues: u -> e3
    C = (np.einsum("qi,mq->mi", N, jw) / nb)[..., None, None] * Q
    C[~curved] = np.eye(3)
    return C


# ------------------------------------------------------------------ registered kinds -------

def _edge(what):
    def build(problem, nodes, scale, follower=False, **v):
        vec = v[what]
        kw = {what: vec}
        return NodalLoad(problem.mesh.n_nodes, nodes, edge_weights(problem.mesh, nodes),
                         follower=follower, scale=scale, name=f"edge {what}", **kw)
    return build


def _nodal(problem, nodes, scale, force=(0, 0, 0), moment=(0, 0, 0), follower=False):
    return NodalLoad(problem.mesh.n_nodes, nodes, np.ones(len(nodes)), force=force, moment=moment,
                     follower=follower, scale=scale, name="nodal")


def _nodal_check(values, given):
    if "force" not in given and "moment" not in given:
        return None, "a nodal load needs 'force' and/or 'moment'"
    return None


def curved_area(jb, j0, what="load"):
    """The area element (k, 4) that the area loads and the magnets (``Magnetisation``) integrate
    with: the element's own ``j0`` (its exact-arc geometry, :func:`element_area`) on curved
    elements, the bilinear quads' ``jb`` elsewhere (bit for bit: a flat element's tied j0 is the
    bilinear one to round-off, <= 6.3e-16 relative); and the curved mask (k,).  ``j0`` None:
    ``jb`` everywhere.  A ``j0`` of another shape, or not positive and finite, is a LoadError
    naming ``what``.

    Example
    -------
    >>> import numpy as np
    >>> jb = np.full((2, 4), 0.25)
    >>> jw, curved = curved_area(jb, np.array([[0.25] * 4, [0.26] * 4]))
    >>> jw[:, 0].tolist(), curved.tolist()
    ([0.25, 0.26], [False, True])
    """
    if j0 is None:
        return jb, np.zeros(len(jb), bool)
    j0 = np.asarray(j0, float)
    if j0.shape != jb.shape or not np.all(np.isfinite(j0) & (j0 > 0)):
        raise LoadError(f"{what}: j0 must be positive and finite, (k, 4) for the k = {len(jb)} loaded "
                        f"elements' Gauss points, got shape {j0.shape}")
    curved = np.any(np.abs(j0 - jb) > 16 * np.finfo(float).eps * jb, axis=1)
    return np.where(curved[:, None], j0, jb), curved


def element_area(problem, elements):
    """The problem's element's own area element (k, 4) at the Gauss points of ``elements`` (its
    ``j0``: the default element's, of its exact-arc geometry, from its class's ``reference_area``
    without building it), or None for an element without one (the bilinear quads' are then used:
    SurfaceLoad).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.cylinder_panel(1.0, 1.0, 0.0, 1.2, 3, 1), Material(1e3, 0.0, 0.01))
    >>> round(float(element_area(p, np.arange(3)).sum()), 12)          # the exact area 1.2 x 1
    1.2
    """
    # the element's class gives it from the geometry (``reference_area``): building the element
    # (its stiffness on the whole mesh) here would cost every rank of a distributed run, which
    # holds the whole Problem but builds only its own elements
    area = getattr(ELEMENTS.get(problem.element_name), "reference_area", None)
    if area is None:
        return None
    j0 = area(problem.mesh, problem.material)
    sel = np.arange(problem.mesh.n_elements) if elements is None else np.asarray(elements)
    return np.asarray(j0)[sel]


def _pressure(problem, elements, scale, p, direction=(0.0, 0.0, 1.0), follower=False):
    if not np.isfinite(p):
        raise LoadError(f"pressure must be finite, got {p}")
    j0 = element_area(problem, elements)
    if follower:
        return SurfaceLoad(problem.mesh, p, True, elements, scale, "follower pressure", j0)
    d = np.array([0, 0, 1.0]) if direction is None else finite_vector(direction, "pressure direction")
    if not np.any(d):
        raise LoadError("pressure direction must be a non-zero 3-vector (the lab direction of a dead "
                        "pressure), got (0, 0, 0)")
    return SurfaceLoad(problem.mesh, p * d / np.linalg.norm(d), False, elements, scale, "dead pressure", j0)


def _pressure_check(values, given):
    if values.get("follower") and "direction" in given:
        return "direction", ("a follower pressure acts along the current normal; 'direction' is "
                             "only for dead pressure")
    return None


def _body_force(problem, elements, scale, q):
    return SurfaceLoad(problem.mesh, q, False, elements, scale, "body force", element_area(problem, elements))


def _gravity(problem, elements, scale, g=(0.0, 0.0, -9.81), rho=None):
    """Self-weight rho h g per unit reference area, one load per group of elements sharing
    (rho, h) (rho from the material where the load gives none)."""
    mesh, mat = problem.mesh, problem.material
    sel = np.arange(mesh.n_elements) if elements is None else np.asarray(elements)
    m = mesh.n_elements
    h, dens = material_per_element(mat, "h", m)[sel], material_per_element(mat, "rho", m)[sel]
    if rho is not None:
        if not (np.isfinite(rho) and rho >= 0):
            raise param_error(f"density must be non-negative and finite, got {rho}", "rho")
        dens = np.full(len(sel), float(rho))
    if np.any(np.isnan(dens)):
        raise param_error("gravity needs a density on every loaded element: give 'rho' to the "
                          "load or to the material (Material(..., rho=...), [material] rho)", "rho")
    gv = np.asarray(g, float)
    if not np.any(dens):
        whose = f"the load's rho = {rho:g}" if rho is not None else "the material's rho (Material(..., rho=...), " \
                                                                     "[material] rho) is 0"
        warnings.warn(LoadWarning(f"gravity on {len(sel)} element(s) of zero mass adds nothing: {whose}; give a "
                                  "positive density, or drop the gravity load"), stacklevel=3)
    j0 = element_area(problem, sel)
    return [SurfaceLoad(mesh, r * t * gv, False, sel[(dens == r) & (h == t)], scale, "gravity",
                        None if j0 is None else j0[(dens == r) & (h == t)])
            for r, t in sorted(set(zip(dens.tolist(), h.tolist()))) if r != 0]


def material_per_element(material, name, n_elements):
    """Property ``name`` of every element's material (m,) as floats, NaN where it is None."""
    per = getattr(material, "per_element", None)
    vals = per(name) if per is not None else [getattr(material, name)] * n_elements
    return np.array([np.nan if v is None else v for v in vals], float)


register_load(LoadKind("edge_force", "line", (
    Param("force", "vector", doc="total force [force]: lab vector (dead) or d1, d2, d3 components "
                                 "(follower), spread consistently along the line"),
    Param("follower", "bool", False, doc="components in each node's current frame")),
    _edge("force"), doc="a total force spread along a line of element edges: a lab vector, or components in each "
                       "node's frame d1, d2, d3 if follower"))
register_load(LoadKind("edge_moment", "line", (
    Param("moment", "vector", doc="total moment [force x length], spread along the line"),
    Param("follower", "bool", False, doc="components in each node's current frame")),
    _edge("moment"), doc="a total moment spread along a line of element edges"))
register_load(LoadKind("nodal", "nodes", (
    Param("force", "vector", (0.0, 0.0, 0.0), doc="force on each selected node"),
    Param("moment", "vector", (0.0, 0.0, 0.0), doc="moment on each selected node"),
    Param("follower", "bool", False, doc="components in each node's current frame")),
    _nodal, _nodal_check, doc="the same force and moment on every selected node"))
register_load(LoadKind("pressure", "elements", (
    Param("p", "number", doc="pressure [force/length^2]"),
    Param("direction", "vector", (0.0, 0.0, 1.0), nonzero=True,
          doc="lab direction of a dead pressure (per reference area; its length does not matter)"),
    Param("follower", "bool", False, doc="along the current normal, per current area")),
    _pressure, _pressure_check, doc="dead: p along the lab direction per unit reference area; follower: along the "
                                  "current normal d3 per unit current area"))
register_load(LoadKind("body_force", "elements", (
    Param("q", "vector", doc="dead force per unit reference area [force/length^2]"),),
    _body_force, doc="a dead force per unit reference area (lab vector)"))
register_load(LoadKind("gravity", "elements", (
    Param("g", "vector", (0.0, 0.0, -9.81), doc="gravitational acceleration [length/time^2]"),
    Param("rho", "number", None, lo=0.0, doc="density [mass/length^3] (default: the material's)")),
    _gravity, doc="self-weight rho h g per unit reference area (rho: the material's by default)"))
