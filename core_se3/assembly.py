"""Sparse assembly with a sparsity pattern built once, on node-pair blocks.

Element (4x4 node), edge (2x2 node) and nodal (1x1) 6x6 blocks are summed into one 6x6 block
per coupled node pair by ``np.bincount`` over a precomputed slot index; the CSR matrix on the
free degrees of freedom is then a single gather from those blocks.  The pattern is built on
node pairs (36x fewer keys than dof pairs) and the CSR order follows from the sorted block
rows without any sort over dofs.  No Python loop over elements.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["Assembler"]


def _pairs(nodes_a, nodes_b):
    A = np.broadcast_to(nodes_a[:, :, None], (len(nodes_a), nodes_a.shape[1], nodes_b.shape[1]))
    B = np.broadcast_to(nodes_b[:, None, :], A.shape)
    return A.ravel(), B.ravel()


class Assembler:
    """Assembles K_ff (CSR) and r_f on the free dofs ``free`` (boolean mask of length 6n).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(1.0, 1.0, 1, 1)
    >>> asm = Assembler(m, np.ones(6 * m.n_nodes, bool))
    >>> K = asm.matrix(None, None, np.broadcast_to(np.eye(6), (4, 6, 6)))
    >>> K.shape, float(K.diagonal().sum())
    ((24, 24), 24.0)
    """

    def __init__(self, mesh, free):
        self.mesh = mesh
        self._pattern = None
        n = mesh.n_nodes
        self.ndof = 6 * n
        self.free = np.asarray(free, bool)
        self.nfree = int(self.free.sum())
        groups = [_pairs(mesh.quads, mesh.quads), _pairs(mesh.edge_nodes, mesh.edge_nodes),
                  (np.arange(n), np.arange(n))]
        keys = np.concatenate([a * n + b for a, b in groups])
        ukeys, inv = np.unique(keys, return_inverse=True)
        self.nblocks = len(ukeys)
        sizes = np.cumsum([0] + [len(a) for a, _ in groups])
        ij = np.arange(36)
        # bincount index of every entry of the element / edge / nodal block arrays
        self.slots = [(inv[sizes[k]:sizes[k + 1], None] * 36 + ij).ravel() for k in range(3)]
        bA, bB = ukeys // n, ukeys % n                                  # sorted by (A, B)
        # CSR of the full matrix: row (A, i) lists, for each block (A, B) in order, cols 6B + j
        cnt = np.bincount(bA, minlength=n)                               # blocks per block-row
        first = np.concatenate([[0], np.cumsum(cnt)[:-1]])               # first block of row A
        rank = np.arange(self.nblocks) - first[bA]
        rowstart = 36 * first                                            # entries before row A
        i = np.arange(6)[None, :, None]
        j = np.arange(6)[None, None, :]
        pos = (rowstart[bA][:, None, None] + i * 6 * cnt[bA][:, None, None]
               + rank[:, None, None] * 6 + j)                            # (nb, 6, 6) CSR position
        take = np.empty(self.nblocks * 36, np.int64)
        take[pos.ravel()] = np.arange(self.nblocks * 36)                 # CSR entry -> block entry
        rows = np.repeat(np.arange(self.ndof), np.repeat(6 * cnt, 6))
        cols = (6 * bB[:, None, None] + j + 0 * i).ravel()[take]
        keep = self.free[rows] & self.free[cols]
        red = -np.ones(self.ndof, np.int64)
        red[self.free] = np.arange(self.nfree)
        self.take = take[keep]
        self.indices = red[cols[keep]].astype(np.int32)
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(red[rows[keep]], minlength=self.nfree))]).astype(np.int32)
        self.nnz = len(self.take)

    def matrix(self, element_blocks=None, edge_blocks=None, node_blocks=None):
        """CSR K_ff from the element (m,4,4,6,6), edge (E,2,2,6,6) and nodal (n,6,6) blocks
        (None: no blocks of that shape)."""
        nb36 = self.nblocks * 36
        acc = np.zeros(nb36)
        for slot, b in zip(self.slots, (element_blocks, edge_blocks, node_blocks)):
            if b is not None:
                acc += np.bincount(slot, weights=np.ascontiguousarray(b).ravel(), minlength=nb36)
        return sp.csr_matrix((acc[self.take], self.indices, self.indptr), shape=(self.nfree, self.nfree))

    def pattern(self):
        """The compiled backend's pattern of these free dofs (``kernels.Pattern``: the same CSR
        structure, plus the map that writes 6x6 blocks straight into its data), built once."""
        if self._pattern is None:
            from .kernels import Pattern
            m = self.mesh
            self._pattern = Pattern(m.quads, m.edge_nodes, m.elem_edges, m.n_nodes, self.free)
        return self._pattern

    def vector(self, r):
        """Free part of a nodal (n, 6) array."""
        return np.asarray(r).ravel()[self.free]

    def scatter(self, x_free):
        """(n, 6) array with x on the free dofs and zero elsewhere."""
        out = np.zeros(self.ndof)
        out[self.free] = x_free
        return out.reshape(-1, 6)
