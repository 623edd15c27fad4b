"""The fixed sparsity pattern of the compiled backend: the block -> CSR map built once per mesh and
support set (NumPy), the mesh colourings and incidences, and the scatter of 6x6 blocks into the
CSR ``data`` array (numba).

The entry (i, j) of node-pair block b = (A, B) sits at ``data[rowbase[A, i] + colstart[b] +
colrank[B, j]]`` when dofs (A, i) and (B, j) are free (-1 otherwise); ``indptr``/``indices``
equal those of ``core_se3.assembly.Assembler``, so the compiled and the reference CSR matrices
compare entry by entry.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np
import scipy.sparse as sp
from numba import njit

__all__ = ["Topology", "CsrMap", "greedy_colouring", "Pattern", "scatter", "scatter_diag", "scatter_node_blocks",
           "scatter_element_blocks", "add_blocks"]

# ------------------------------------------------------------------------------------------
# Pattern: CSR of the free dofs and the block -> CSR map (built once per mesh, NumPy)
# ------------------------------------------------------------------------------------------
Topology = namedtuple("Topology", "edge_slots node_ptr node_inc elem_cptr elem_order edge_cptr edge_order")
Topology.__doc__ = """Mesh incidence for the gathers and the colourings (all int64).

edge_slots (E, 2): flat ids el*4+k of the (<= 2) element sides of each edge, -1 if none;
node_ptr (n+1,), node_inc (2E,): CSR node -> edge ends e*2+side (side 0: edge_nodes[e,0]);
elem_cptr (ncol+1,), elem_order (m,): elements grouped by colour;
edge_cptr, edge_order: the same for edges."""

CsrMap = namedtuple("CsrMap", "elem_blk edge_blk diag_blk rowbase colstart colrank full blk_a blk_b src_ptr src")
CsrMap.__doc__ = """Block -> CSR data positions.

The entry (i, j) of node-pair block b = (A, B) sits at
    data[rowbase[A, i] + colstart[b] + colrank[B, j]]
when dof (A, i) and dof (B, j) are free (rowbase, colrank = -1 otherwise); full (n,) marks
the nodes with all six dofs free.
elem_blk (m,4,4), edge_blk (E,2,2), diag_blk (n,): block ids; blk_a, blk_b (nb,): the node
pair of each block (sorted by (A, B)); src_ptr (nb+1,), src: for the
gather variant, the contributing element blocks (el*16 + a*4 + b) and edge blocks
(m*16 + e*4 + I*2 + J) of every block."""


@njit(cache=True)
def greedy_colouring(items):
    """Colour (k,) of items (k, p) of node ids: greedy, lowest colour not used by an item
    sharing a node (bit masks per node, < 64 colours).  Returns (colour, ncolours)."""
    k, p = items.shape
    n = items.max() + 1 if k else 0
    mask = np.zeros(n, np.int64)
    colour = np.empty(k, np.int64)
    ncol = 0
    for e in range(k):
        used = np.int64(0)
        for a in range(p):
            used |= mask[items[e, a]]
        c = 0
        while (used >> c) & 1:
            c += 1
        colour[e] = c
        ncol = max(ncol, c + 1)
        bit = np.int64(1) << c
        for a in range(p):
            mask[items[e, a]] |= bit
    return colour, ncol


PATTERN_CHUNK = 1 << 16   # node-pair blocks per chunk of the pattern's set-up


def _group(colour, ncol):
    order = np.argsort(colour, kind="stable").astype(np.int64)
    cptr = np.concatenate([[0], np.cumsum(np.bincount(colour, minlength=ncol))]).astype(np.int64)
    return cptr, order


class Pattern:
    """CSR pattern of the free-dof tangent and the maps that fill its ``data`` in place.

    Parameters
    ----------
    quads : (m, 4) int, edge_nodes : (E, 2) int, elem_edges : (m, 4) int, n_nodes : int,
    free : (6n,) bool -- the free dofs (constrained rows and columns are dropped).

    The blocks are the node pairs of element (4x4), edge (2x2) and nodal (1x1) couplings
    (as ``core_se3.assembly.Assembler``); rows are the free dofs in order, and columns in a
    row are sorted, so ``indptr``/``indices`` equal the Assembler's.  Built with NumPy only
    (np.unique on node-pair keys, cumulative sums), once per mesh and support set.
    """

    def __init__(self, quads, edge_nodes, elem_edges, n_nodes, free):
        quads = np.asarray(quads, np.int64)
        En = np.asarray(edge_nodes, np.int64)
        n = int(n_nodes)
        m, nE = len(quads), len(En)
        self.n, self.m, self.nE = n, m, nE
        free = np.asarray(free, bool).reshape(n, 6)
        self.free = free.ravel()
        keys = np.concatenate([(quads[:, :, None] * n + quads[:, None, :]).ravel(),
                               (En[:, :, None] * n + En[:, None, :]).ravel(),
                               np.arange(n, dtype=np.int64) * (n + 1)])
        ukeys, inv = np.unique(keys, return_inverse=True)
        nb = len(ukeys)
        self.nblocks = nb
        elem_blk = inv[:16 * m].reshape(m, 4, 4)
        edge_blk = inv[16 * m:16 * m + 4 * nE].reshape(nE, 2, 2)
        diag_blk = inv[16 * m + 4 * nE:]
        bA, bB = ukeys // n, ukeys % n
        nf = free.sum(1)                                               # free dofs per node
        wcol = nf[bB]
        excl = np.cumsum(wcol) - wcol                                   # free cols before b
        first = np.searchsorted(bA, np.arange(n))                       # first block of row A
        colstart = excl - excl[first[bA]]
        rowlen = np.bincount(bA, weights=wcol, minlength=n).astype(np.int64)
        red = -np.ones(6 * n, np.int64)
        red[free.ravel()] = np.arange(int(free.sum()))
        self.nfree = int(free.sum())
        lens = np.repeat(rowlen, 6)[free.ravel()]
        indptr = np.concatenate([[0], np.cumsum(lens)]).astype(np.int64)
        rowbase = np.where(free.ravel(), indptr[np.maximum(red, 0)], -1).reshape(n, 6)
        colrank = np.where(free, np.cumsum(free, 1) - 1, -1).astype(np.int64)
        self.nnz = int(indptr[-1])
        # indices: every free (row, col) of every block at its position, in chunks of blocks
        # (the (k, 6, 6) position and column arrays take 17 bytes per entry)
        i = np.arange(6)
        self.indices = np.empty(self.nnz, np.int32)
        for s in range(0, nb, PATTERN_CHUNK):
            a, b = bA[s:s + PATTERN_CHUNK], bB[s:s + PATTERN_CHUNK]
            ok = free[a][:, :, None] & free[b][:, None, :]               # (k, 6, 6)
            pos = rowbase[a][:, :, None] + colstart[s:s + PATTERN_CHUNK, None, None] + colrank[b][:, None, :]
            col = np.broadcast_to(6 * b[:, None, None] + i[None, None, :], ok.shape)
            self.indices[pos[ok]] = red[col[ok]]
        self.indptr = indptr.astype(np.int32)
        # gather lists: contributors of every block
        contrib = np.concatenate([elem_blk.ravel(), edge_blk.ravel()])
        order = np.argsort(contrib, kind="stable").astype(np.int64)
        src_ptr = np.concatenate([[0], np.cumsum(np.bincount(contrib, minlength=nb))]).astype(np.int64)
        self.map = CsrMap(elem_blk.astype(np.int64), edge_blk.astype(np.int64), diag_blk.astype(np.int64),
                          rowbase.astype(np.int64), colstart.astype(np.int64), colrank, free.all(1), bA.astype(np.int64),
                          bB.astype(np.int64), src_ptr, order)
        # topology: edge sides, node -> edge ends, colourings
        ee = np.asarray(elem_edges, np.int64).ravel()
        srt = np.argsort(ee, kind="stable")
        cnt = np.bincount(ee, minlength=nE)
        start = np.concatenate([[0], np.cumsum(cnt)[:-1]])
        edge_slots = -np.ones((nE, 2), np.int64)
        rank = np.arange(len(ee)) - start[ee[srt]]
        edge_slots[ee[srt], rank] = srt
        ends = En.ravel()
        node_inc = np.argsort(ends, kind="stable").astype(np.int64)
        node_ptr = np.concatenate([[0], np.cumsum(np.bincount(ends, minlength=n))]).astype(np.int64)
        ecol, nec = greedy_colouring(quads)
        self.elem_colour = ecol
        gcol, ngc = greedy_colouring(En)
        ec, eo = _group(ecol, nec)
        gc, go = _group(gcol, ngc)
        self.topo = Topology(edge_slots, node_ptr, node_inc, ec, eo, gc, go)

    def group_elements(self, elements):
        """(cptr, order): positions into ``elements`` grouped by the mesh colouring (for element
        loads: race-free within a colour as long as ``elements`` has no repeats)."""
        el = np.asarray(elements, np.int64)
        ncol = int(self.elem_colour.max()) + 1
        return _group(self.elem_colour[el], ncol)

    def new_data(self):
        return np.zeros(self.nnz)

    def matrix(self, data):
        """scipy CSR (nfree, nfree) sharing ``data`` (no copy)."""
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.nfree, self.nfree), copy=False)


# ------------------------------------------------------------------------------------------
# Scatter helpers
# ------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def scatter(data, cmap, blk, A, B, M, i0, j0, transpose, s):
    """data[block (A,B)] += s * M[i0:i0+6, j0:j0+6] (or of M^T's sub-block if ``transpose``).

    Position of entry (i, j): rowbase[A, i] + colstart[blk] + colrank[B, j], skipped where a
    dof is constrained (-1).  Fast path when all 12 dofs are free: contiguous rows of 6."""
    cs = cmap.colstart[blk]
    if cmap.full[A] and cmap.full[B]:
        for i in range(6):
            base = cmap.rowbase[A, i] + cs
            if transpose:
                for j in range(6):
                    data[base + j] += s * M[j0 + j, i0 + i]
            else:
                for j in range(6):
                    data[base + j] += s * M[i0 + i, j0 + j]
        return
    for i in range(6):
        rb = cmap.rowbase[A, i]
        if rb < 0:
            continue
        base = rb + cs
        for j in range(6):
            cr = cmap.colrank[B, j]
            if cr >= 0:
                if transpose:
                    data[base + cr] += s * M[j0 + j, i0 + i]
                else:
                    data[base + cr] += s * M[i0 + i, j0 + j]


@njit(cache=True, inline="always")
def scatter_diag(data, cmap, node, M, s):
    scatter(data, cmap, cmap.diag_blk[node], node, node, M, 0, 0, False, s)


@njit(cache=True)
def scatter_node_blocks(data, cmap, nodes, blocks):
    """data += the 6x6 diagonal blocks (k, 6, 6) of the nodes (k,) (repeats add up)."""
    for t in range(nodes.size):
        scatter_diag(data, cmap, nodes[t], blocks[t], 1.0)


@njit(cache=True)
def scatter_element_blocks(data, cmap, quads, elements, blocks):
    """data += the element blocks (k, 24, 24) (node-pair blocks (a, b) at rows 6a, columns 6b)
    of the elements (k,)."""
    for t in range(elements.size):
        el = elements[t]
        for a in range(4):
            for b in range(4):
                scatter(data, cmap, cmap.elem_blk[el, a, b], quads[el, a], quads[el, b], blocks[t],
                        6 * a, 6 * b, False, 1.0)


def add_blocks(data, pattern, quads, node_blocks=None, element_blocks=None):
    """Scatter a LoadEvaluation's NumPy blocks into the CSR data of ``pattern`` (the compiled
    backend's path for a load without a compiled kernel): node_blocks (n, 6, 6), element_blocks
    (ids (k,), (k, 4, 4, 6, 6))."""
    if node_blocks is not None:
        nb = np.ascontiguousarray(node_blocks, dtype=float)
        scatter_node_blocks(data, pattern.map, np.arange(len(nb), dtype=np.int64), nb)
    if element_blocks is not None:
        ids, blocks = element_blocks
        b24 = np.ascontiguousarray(np.asarray(blocks, float).transpose(0, 1, 3, 2, 4).reshape(-1, 24, 24))
        scatter_element_blocks(data, pattern.map, np.ascontiguousarray(quads, dtype=np.int64),
                               np.ascontiguousarray(ids, dtype=np.int64), b24)
