"""The default element on plain arrays (numba): residual-only and residual + tangent drivers,
serial (small meshes), coloured and gathering (parallel over elements, race-free), and the
Python wrapper :class:`ElementKernels` with its preallocated workspace.

The tangent drivers write the element's blocks (material G^T Dbar G, edge geometric, nodal
1/2 adt(r)) straight into the CSR ``data`` of the free-dof pattern (``kernels.csr``): no COO to
CSR conversion and no pattern-sized allocation per iteration.
"""
from __future__ import annotations

from math import sqrt

import numpy as np
from numba import njit, prange

from .csr import scatter
from .element_mixed import element_linear_stress, element_linear_stress_serial, signed_edge_stress, stress_from_signed
from .element_ops import (CHUNK, MAX_EDGE_ANGLE, check_angles, edge_F, edge_KE, edge_pass1, edge_residual,
                          element_force, element_G, element_Ke, node_Kn, node_residual)

__all__ = ["ElementKernels", "element_residual", "element_residual_serial", "element_tangent",
           "element_tangent_serial", "element_tangent_gather", "SERIAL_BELOW"]

@njit(cache=True, parallel=True)
def element_residual(g, edge_nodes, elem_edges, elem_edge_sign, Dbar, z0, Dz0, topo,
                     psi, coef, ang, fe, rE, r):
    """Residual only.  Returns (energy, force_scale, flag, edge); r (n, 6) is written.

    energy = 1/2 sum_e dz^T Dbar dz, dz = z - z0, z = (sgn psi / 2) over the 4 edges;
    F_E = sum over elements of sgn f (f = Dbar dz); r_a += -1/2 L(-psi)^T F, r_b += 1/2 L(psi)^T F;
    force_scale = sqrt(sum |f + Dz0|^2 + |f|^2).  Workspace: psi (E,6), coef (E,3), ang (E,),
    fe (m,4,6), rE (E,2,6).  Parallel over edges, elements, nodes (no colouring needed)."""
    nE = edge_nodes.shape[0]
    m = elem_edges.shape[0]
    n = r.shape[0]
    nchE = (nE + CHUNK - 1) // CHUNK
    for ch in prange(nchE):
        R = np.empty((3, 3))
        for e in range(ch * CHUNK, min(nE, (ch + 1) * CHUNK)):
            ang[e] = edge_pass1(g, edge_nodes, e, R, psi, coef)
    flag, bad = check_angles(ang)
    if flag:
        return 0.0, 0.0, flag, bad
    energy = 0.0
    fs = 0.0
    nchm = (m + CHUNK - 1) // CHUNK
    for ch in prange(nchm):
        z = np.empty(24)
        f = np.empty(24)
        for el in range(ch * CHUNK, min(m, (ch + 1) * CHUNK)):
            a, b = element_force(el, elem_edges, elem_edge_sign, Dbar, z0, Dz0, psi, z, f, fe)
            energy += a
            fs += b
    for ch in prange(nchE):
        F = np.empty(6)
        for e in range(ch * CHUNK, min(nE, (ch + 1) * CHUNK)):
            edge_F(e, topo.edge_slots, fe, F)
            edge_residual(e, psi, coef, F, rE)
    for nd in prange(n):
        node_residual(nd, topo.node_ptr, topo.node_inc, rE, r)
    return energy, sqrt(fs), 0, -1


@njit(cache=True)
def _element_tangent_one(el, quads, elem_edges, sgn, Dbar, z0, Dz0, psi, coef, fe, cmap, data,
                         z, f, G, TT, TTt, KeT):
    """Residual forces and material blocks Ke = G^T Dbar G of element el, scattered into data."""
    a, b = element_force(el, elem_edges, sgn, Dbar, z0, Dz0, psi, z, f, fe)
    element_G(el, elem_edges, sgn, psi, coef, G)
    element_Ke(el, Dbar, G, TT, TTt, KeT)
    # Ke = KeT^T = KeT up to round-off (Dbar is symmetric): read KeT row-wise (contiguous)
    for A in range(4):
        nA = quads[el, A]
        for B in range(4):
            scatter(data, cmap, cmap.elem_blk[el, A, B], nA, quads[el, B], KeT, 6 * A, 6 * B, False, 1.0)
    return a, b


# mixed = "fe_geo is not None": pruned at compile time (one version per argument types); a run-time
# flag, or these branches one helper level deeper, cost ~10 % in the serial driver (measured)
@njit(cache=True)
def _edge_tangent_one(e, edge_nodes, topo, psi, coef, fe, rE, fe_geo, rEg, cmap, data, F, Fg,
                      Lp, Lm, Ad, Jm, Y, H, p):
    """F_e, the nodal residual parts and the geometric blocks of edge e, scattered into data;
    mixed (fe_geo given): the blocks from F_geo = edge sum of fe_geo (into Fg), whose nodal
    parts go to rEg[e]."""
    edge_F(e, topo.edge_slots, fe, F)
    edge_residual(e, psi, coef, F, rE)
    if fe_geo is not None:
        edge_F(e, topo.edge_slots, fe_geo, Fg)
        edge_residual(e, psi, coef, Fg, rEg)
        edge_KE(e, psi, coef, Fg, Lp, Lm, Ad, Jm, Y, H, p)
    else:
        edge_KE(e, psi, coef, F, Lp, Lm, Ad, Jm, Y, H, p)
    for I in range(2):
        for J in range(2):
            scatter(data, cmap, cmap.edge_blk[e, I, J], edge_nodes[e, I], edge_nodes[e, J], H,
                     6 * I, 6 * J, False, 1.0)


@njit(cache=True, parallel=True)
def element_tangent(g, quads, edge_nodes, elem_edges, elem_edge_sign, Dbar, z0, Dz0, topo, cmap,
                    psi, coef, ang, fe, rE, r, data, fe_geo, rEg, rg):
    """Residual and tangent of the default element, written into the CSR ``data`` (nnz,).

    Coloured, fused compute + scatter (parallel within each colour, race-free):

      1. edges:    psi = log(g_a^-1 g_b), c, c'/t, (c'/t)'/t of |w|^2;
      2. elements: f = Dbar (z - z0), Ke = G^T Dbar G (element.py's material part), scattered;
      3. edges:    F = sum of sgn f, r_a = -L(-psi)^T F/2, r_b = L(psi)^T F/2 and the geometric
                   block H (element.py: A = M^T J_m N, H = (A + A^T)/4 + adt terms), scattered;
      4. nodes:    r = sum of edge ends, Kn = adt(r)/2 on the diagonal block.

    data is zeroed first; loads add their blocks afterwards.  Returns (energy, force_scale,
    flag, edge) like ``element_residual``; on flag = 1 nothing past pass 1 is computed.

    Mixed iteration (fe_geo, rEg, rg arrays; Magisano, Leonetti and Garcea 2017): the
    geometric part sees independent stresses, fe_geo (m,4,6) = their signed edge parts (like
    fe): pass 3 also forms F_geo = sum of fe_geo and its nodal parts into rEg (E,2,6), H is
    built with F_geo, and pass 4 sums r_geo into rg (n,6) and writes 1/2 adt(r_geo).  The
    residual, the energy and the material blocks do not change.  fe_geo = rEg = rg = None:
    the ordinary tangent (a separate compiled version: the mixed branches are pruned)."""
    nE = edge_nodes.shape[0]
    n = r.shape[0]
    for i in prange(data.size):
        data[i] = 0.0
    nchE = (nE + CHUNK - 1) // CHUNK
    for ch in prange(nchE):
        R = np.empty((3, 3))
        for e in range(ch * CHUNK, min(nE, (ch + 1) * CHUNK)):
            ang[e] = edge_pass1(g, edge_nodes, e, R, psi, coef)
    flag, bad = check_angles(ang)
    if flag:
        return 0.0, 0.0, flag, bad
    energy = 0.0
    fs = 0.0
    cptr, order = topo.elem_cptr, topo.elem_order
    for col in range(len(cptr) - 1):
        lo, hi = cptr[col], cptr[col + 1]
        nch = (hi - lo + CHUNK - 1) // CHUNK
        for ch in prange(nch):
            z = np.empty(24)
            f = np.empty(24)
            G = np.empty((4, 2, 6, 6))
            TT = np.empty((24, 24))
            TTt = np.empty((24, 24))
            KeT = np.empty((24, 24))
            for ii in range(lo + ch * CHUNK, min(hi, lo + (ch + 1) * CHUNK)):
                a, b = _element_tangent_one(order[ii], quads, elem_edges, elem_edge_sign, Dbar, z0, Dz0,
                                            psi, coef, fe, cmap, data, z, f, G, TT, TTt, KeT)
                energy += a
                fs += b
    cptr, order = topo.edge_cptr, topo.edge_order
    for col in range(len(cptr) - 1):
        lo, hi = cptr[col], cptr[col + 1]
        nch = (hi - lo + CHUNK - 1) // CHUNK
        for ch in prange(nch):
            F = np.empty(6)
            Fg = np.empty(6) if fe_geo is not None else F
            p = np.empty(6)
            Lp = np.empty((6, 6))
            Lm = np.empty((6, 6))
            Ad = np.empty((6, 6))
            Jm = np.empty((6, 6))
            Y = np.empty((12, 6))
            H = np.empty((12, 12))
            for ii in range(lo + ch * CHUNK, min(hi, lo + (ch + 1) * CHUNK)):
                _edge_tangent_one(order[ii], edge_nodes, topo, psi, coef, fe, rE, fe_geo, rEg,
                                  cmap, data, F, Fg, Lp, Lm, Ad, Jm, Y, H, p)
    nchn = (n + CHUNK - 1) // CHUNK
    for ch in prange(nchn):
        K6 = np.empty((6, 6))
        for nd in range(ch * CHUNK, min(n, (ch + 1) * CHUNK)):
            node_residual(nd, topo.node_ptr, topo.node_inc, rE, r)
            if rEg is not None:
                node_residual(nd, topo.node_ptr, topo.node_inc, rEg, rg)
                node_Kn(nd, rg, data, cmap, K6)
            else:
                node_Kn(nd, r, data, cmap, K6)
    return energy, sqrt(fs), 0, -1


@njit(cache=True)
def element_tangent_serial(g, quads, edge_nodes, elem_edges, elem_edge_sign, Dbar, z0, Dz0, topo, cmap,
                           psi, coef, ang, fe, rE, r, data, fe_geo, rEg, rg):
    """``element_tangent`` in one thread, natural order (no threading overhead: small meshes);
    the same mixed option (fe_geo, rEg, rg: arrays or None)."""
    nE = edge_nodes.shape[0]
    m = elem_edges.shape[0]
    n = r.shape[0]
    data[:] = 0.0
    R = np.empty((3, 3))
    for e in range(nE):
        ang[e] = edge_pass1(g, edge_nodes, e, R, psi, coef)
    flag, bad = check_angles(ang)
    if flag:
        return 0.0, 0.0, flag, bad
    energy = 0.0
    fs = 0.0
    z = np.empty(24)
    f = np.empty(24)
    G = np.empty((4, 2, 6, 6))
    TT = np.empty((24, 24))
    TTt = np.empty((24, 24))
    KeT = np.empty((24, 24))
    for el in range(m):
        a, b = _element_tangent_one(el, quads, elem_edges, elem_edge_sign, Dbar, z0, Dz0,
                                    psi, coef, fe, cmap, data, z, f, G, TT, TTt, KeT)
        energy += a
        fs += b
    F = np.empty(6)
    Fg = np.empty(6) if fe_geo is not None else F
    p = np.empty(6)
    Lp = np.empty((6, 6))
    Lm = np.empty((6, 6))
    Ad = np.empty((6, 6))
    Jm = np.empty((6, 6))
    Y = np.empty((12, 6))
    H = np.empty((12, 12))
    for e in range(nE):
        _edge_tangent_one(e, edge_nodes, topo, psi, coef, fe, rE, fe_geo, rEg, cmap, data, F, Fg,
                          Lp, Lm, Ad, Jm, Y, H, p)
    K6 = np.empty((6, 6))
    for nd in range(n):
        node_residual(nd, topo.node_ptr, topo.node_inc, rE, r)
        if rEg is not None:
            node_residual(nd, topo.node_ptr, topo.node_inc, rEg, rg)
            node_Kn(nd, rg, data, cmap, K6)
        else:
            node_Kn(nd, r, data, cmap, K6)
    return energy, sqrt(fs), 0, -1


@njit(cache=True)
def element_residual_serial(g, edge_nodes, elem_edges, elem_edge_sign, Dbar, z0, Dz0, topo,
                            psi, coef, ang, fe, rE, r):
    """``element_residual`` in one thread."""
    nE = edge_nodes.shape[0]
    m = elem_edges.shape[0]
    R = np.empty((3, 3))
    for e in range(nE):
        ang[e] = edge_pass1(g, edge_nodes, e, R, psi, coef)
    flag, bad = check_angles(ang)
    if flag:
        return 0.0, 0.0, flag, bad
    energy = 0.0
    fs = 0.0
    z = np.empty(24)
    f = np.empty(24)
    for el in range(m):
        a, b = element_force(el, elem_edges, elem_edge_sign, Dbar, z0, Dz0, psi, z, f, fe)
        energy += a
        fs += b
    F = np.empty(6)
    for e in range(nE):
        edge_F(e, topo.edge_slots, fe, F)
        edge_residual(e, psi, coef, F, rE)
    for nd in range(r.shape[0]):
        node_residual(nd, topo.node_ptr, topo.node_inc, rE, r)
    return energy, sqrt(fs), 0, -1


@njit(cache=True, parallel=True)
def element_tangent_gather(g, quads, edge_nodes, elem_edges, elem_edge_sign, Dbar, z0, Dz0, topo, cmap,
                           psi, coef, ang, fe, rE, r, data, fe_geo, rEg, rg, Keb, KEb):
    """``element_tangent`` by compute-then-gather: element blocks Keb (m,4,4,6,6) and edge
    blocks KEb (E,2,2,6,6) are stored (parallel, no colours), then every CSR block sums its
    contributors (``cmap.src``) and is written once (no zeroing of data needed).  The same
    mixed option as ``element_tangent`` (fe_geo, rEg, rg: arrays or None)."""
    nE = edge_nodes.shape[0]
    m = elem_edges.shape[0]
    n = r.shape[0]
    nchE = (nE + CHUNK - 1) // CHUNK
    for ch in prange(nchE):
        R = np.empty((3, 3))
        for e in range(ch * CHUNK, min(nE, (ch + 1) * CHUNK)):
            ang[e] = edge_pass1(g, edge_nodes, e, R, psi, coef)
    flag, bad = check_angles(ang)
    if flag:
        return 0.0, 0.0, flag, bad
    energy = 0.0
    fs = 0.0
    nchm = (m + CHUNK - 1) // CHUNK
    for ch in prange(nchm):
        z = np.empty(24)
        f = np.empty(24)
        G = np.empty((4, 2, 6, 6))
        TT = np.empty((24, 24))
        TTt = np.empty((24, 24))
        KeT = np.empty((24, 24))
        for el in range(ch * CHUNK, min(m, (ch + 1) * CHUNK)):
            a, b = element_force(el, elem_edges, elem_edge_sign, Dbar, z0, Dz0, psi, z, f, fe)
            energy += a
            fs += b
            element_G(el, elem_edges, elem_edge_sign, psi, coef, G)
            element_Ke(el, Dbar, G, TT, TTt, KeT)
            for A in range(4):
                for B in range(4):
                    for i in range(6):
                        for j in range(6):
                            Keb[el, A, B, i, j] = KeT[6 * A + i, 6 * B + j]
    for ch in prange(nchE):
        F = np.empty(6)
        Fg = np.empty(6) if fe_geo is not None else F
        p = np.empty(6)
        Lp = np.empty((6, 6))
        Lm = np.empty((6, 6))
        Ad = np.empty((6, 6))
        Jm = np.empty((6, 6))
        Y = np.empty((12, 6))
        H = np.empty((12, 12))
        for e in range(ch * CHUNK, min(nE, (ch + 1) * CHUNK)):
            edge_F(e, topo.edge_slots, fe, F)
            edge_residual(e, psi, coef, F, rE)
            if fe_geo is not None:
                edge_F(e, topo.edge_slots, fe_geo, Fg)
                edge_residual(e, psi, coef, Fg, rEg)
                edge_KE(e, psi, coef, Fg, Lp, Lm, Ad, Jm, Y, H, p)
            else:
                edge_KE(e, psi, coef, F, Lp, Lm, Ad, Jm, Y, H, p)
            for I in range(2):
                for J in range(2):
                    for i in range(6):
                        for j in range(6):
                            KEb[e, I, J, i, j] = H[6 * I + i, 6 * J + j]
    nb = cmap.blk_a.size
    ke = Keb.reshape(-1, 6, 6)
    kE = KEb.reshape(-1, 6, 6)
    m16 = 16 * m
    nchb = (nb + CHUNK - 1) // CHUNK
    for ch in prange(nchb):
        S = np.empty((6, 6))
        for blk in range(ch * CHUNK, min(nb, (ch + 1) * CHUNK)):
            S[:, :] = 0.0
            for t in range(cmap.src_ptr[blk], cmap.src_ptr[blk + 1]):
                q = cmap.src[t]
                if q < m16:
                    for i in range(6):
                        for j in range(6):
                            S[i, j] += ke[q, i, j]
                else:
                    for i in range(6):
                        for j in range(6):
                            S[i, j] += kE[q - m16, i, j]
            A, B = cmap.blk_a[blk], cmap.blk_b[blk]
            cs = cmap.colstart[blk]
            for i in range(6):
                rb = cmap.rowbase[A, i]
                if rb < 0:
                    continue
                for j in range(6):
                    cr = cmap.colrank[B, j]
                    if cr >= 0:
                        data[rb + cs + cr] = S[i, j]
    nchn = (n + CHUNK - 1) // CHUNK
    for ch in prange(nchn):
        K6 = np.empty((6, 6))
        for nd in range(ch * CHUNK, min(n, (ch + 1) * CHUNK)):
            node_residual(nd, topo.node_ptr, topo.node_inc, rE, r)
            if rEg is not None:
                node_residual(nd, topo.node_ptr, topo.node_inc, rEg, rg)
                node_Kn(nd, rg, data, cmap, K6)
            else:
                node_Kn(nd, r, data, cmap, K6)
    return energy, sqrt(fs), 0, -1


# ------------------------------------------------------------------------------------------
# Python wrapper of the element kernels
# ------------------------------------------------------------------------------------------
SERIAL_BELOW = 1500   # elements: below this the serial driver is faster (threading overhead)


class ElementKernels:
    """The default element on plain arrays, with preallocated workspace.

    Parameters
    ----------
    quads (m,4), edge_nodes (E,2), elem_edges (m,4), elem_edge_sign (m,4) : mesh topology
    Dbar (m,24,24), z0 (m,24), Dz0 (m,24) : DefaultElement's constant data
    pattern : Pattern of the free dofs
    mode : 'auto' (serial below SERIAL_BELOW elements, else 'gather'), 'serial', 'colour', 'gather'
    error : exception class raised when an edge turns by more than MAX_EDGE_ANGLE
    """

    def __init__(self, quads, edge_nodes, elem_edges, elem_edge_sign, Dbar, z0, Dz0, pattern,
                 mode="auto", error=RuntimeError):
        c = np.ascontiguousarray
        self.quads = c(quads, dtype=np.int64)
        self.edge_nodes = c(edge_nodes, dtype=np.int64)
        self.elem_edges = c(elem_edges, dtype=np.int64)
        self.sign = c(elem_edge_sign, dtype=np.int64)
        self.Dbar, self.z0, self.Dz0 = c(Dbar, dtype=float), c(z0, dtype=float), c(Dz0, dtype=float)
        self.pattern = pattern
        m, nE, n = len(self.quads), len(self.edge_nodes), pattern.n
        if mode == "auto":
            mode = "serial" if m < SERIAL_BELOW else "gather"
        if mode not in ("serial", "colour", "gather"):
            raise ValueError(f"unknown mode {mode!r}")
        self.mode = mode
        self.error = error
        self.psi = np.zeros((nE, 6))
        self.coef = np.zeros((nE, 3))
        self.ang = np.zeros(nE)
        self.fe = np.zeros((m, 4, 6))
        self.rE = np.zeros((nE, 2, 6))
        self.r = np.zeros((n, 6))
        self.fe_geo = np.zeros((m, 4, 6))      # the mixed tangent's workspace (signed stresses,
        self.rEg = np.zeros((nE, 2, 6))        # their edge-end and nodal forces)
        self.rg = np.zeros((n, 6))
        self.data = pattern.new_data()
        if mode == "gather":
            self.Keb = np.zeros((m, 4, 4, 6, 6))
            self.KEb = np.zeros((nE, 2, 2, 6, 6))

    @classmethod
    def from_element(cls, element, pattern, **kw):
        """From a ``DefaultElement``-like object (attributes mesh, Dbar, z0, Dz0).

        The reference edge twists z0 are recomputed by these kernels at the reference frames
        g0, so that the reference state is stress free to the last bit in this backend too (the
        kernels form Ra^T (pb - pa), the NumPy element log(ga^-1 gb): they differ by round-off).
        """
        mesh = element.mesh
        self = cls(mesh.quads, mesh.edge_nodes, mesh.elem_edges, mesh.elem_edge_sign,
                   element.Dbar, element.z0, element.Dz0, pattern, **kw)
        self.residual(np.ascontiguousarray(mesh.g0, dtype=float))
        z0 = (self.sign[..., None] * (0.5 * self.psi)[self.elem_edges]).reshape(-1, 24)
        self.z0 = np.ascontiguousarray(z0)
        self.Dz0 = np.ascontiguousarray(np.einsum("mij,mj->mi", self.Dbar, z0))
        return self

    def _raise(self, e):
        a, b = self.edge_nodes[e].tolist()
        ang = float(self.ang[e])
        raise self.error(
            f"edge {[a, b]} turns by {ang:.3f} rad (>= {MAX_EDGE_ANGLE:.3f}); the relative rotation "
            "across an element must stay below pi: refine the mesh or the load step")

    def residual(self, g):
        """dict(energy, r (n,6) -- a view of the workspace, force_scale, stress (m,24) -- the
        displacement stresses Dbar (z - z0), a new array)."""
        g = np.ascontiguousarray(g, dtype=float)
        fn = element_residual_serial if self.mode == "serial" else element_residual
        en, fs, flag, e = fn(g, self.edge_nodes, self.elem_edges, self.sign, self.Dbar, self.z0,
                             self.Dz0, self.pattern.topo, self.psi, self.coef, self.ang, self.fe,
                             self.rE, self.r)
        if flag:
            self._raise(e)
        return {"energy": en, "r": self.r, "force_scale": fs, "stress": stress_from_signed(self.fe, self.sign)}

    def tangent(self, g, data=None, stress=None):
        """dict(energy, r, force_scale, stress, data): data (nnz,) of the free-dof CSR, element
        part; stress as in :meth:`residual`.

        stress : (m, 24) independent element stresses, or None.  Given, the geometric part of
        the tangent (edge blocks and 1/2 adt(r)) is built from their forces (the mixed
        iteration, ``DefaultElement.evaluate(g, stress=...)``); r, energy and the material
        blocks stay those of Dbar (z(g) - z0)."""
        g = np.ascontiguousarray(g, dtype=float)
        data = self.data if data is None else data
        mixed = (None, None, None)
        if stress is not None:
            mixed = (signed_edge_stress(stress, self.sign, self.fe_geo), self.rEg, self.rg)
        args = (g, self.quads, self.edge_nodes, self.elem_edges, self.sign, self.Dbar, self.z0,
                self.Dz0, self.pattern.topo, self.pattern.map, self.psi, self.coef, self.ang,
                self.fe, self.rE, self.r, data, *mixed)
        if self.mode == "serial":
            en, fs, flag, e = element_tangent_serial(*args)
        elif self.mode == "colour":
            en, fs, flag, e = element_tangent(*args)
        else:
            en, fs, flag, e = element_tangent_gather(*args, self.Keb, self.KEb)
        if flag:
            self._raise(e)
        return {"energy": en, "r": self.r, "force_scale": fs, "data": data,
                "stress": stress_from_signed(self.fe, self.sign)}

    def linear_stress(self, eta):
        """Element stresses linearised about the state of the last :meth:`residual` or
        :meth:`tangent` call: Dbar (z(g) - z0 + G eta) (m, 24), a new array
        (``DefaultElement.linear_stress``).

        Parameters
        ----------
        eta : (n, 6) array_like
            Nodal increments (g <- g exp(eta)).
        """
        eta = np.ascontiguousarray(eta, dtype=float).reshape(-1, 6)
        if eta.shape[0] != self.r.shape[0]:
            raise ValueError(f"eta must have {self.r.shape[0]} rows of 6, got {eta.shape[0]}")
        out = np.empty((len(self.quads), 24))
        fn = element_linear_stress_serial if self.mode == "serial" else element_linear_stress
        fn(self.quads, self.elem_edges, self.sign, self.Dbar, self.z0, self.psi, self.coef, eta, out)
        return out
