"""Sparse assembly with a sparsity pattern built once.

Element (4x4 node), edge (2x2 node) and nodal (1x1) 6x6 blocks are summed into one CSR matrix
on the free degrees of freedom.  The map from every block entry to its CSR slot is computed
once; each Newton iteration is then a single ``np.bincount``: no Python loop over elements.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["Assembler"]


def _block_rc(nodes_a, nodes_b):
    """Global (row, col) dof indices of blocks (k, A, B, 6, 6) for node ids (k, A), (k, B)."""
    ra = (6 * nodes_a[:, :, None] + np.arange(6))                   # (k, A, 6)
    cb = (6 * nodes_b[:, :, None] + np.arange(6))                   # (k, B, 6)
    R = np.broadcast_to(ra[:, :, None, :, None], (len(nodes_a), nodes_a.shape[1], nodes_b.shape[1], 6, 6))
    C = np.broadcast_to(cb[:, None, :, None, :], R.shape)
    return R.ravel(), C.ravel()


class Assembler:
    """Assembles K_ff (CSR) and r_f on the free dofs ``free`` (boolean mask of length 6n)."""

    def __init__(self, mesh, free, extra_pairs=None):
        n = mesh.n_nodes
        self.ndof = 6 * n
        self.free = np.asarray(free, bool)
        red = -np.ones(self.ndof, np.int64)
        red[self.free] = np.arange(self.free.sum())
        self.red = red
        self.nfree = int(self.free.sum())
        parts = [
            _block_rc(mesh.quads, mesh.quads),
            _block_rc(mesh.edge_nodes, mesh.edge_nodes),
            _block_rc(np.arange(n)[:, None], np.arange(n)[:, None]),
        ]
        if extra_pairs is not None and len(extra_pairs):
            parts.append(_block_rc(extra_pairs[0], extra_pairs[1]))
        self.sizes = [len(p[0]) for p in parts]
        rows = np.concatenate([p[0] for p in parts])
        cols = np.concatenate([p[1] for p in parts])
        rr, cc = red[rows], red[cols]
        keep = (rr >= 0) & (cc >= 0)
        self.keep = np.nonzero(keep)[0]
        key = rr[keep] * self.nfree + cc[keep]
        uniq, target = np.unique(key, return_inverse=True)
        self.target = target
        self.nnz = len(uniq)
        self.indices = (uniq % self.nfree).astype(np.int32)
        row_of = uniq // self.nfree
        self.indptr = np.searchsorted(row_of, np.arange(self.nfree + 1)).astype(np.int32)

    def matrix(self, *blocks):
        """CSR K_ff from block arrays in the order given at construction (element, edge, node, extra)."""
        vals = np.concatenate([np.ascontiguousarray(b).ravel() for b in blocks])
        data = np.bincount(self.target, weights=vals[self.keep], minlength=self.nnz)
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.nfree, self.nfree))

    def vector(self, r):
        """Free part of a nodal (n, 6) array."""
        return np.asarray(r).ravel()[self.free]

    def scatter(self, x_free):
        """(n, 6) array with x on the free dofs and zero elsewhere."""
        out = np.zeros(self.ndof)
        out[self.free] = x_free
        return out.reshape(-1, 6)
