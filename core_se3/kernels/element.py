"""The default element on plain arrays (numba): residual-only and residual + tangent drivers,
serial (small meshes), coloured and gathering (parallel over elements, race-free), and the
Python wrapper :class:`ElementKernels` with its preallocated workspace.

The tangent drivers write the element's blocks (material G^T Dbar G, edge geometric, nodal
1/2 adt(r)) straight into the CSR ``data`` of the free-dof pattern (``kernels.csr``): no COO to
CSR conversion and no pattern-sized allocation per iteration.  Dbar is read in its split form
(two 12x12 blocks per element) when its v-w coupling is exactly zero, as for every law of
``fem.material``, else unpacked per element (``element_ops``' module docstring).
"""
from __future__ import annotations

from math import sqrt

import numpy as np
from numba import njit, prange

from ..errors import edge_turn_error
from .element_mixed import element_linear_stress, element_linear_stress_serial, signed_edge_stress, stress_from_signed
from .element_dbar import NSYM, packed_matvec, split_form
from .element_ops import CHUNK, MAX_EDGE_ANGLE, check_angles
from .element_passes import (ElementData, ElementMesh, Workspace, edges_log, edges_residual, edges_tangent,
                             edges_tangent_store, elements_force, elements_tangent, elements_tangent_store,
                             nodes_pass)

__all__ = ["ElementKernels", "element_residual", "element_residual_serial", "element_tangent",
           "element_tangent_serial", "element_tangent_gather", "SERIAL_BELOW"]

@njit(cache=True, parallel=True)
def element_residual(g, mesh, ed, topo, w):
    """Residual only.  Returns (energy, force_scale, flag, edge); w.r (n, 6) is written.

    energy = 1/2 sum_e dz^T Dbar dz, dz = z - z0, z = (sgn psi / 2) over the 4 edges;
    F_E = sum over elements of sgn f (f = Dbar dz); r_a += -1/2 L(-psi)^T F, r_b += 1/2 L(psi)^T F;
    force_scale = sqrt(sum |f + Dz0|^2 + |f|^2).  Dbar (m,300) packed, Dsplit (m,24,12) its
    split form or empty (0,24,12) for the general path (``ElementKernels.split``): the fields of
    ``ed`` (``ElementData``); mesh: ``ElementMesh``; workspace w (``Workspace``): psi (E,6),
    coef (E,3), ang (E,), fe (m,4,6), rE (E,2,6), r.  Parallel over edges, elements, nodes (no
    colouring needed)."""
    nE, m, n = mesh.edge_nodes.shape[0], mesh.elem_edges.shape[0], w.r.shape[0]
    for ch in prange((nE + CHUNK - 1) // CHUNK):
        edges_log(g, mesh, w, ch * CHUNK, min(nE, (ch + 1) * CHUNK))
    flag, bad = check_angles(w.ang)
    if flag:
        return 0.0, 0.0, flag, bad
    energy = 0.0
    fs = 0.0
    for ch in prange((m + CHUNK - 1) // CHUNK):
        a, b = elements_force(mesh, ed, w, ch * CHUNK, min(m, (ch + 1) * CHUNK))
        energy += a
        fs += b
    for ch in prange((nE + CHUNK - 1) // CHUNK):
        edges_residual(topo, mesh.Rk, w, ch * CHUNK, min(nE, (ch + 1) * CHUNK))
    for ch in prange((n + CHUNK - 1) // CHUNK):
        nodes_pass(topo, mesh.Rq, w, None, None, None, None, ch * CHUNK, min(n, (ch + 1) * CHUNK))
    return energy, sqrt(fs), 0, -1


@njit(cache=True)
def element_residual_serial(g, mesh, ed, topo, w):
    """``element_residual`` in one thread."""
    nE, m, n = mesh.edge_nodes.shape[0], mesh.elem_edges.shape[0], w.r.shape[0]
    edges_log(g, mesh, w, 0, nE)
    flag, bad = check_angles(w.ang)
    if flag:
        return 0.0, 0.0, flag, bad
    energy, fs = elements_force(mesh, ed, w, 0, m)
    edges_residual(topo, mesh.Rk, w, 0, nE)
    nodes_pass(topo, mesh.Rq, w, None, None, None, None, 0, n)
    return energy, sqrt(fs), 0, -1


@njit(cache=True, parallel=True)
def element_tangent(g, mesh, ed, topo, cmap, w, data, mixed):
    """Residual and tangent of the default element, written into the CSR ``data`` (nnz,).

    Coloured, fused compute + scatter (parallel within each colour, race-free):

      1. edges:    psi = log(g_a^-1 g_b), c, c'/t, (c'/t)'/t of |w|^2;
      2. elements: f = Dbar (z - z0), Ke = G^T Dbar G (element.py's material part), scattered;
      3. edges:    F = sum of sgn f, r_a = -L(-psi)^T F/2, r_b = L(psi)^T F/2 and the geometric
                   block H (element.py: A = M^T J_m N, H = (A + A^T)/4 + adt terms), scattered;
      4. nodes:    r = sum of edge ends, Kn = adt(r)/2 on the diagonal block.

    data is zeroed first; loads add their blocks afterwards.  Returns (energy, force_scale,
    flag, edge) like ``element_residual``; on flag = 1 nothing past pass 1 is computed.

    Mixed iteration (mixed = (fe_geo, rEg, rg) arrays; Magisano, Leonetti and Garcea 2017): the
    geometric part sees independent stresses, fe_geo (m,4,6) = their signed edge parts (like
    fe): pass 3 also forms F_geo = sum of fe_geo and its nodal parts into rEg (E,2,6), H is
    built with F_geo, and pass 4 sums r_geo into rg (n,6) and writes 1/2 adt(r_geo).  The
    residual, the energy and the material blocks do not change.  fe_geo = rEg = rg = None:
    the ordinary tangent (a separate compiled version: the mixed branches are pruned)."""
    fe_geo, rEg, rg = mixed
    nE, n = mesh.edge_nodes.shape[0], w.r.shape[0]
    for i in prange(data.size):
        data[i] = 0.0
    for ch in prange((nE + CHUNK - 1) // CHUNK):
        edges_log(g, mesh, w, ch * CHUNK, min(nE, (ch + 1) * CHUNK))
    flag, bad = check_angles(w.ang)
    if flag:
        return 0.0, 0.0, flag, bad
    energy = 0.0
    fs = 0.0
    cptr, order = topo.elem_cptr, topo.elem_order
    for col in range(len(cptr) - 1):
        lo, hi = cptr[col], cptr[col + 1]
        for ch in prange((hi - lo + CHUNK - 1) // CHUNK):
            a, b = elements_tangent(order, mesh, ed, w, cmap, data, lo + ch * CHUNK,
                                    min(hi, lo + (ch + 1) * CHUNK))
            energy += a
            fs += b
    cptr, order = topo.edge_cptr, topo.edge_order
    for col in range(len(cptr) - 1):
        lo, hi = cptr[col], cptr[col + 1]
        for ch in prange((hi - lo + CHUNK - 1) // CHUNK):
            edges_tangent(order, mesh, topo, w, fe_geo, rEg, cmap, data, lo + ch * CHUNK,
                          min(hi, lo + (ch + 1) * CHUNK))
    for ch in prange((n + CHUNK - 1) // CHUNK):
        nodes_pass(topo, mesh.Rq, w, rEg, rg, data, cmap, ch * CHUNK, min(n, (ch + 1) * CHUNK))
    return energy, sqrt(fs), 0, -1


@njit(cache=True)
def element_tangent_serial(g, mesh, ed, topo, cmap, w, data, mixed):
    """``element_tangent`` in one thread, natural order (no threading overhead: small meshes);
    the same mixed option (mixed = (fe_geo, rEg, rg): arrays or None)."""
    fe_geo, rEg, rg = mixed
    nE, m, n = mesh.edge_nodes.shape[0], mesh.elem_edges.shape[0], w.r.shape[0]
    data[:] = 0.0
    edges_log(g, mesh, w, 0, nE)
    flag, bad = check_angles(w.ang)
    if flag:
        return 0.0, 0.0, flag, bad
    energy, fs = elements_tangent(None, mesh, ed, w, cmap, data, 0, m)
    edges_tangent(None, mesh, topo, w, fe_geo, rEg, cmap, data, 0, nE)
    nodes_pass(topo, mesh.Rq, w, rEg, rg, data, cmap, 0, n)
    return energy, sqrt(fs), 0, -1


@njit(cache=True, parallel=True)
def element_tangent_gather(g, mesh, ed, topo, cmap, w, data, mixed, store):
    """``element_tangent`` by compute-then-gather: element blocks Keb (m,4,4,6,6) and edge
    blocks KEb (E,2,2,6,6) (store = (Keb, KEb)) are stored (parallel, no colours), then every
    CSR block sums its contributors (``cmap.src``) and is written once (no zeroing of data
    needed).  The same mixed option as ``element_tangent`` (fe_geo, rEg, rg: arrays or None)."""
    fe_geo, rEg, rg = mixed
    Keb, KEb = store
    nE, m, n = mesh.edge_nodes.shape[0], mesh.elem_edges.shape[0], w.r.shape[0]
    for ch in prange((nE + CHUNK - 1) // CHUNK):
        edges_log(g, mesh, w, ch * CHUNK, min(nE, (ch + 1) * CHUNK))
    flag, bad = check_angles(w.ang)
    if flag:
        return 0.0, 0.0, flag, bad
    energy = 0.0
    fs = 0.0
    for ch in prange((m + CHUNK - 1) // CHUNK):
        a, b = elements_tangent_store(mesh, ed, w, Keb, ch * CHUNK, min(m, (ch + 1) * CHUNK))
        energy += a
        fs += b
    for ch in prange((nE + CHUNK - 1) // CHUNK):
        edges_tangent_store(mesh, topo, w, fe_geo, rEg, KEb, ch * CHUNK, min(nE, (ch + 1) * CHUNK))
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
    for ch in prange((n + CHUNK - 1) // CHUNK):
        nodes_pass(topo, mesh.Rq, w, rEg, rg, data, cmap, ch * CHUNK, min(n, (ch + 1) * CHUNK))
    return energy, sqrt(fs), 0, -1


# ------------------------------------------------------------------------------------------
# Python wrapper of the element kernels
# ------------------------------------------------------------------------------------------
def _quarter_turns(k):
    """Rz(k pi/2) (E, 3, 3) of the quarter turns k (E,), exact (``mesh.gauge.quarter_turns``)."""
    k = np.asarray(k, dtype=np.int64) % 4
    c, s = np.array([1.0, 0.0, -1.0, 0.0])[k], np.array([0.0, 1.0, 0.0, -1.0])[k]
    R = np.zeros((len(k), 3, 3))
    R[:, 0, 0] = R[:, 1, 1] = c
    R[:, 1, 0], R[:, 0, 1] = s, -s
    R[:, 2, 2] = 1.0
    return R


SERIAL_BELOW = 1500   # elements: below this the serial driver is faster (threading overhead)


class ElementKernels:
    """The default element on plain arrays, with preallocated workspace.

    Parameters
    ----------
    quads (m,4), edge_nodes (E,2), elem_edges (m,4), elem_edge_sign (m,4) : mesh topology
    Dbar (m,300) (the upper triangles, row by row: ``DefaultElement.Dbar_packed``), z0 (m,24),
    Dz0 (m,24) : DefaultElement's constant data
    pattern : Pattern of the free dofs
    gauge : (n, 4, 4) array or None
        The constant turns Q of the element's frames g Q about the nodal normals
        (``fem.element_default``, "Frames"): the drivers take g Q and return forces and blocks
        in the user's frames; None (the default) where there are none.
    matching : (E,) int array or None
        The edges' quarter turns across a cross field's cuts (``fem.element_default``, "Cuts":
        psi = log(g_a^-1 g_b Rz(k pi/2))); None (the default) where there are none.
    mode : 'auto' (serial below SERIAL_BELOW elements, else 'gather'), 'serial', 'colour', 'gather'
    error : exception class raised when an edge turns by more than MAX_EDGE_ANGLE

    Attributes
    ----------
    split : bool
        Whether Dbar's v-w coupling blocks are exactly zero on every element (every law of
        ``fem.material``): the element passes then read ``Dsplit`` (m, 24, 12), the two 12x12
        diagonal blocks in the order z' (``element_ops.split_form``: no unpacking, half the
        force products and half of G^T Dbar's), or (m, 24, 16) with the membrane-drilling
        coupling of distorted quads in 4 more columns, else the general path unpacks the packed
        Dbar per element (a law coupling v and w; ``Dsplit`` is then empty, (0, 24, 12)).
    """

    def __init__(self, quads, edge_nodes, elem_edges, elem_edge_sign, Dbar, z0, Dz0, pattern,
                 mode="auto", error=RuntimeError, gauge=None, matching=None):
        c = np.ascontiguousarray
        self.Rk = np.empty((0, 3, 3)) if matching is None else _quarter_turns(matching)
        self.gauge = None if gauge is None else c(gauge, dtype=float)
        self.Rq = np.empty((0, 3, 3)) if gauge is None else c(self.gauge[:, :3, :3])
        self.quads = c(quads, dtype=np.int64)
        self.edge_nodes = c(edge_nodes, dtype=np.int64)
        self.elem_edges = c(elem_edges, dtype=np.int64)
        self.sign = c(elem_edge_sign, dtype=np.int64)
        self.Dbar, self.z0, self.Dz0 = c(Dbar, dtype=float), c(z0, dtype=float), c(Dz0, dtype=float)
        if self.Dbar.shape != (len(self.quads), NSYM):
            raise ValueError(f"Dbar must be packed ({len(self.quads)}, {NSYM}), got {self.Dbar.shape}")
        Ds = split_form(self.Dbar)
        self.split = Ds is not None
        self.Dsplit = Ds if Ds is not None else np.empty((0, 24, 12))
        self.pattern = pattern
        m, nE, n = len(self.quads), len(self.edge_nodes), pattern.n
        if mode == "auto":
            mode = "serial" if m < SERIAL_BELOW else "gather"
        if mode not in ("serial", "colour", "gather"):
            raise ValueError(f"unknown mode {mode!r}")
        self.mode = mode
        self.error = error
        self.whole_ids = None                  # (elements, nodes) of the whole mesh (a rank's part)
        self.psi = np.zeros((nE, 6))
        self.coef = np.zeros((nE, 3))
        self.ang = np.zeros(nE)
        self.fe = np.zeros((m, 4, 6))
        self.rE = np.zeros((nE, 2, 6))
        self.r = np.zeros((n, 6))
        self.fe_geo = np.zeros((m, 4, 6))      # the mixed tangent's workspace (signed stresses,
        self.rEg = np.zeros((nE, 2, 6))        # their edge-end and nodal forces)
        self.rg = np.zeros((n, 6))
        self._data = None                      # the CSR data when the caller gives none (lazy:
                                               # a distributed run writes into PETSc's input)
        if mode == "gather":
            self.Keb = np.zeros((m, 4, 4, 6, 6))
            self.KEb = np.zeros((nE, 2, 2, 6, 6))

    @classmethod
    def from_element(cls, element, pattern, **kw):
        """From a ``DefaultElement``-like object (attributes mesh, Dbar_packed, z0, Dz0).

        The reference edge twists z0 are recomputed by these kernels at the reference frames
        g0, so that the reference state is stress free to the last bit in this backend too (both
        form Ra^T (pb - pa), the NumPy element with ``lie.relative``; their logs differ by round-off).
        """
        mesh = element.mesh
        self = cls(mesh.quads, mesh.edge_nodes, mesh.elem_edges, mesh.elem_edge_sign,
                   element.Dbar_packed, element.z0, element.Dz0, pattern, gauge=getattr(element, "gauge", None),
                   matching=getattr(element, "matching", None), **kw)
        self.whole_ids = getattr(mesh, "whole_ids", None)      # a rank's part: its errors name the whole mesh's nodes
        self.residual(np.ascontiguousarray(mesh.g0, dtype=float))
        z0 = (self.sign[..., None] * (0.5 * self.psi)[self.elem_edges]).reshape(-1, 24)
        self.z0 = np.ascontiguousarray(z0)
        self.Dz0 = np.empty_like(self.z0)
        packed_matvec(self.Dbar, self.z0, self.Dz0)
        return self

    def _element_frames(self, g):
        """g Q (contiguous): the element's frames of the nodal frames g (``gauge``)."""
        g = np.ascontiguousarray(g, dtype=float)
        return g if self.gauge is None else np.ascontiguousarray(g @ self.gauge)

    def _raise(self, e):
        """The error of edge e turning by pi, its nodes named by the whole mesh's ids (``whole_ids``)."""
        exc = edge_turn_error(self.edge_nodes, e, float(self.ang[e]), MAX_EDGE_ANGLE, self)
        raise self.error(str(exc))

    def bundles(self):
        """(ElementMesh, ElementData, Workspace): the arrays the drivers take, from the
        attributes of the moment (``element_passes``' bundles; views, no copies)."""
        return (ElementMesh(self.quads, self.edge_nodes, self.elem_edges, self.sign, self.Rq, self.Rk),
                ElementData(self.Dbar, self.Dsplit, self.z0, self.Dz0),
                Workspace(self.psi, self.coef, self.ang, self.fe, self.rE, self.r))

    def residual(self, g):
        """dict(energy, r (n,6) -- a view of the workspace, force_scale, stress (m,24) -- the
        displacement stresses Dbar (z - z0), a new array)."""
        g = self._element_frames(g)
        fn = element_residual_serial if self.mode == "serial" else element_residual
        mesh, ed, w = self.bundles()
        en, fs, flag, e = fn(g, mesh, ed, self.pattern.topo, w)
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
        g = self._element_frames(g)
        if data is None:
            if self._data is None:
                self._data = self.pattern.new_data()
            data = self._data
        mixed = (None, None, None)
        if stress is not None:
            mixed = (signed_edge_stress(stress, self.sign, self.fe_geo), self.rEg, self.rg)
        mesh, ed, w = self.bundles()
        args = (g, mesh, ed, self.pattern.topo, self.pattern.map, w, data, mixed)
        if self.mode == "serial":
            en, fs, flag, e = element_tangent_serial(*args)
        elif self.mode == "colour":
            en, fs, flag, e = element_tangent(*args)
        else:
            en, fs, flag, e = element_tangent_gather(*args, (self.Keb, self.KEb))
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
        if self.gauge is not None:                 # Ad_{Q^-1} eta: the element's frames
            R = self.Rq
            eta = np.ascontiguousarray(np.concatenate([np.einsum("nji,nj->ni", R, eta[:, :3]),
                                                       np.einsum("nji,nj->ni", R, eta[:, 3:])], 1))
        out = np.empty((len(self.quads), 24))
        fn = element_linear_stress_serial if self.mode == "serial" else element_linear_stress
        fn(self.quads, self.elem_edges, self.sign, self.Rk, self.Dbar, self.z0, self.psi, self.coef, eta, out)
        return out
