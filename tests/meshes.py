"""Meshes that several test modules share (import as ``from meshes import ...``; tests/ is on the
path as for ``parallel_cases``)."""
import numpy as np

from core_se3 import mesh


def closed_ring(r_in=1.0, r_out=2.0, nr=2, nt=8):
    """A full ring: ``mesh.annulus`` over 2 pi (a slit ring, Sze et al.) with the slit's two
    lines of nodes merged.  Returns (ring, hole): the Mesh and the hole's nt nodes in loop order
    (the last joined to the first by an element edge)."""
    a = mesh.annulus(r_in, r_out, 2 * np.pi, nr, nt)
    ids = np.arange(a.n_nodes).reshape(nt + 1, nr + 1)
    remap = np.arange(a.n_nodes)
    remap[ids[-1]] = ids[0]
    keep = np.unique(remap)
    new = np.searchsorted(keep, remap)
    ring = mesh.Mesh(a.g0[keep], new[a.quads], {}, shape=None)
    return ring, new[a.edges["x0"]][:-1]
