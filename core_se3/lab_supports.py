"""Supports on lab-frame translation directions (e.g. a rigid diaphragm), by penalty springs.

``Problem.fix`` fixes body-frame dofs, which stay lab-fixed only while the node's frame does
not rotate about an axis that tilts the fixed direction.  A rigid diaphragm (radial and
circumferential displacement zero, axial displacement and rotations free) is such a case: the
end section bends about the circumferential axis.  ``LabSpring`` adds, at each selected node,
the force F = -k P (phi - X) with P the projector on the lab directions ``dirs``; its
generalised (body-frame) force is f = (R^T F, 0) and the load stiffness along g <- g exp(eta)

    -df/deta = [[k R^T P R, -hat(R^T F)], [0, 0]].

It does not depend on the load factor (so continuation's load direction q is unaffected).  The
constraint error is |F|/k: choose k a few decades above the element stiffness (E h).
"""
from __future__ import annotations

import numpy as np

from . import se3

__all__ = ["LabSpring", "add_lab_support"]


class LabSpring:
    """Penalty on the lab displacement components ``dirs`` (rows: unit vectors, per node)."""

    def __init__(self, mesh, nodes, dirs, k, name="lab support"):
        self.nodes = np.asarray(nodes, np.int64)
        D = np.asarray(dirs, float)
        if D.ndim == 2:
            D = np.broadcast_to(D, (len(self.nodes),) + D.shape)
        self.P = np.einsum("nai,naj->nij", D, D)                     # (k, 3, 3) projectors
        self.X0 = mesh.X[self.nodes].copy()
        self.k = float(k)
        self.name = name

    def evaluate(self, g, lam, n):
        R = g[self.nodes, :3, :3]
        F = -self.k * np.einsum("nij,nj->ni", self.P, g[self.nodes, :3, 3] - self.X0)
        Fb = np.einsum("nji,nj->ni", R, F)
        f = np.zeros((n, 6))
        np.add.at(f, self.nodes, np.concatenate([Fb, np.zeros_like(Fb)], 1))
        blk = np.zeros((len(self.nodes), 6, 6))
        blk[:, :3, :3] = self.k * np.einsum("nji,njk,nkl->nil", R, self.P, R)
        blk[:, :3, 3:] = -se3.hat3(Fb)
        Kn = np.zeros((n, 6, 6))
        np.add.at(Kn, self.nodes, blk)
        return f, Kn, None


def add_lab_support(problem, where, dirs, k):
    """Append a LabSpring on the nodes ``where`` (name or ids) to the problem's loads."""
    nodes = problem._nodes(where)
    spring = LabSpring(problem.mesh, nodes, dirs, k)
    problem.loads.append(spring)
    return spring
