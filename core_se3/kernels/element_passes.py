"""The passes of the default element's drivers (numba), each over a range [lo, hi) of edges,
elements or nodes: the serial drivers of ``kernels.element`` call them once over everything,
the parallel ones once per chunk of CHUNK items (inside ``prange``), so that every pass is
written once.  Each pass allocates its own small scratch arrays.

The arrays travel in three named bundles (namedtuples of arrays: numba compiles their fields
as it does separate arguments, and the loops below read them unchanged):

* ``ElementMesh`` -- the topology (quads, edge_nodes, elem_edges, sgn) and the rotations Rq of
  the element's frames (``fem.element_default``, "Frames"; empty without a gauge);
* ``ElementData`` -- the elements' constant data (Dbar packed, its split form Dsplit, the
  reference edge twists z0 and Dbar z0);
* ``Workspace`` -- the state a call writes (psi, coef, ang per edge, fe per element side,
  rE per edge end, r per node).

``order`` is None (natural order) or an index array (the coloured drivers' order: item
``order[i]`` for i in [lo, hi)); ``fe_geo``, ``rEg``, ``rg`` None or arrays select at compile
time the ordinary or the mixed tangent (``kernels.element``); ``data`` None selects the
residual-only node pass (these stay separate arguments: numba prunes an ``is None`` branch on
an argument, not on a tuple's field).  The element passes read Dbar through
``element_ops.element_D``: ``Dsplit`` (m, 24, 12) is the split form of a law without v-w
coupling (``split_form``), or empty (0, 24, 12) for the general path that unpacks the packed
``Dbar`` (m, 300) per element (a run-time choice: one compiled version).
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import njit

from .csr import scatter
from .element_dbar import element_D
from .element_ops import (edge_F, edge_KE, edge_pass1, edge_residual, element_force, element_G,
                          element_Ke, match_edge, match_G, node_Kn, node_residual, rotate_blocks, rotate_G,
                          rotate_wrench)

__all__ = ["ElementMesh", "ElementData", "Workspace", "edges_log", "elements_force", "edges_residual", "nodes_pass", "elements_tangent",
           "edges_tangent", "elements_tangent_store", "edges_tangent_store"]

ElementMesh = namedtuple("ElementMesh", "quads edge_nodes elem_edges sgn Rq Rk")
ElementMesh.__doc__ = """The default element's topology (int64): quads (m, 4), edge_nodes (E, 2), elem_edges
(m, 4), sgn (m, 4) the orientation of each element side's edge (+1/-1); Rq (n, 3, 3) the turns of
the element's frames about the normals (g Q, ``mesh.gauge``), or empty (0, 3, 3) without them; Rk
(E, 3, 3) the quarter turns of the edges across a cross field's cuts (``fem.element_default``,
"Cuts": log(g_a^-1 g_b Rk)), or empty (0, 3, 3) without cuts."""
ElementData = namedtuple("ElementData", "Dbar Dsplit z0 Dz0")
ElementData.__doc__ = """The elements' constant data: Dbar (m, 300) packed, Dsplit its split form (m, 24, 12)
or (m, 24, 16), or empty (0, 24, 12) for the general path; z0 (m, 24) the reference edge
twists and Dz0 = Dbar z0 (m, 24)."""
Workspace = namedtuple("Workspace", "psi coef ang fe rE r")
Workspace.__doc__ = """What a call writes: psi (E, 6) the edge logs, coef (E, 3) their coefficients, ang (E,)
the turn angles, fe (m, 4, 6) the signed element forces per side, rE (E, 2, 6) the edges'
nodal parts, r (n, 6) the nodal residual."""


@njit(cache=True)
def _item(order, i):
    return i if order is None else order[i]


@njit(cache=True)
def edges_log(g, mesh, w, lo, hi):
    """Edges lo..hi: psi = log(g_a^-1 g_b), its coefficients, the turn angle into w.ang."""
    edge_nodes, Rk, psi, coef, ang = mesh.edge_nodes, mesh.Rk, w.psi, w.coef, w.ang
    R = np.empty((3, 3))
    gb = np.empty((4, 4))
    for e in range(lo, hi):
        ang[e] = edge_pass1(g, edge_nodes, e, R, psi, coef, Rk, gb)


@njit(cache=True)
def elements_force(mesh, ed, w, lo, hi):
    """Elements lo..hi: f = Dbar (z - z0) into w.fe (signed per edge; Dbar packed (m, 300),
    Dsplit its split form or empty); returns (energy, |f+Dz0|^2+|f|^2)."""
    _, _, elem_edges, sgn, _, _ = mesh
    Dbar, Dsplit, z0, Dz0 = ed
    psi, fe = w.psi, w.fe
    z = np.empty(24)
    f = np.empty(24)
    D = np.empty((24, 24))
    en = 0.0
    fs = 0.0
    for el in range(lo, hi):
        Dr = element_D(Dbar, Dsplit, el, D)
        a, b = element_force(el, elem_edges, sgn, Dr, z0, Dz0, psi, z, f, fe)
        en += a
        fs += b
    return en, fs


@njit(cache=True)
def edges_residual(topo, Rk, w, lo, hi):
    """Edges lo..hi: F = sum of the sides' fe, nodal parts r_a, r_b into w.rE (Rk: across the
    cuts, ``match_edge``)."""
    edge_slots, psi, coef, fe, rE = topo.edge_slots, w.psi, w.coef, w.fe, w.rE
    F = np.empty(6)
    for e in range(lo, hi):
        edge_F(e, edge_slots, fe, F)
        edge_residual(e, psi, coef, F, rE)
        match_edge(e, Rk, rE, None)


@njit(cache=True)
def nodes_pass(topo, Rq, w, rEg, rg, data, cmap, lo, hi):
    """Nodes lo..hi: r = sum of the edge ends, in the user's frames (Rq: ``rotate_wrench``); with
    data, the nodal block 1/2 adt(r) (mixed: r_geo from rEg into rg, and 1/2 adt(r_geo))."""
    node_ptr, node_inc, rE, r = topo.node_ptr, topo.node_inc, w.rE, w.r
    K6 = np.empty((6, 6))
    for nd in range(lo, hi):
        node_residual(nd, node_ptr, node_inc, rE, r)
        if Rq.shape[0]:
            rotate_wrench(r, nd, Rq)
        if data is not None:
            if rEg is not None:
                node_residual(nd, node_ptr, node_inc, rEg, rg)
                if Rq.shape[0]:
                    rotate_wrench(rg, nd, Rq)
                node_Kn(nd, rg, data, cmap, K6)
            else:
                node_Kn(nd, r, data, cmap, K6)


# the per-item helpers below take flat arrays: a field read from a bundle inside a loop costs a
# reference-count update per read (about +30 % on the element pass, measured); the passes
# unpack their bundles once, before their loops
@njit(cache=True)
def _element_blocks(el, quads, elem_edges, sgn, Rq, Rk, Dbar, Dsplit, z0, Dz0, psi, coef, fe, z, f, G, TT, TTt,
                    KeT, D):
    """Forces and KeT = (G^T Dbar G)^T of element el (Dbar: ``element_D``, the split form or
    unpacked into D), across the cuts (Rk: ``match_G``), in the user's frames (Rq:
    ``rotate_G``); returns (energy, force scale part)."""
    Dr = element_D(Dbar, Dsplit, el, D)
    a, b = element_force(el, elem_edges, sgn, Dr, z0, Dz0, psi, z, f, fe)
    element_G(el, elem_edges, sgn, psi, coef, G)
    match_G(G, el, elem_edges, sgn, Rk)
    if Rq.shape[0]:                  # the gauge's frames only (no view made without one)
        rotate_G(G, quads[el], Rq)
    element_Ke(Dr, G, TT, TTt, KeT)
    return a, b


@njit(cache=True)
def _element_scratch():
    return (np.empty(24), np.empty(24), np.empty((4, 2, 6, 6)), np.empty((24, 24)), np.empty((24, 24)),
            np.empty((24, 24)), np.empty((24, 24)))


@njit(cache=True)
def elements_tangent(order, mesh, ed, w, cmap, data, lo, hi):
    """Elements lo..hi (through order): forces and material blocks, scattered into data.
    Ke = KeT^T = KeT up to round-off (Dbar is symmetric): KeT is read row-wise (contiguous)."""
    quads, _, elem_edges, sgn, Rq, Rk = mesh
    Dbar, Dsplit, z0, Dz0 = ed
    psi, coef, fe = w.psi, w.coef, w.fe
    z, f, G, TT, TTt, KeT, D = _element_scratch()
    en = 0.0
    fs = 0.0
    for i in range(lo, hi):
        el = _item(order, i)
        a, b = _element_blocks(el, quads, elem_edges, sgn, Rq, Rk, Dbar, Dsplit, z0, Dz0, psi, coef, fe, z, f, G, TT,
                               TTt, KeT, D)
        en += a
        fs += b
        for A in range(4):
            nA = quads[el, A]
            for B in range(4):
                scatter(data, cmap, cmap.elem_blk[el, A, B], nA, quads[el, B], KeT, 6 * A, 6 * B, False, 1.0)
    return en, fs


@njit(cache=True)
def elements_tangent_store(mesh, ed, w, Keb, lo, hi):
    """Elements lo..hi: forces, and the material blocks stored in Keb (m,4,4,6,6)."""
    quads, _, elem_edges, sgn, Rq, Rk = mesh
    Dbar, Dsplit, z0, Dz0 = ed
    psi, coef, fe = w.psi, w.coef, w.fe
    z, f, G, TT, TTt, KeT, D = _element_scratch()
    en = 0.0
    fs = 0.0
    for el in range(lo, hi):
        a, b = _element_blocks(el, quads, elem_edges, sgn, Rq, Rk, Dbar, Dsplit, z0, Dz0, psi, coef, fe, z, f, G, TT,
                               TTt, KeT, D)
        en += a
        fs += b
        for A in range(4):
            for B in range(4):
                for r in range(6):
                    for c in range(6):
                        Keb[el, A, B, r, c] = KeT[6 * A + r, 6 * B + c]
    return en, fs


# mixed = "fe_geo is not None": pruned at compile time (one version per argument types); a
# run-time flag cost ~10 % in the serial driver (measured)
@njit(cache=True)
def _edge_blocks(e, edge_nodes, edge_slots, Rq, Rk, psi, coef, fe, rE, fe_geo, rEg, F, Fg, Lp, Lm, Ad, Jm, Y, H, p,
                 S3):
    """F_e, the nodal residual parts and the geometric block H of edge e (across the cuts: Rk,
    ``match_edge``; in the user's frames: Rq, ``rotate_blocks``); mixed (fe_geo given): H from
    F_geo = edge sum of fe_geo (into Fg), whose nodal parts go to rEg[e]."""
    edge_F(e, edge_slots, fe, F)
    edge_residual(e, psi, coef, F, rE)
    if fe_geo is not None:
        edge_F(e, edge_slots, fe_geo, Fg)
        edge_residual(e, psi, coef, Fg, rEg)
        edge_KE(e, psi, coef, Fg, Lp, Lm, Ad, Jm, Y, H, p)
        match_edge(e, Rk, rEg, None)
    else:
        edge_KE(e, psi, coef, F, Lp, Lm, Ad, Jm, Y, H, p)
    match_edge(e, Rk, rE, H)
    if Rq.shape[0]:
        rotate_blocks(H, edge_nodes[e], Rq, S3)


@njit(cache=True)
def _edge_scratch(mixed):
    F = np.empty(6)
    Fg = np.empty(6) if mixed else F
    return F, Fg, np.empty((6, 6)), np.empty((6, 6)), np.empty((6, 6)), np.empty((6, 6)), \
        np.empty((12, 6)), np.empty((12, 12)), np.empty(6), np.empty((3, 3))


@njit(cache=True)
def edges_tangent(order, mesh, topo, w, fe_geo, rEg, cmap, data, lo, hi):
    """Edges lo..hi (through order): residual parts and geometric blocks, scattered into data."""
    edge_nodes, edge_slots, Rq, Rk = mesh.edge_nodes, topo.edge_slots, mesh.Rq, mesh.Rk
    psi, coef, fe, rE = w.psi, w.coef, w.fe, w.rE
    F, Fg, Lp, Lm, Ad, Jm, Y, H, p, S3 = _edge_scratch(fe_geo is not None)
    for i in range(lo, hi):
        e = _item(order, i)
        _edge_blocks(e, edge_nodes, edge_slots, Rq, Rk, psi, coef, fe, rE, fe_geo, rEg, F, Fg, Lp, Lm, Ad, Jm, Y, H, p,
                     S3)
        for I in range(2):
            for J in range(2):
                scatter(data, cmap, cmap.edge_blk[e, I, J], edge_nodes[e, I], edge_nodes[e, J], H,
                        6 * I, 6 * J, False, 1.0)


@njit(cache=True)
def edges_tangent_store(mesh, topo, w, fe_geo, rEg, KEb, lo, hi):
    """Edges lo..hi: residual parts, and the geometric blocks stored in KEb (E,2,2,6,6)."""
    edge_nodes, edge_slots, Rq, Rk = mesh.edge_nodes, topo.edge_slots, mesh.Rq, mesh.Rk
    psi, coef, fe, rE = w.psi, w.coef, w.fe, w.rE
    F, Fg, Lp, Lm, Ad, Jm, Y, H, p, S3 = _edge_scratch(fe_geo is not None)
    for e in range(lo, hi):
        _edge_blocks(e, edge_nodes, edge_slots, Rq, Rk, psi, coef, fe, rE, fe_geo, rEg, F, Fg, Lp, Lm, Ad, Jm, Y, H, p,
                     S3)
        for I in range(2):
            for J in range(2):
                for r in range(6):
                    for c in range(6):
                        KEb[e, I, J, r, c] = H[6 * I + r, 6 * J + c]
