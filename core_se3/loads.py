"""External loads and their load stiffness.

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

Every load is scaled by a function of the load factor (``scale(lam)``, linear by default).
``evaluate`` returns the generalised forces (n, 6) and the blocks of -d f / d eta to add to
the tangent (nodal (n,6,6) and, for follower pressure, element (m,4,4,6,6)).
"""
from __future__ import annotations

import numpy as np

from . import se3
from .element import GAUSS_2x2
from .errors import LoadError

__all__ = ["NodalLoad", "SurfaceLoad", "edge_weights", "shape_functions"]


def _finite_vec(v, name):
    v = np.asarray(v, float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise LoadError(f"{name} must be a finite 3-vector, got {v!r}")
    return v


def edge_weights(mesh, nodes):
    """Consistent weights (summing to 1) of a uniform line load along ordered edge nodes."""
    nodes = np.asarray(nodes)
    if len(nodes) == 1:
        return np.ones(1)
    X = mesh.X[nodes]
    seg = np.linalg.norm(np.diff(X, axis=0), axis=1)
    w = np.zeros(len(nodes))
    w[:-1] += seg / 2
    w[1:] += seg / 2
    return w / w.sum()


def shape_functions(points=GAUSS_2x2):
    """Bilinear N (q, 4) and dN/dx, dN/dy (q, 2, 4) at natural points."""
    xs = np.array([-1, 1, 1, -1.0])
    ys = np.array([-1, -1, 1, 1.0])
    x, y = points[:, :1], points[:, 1:]
    N = 0.25 * (1 + x * xs) * (1 + y * ys)
    dN = np.stack([0.25 * xs * (1 + y * ys), 0.25 * ys * (1 + x * xs)], 1)
    return N, dN


class NodalLoad:
    """Force and moment on nodes, split by ``weights``; dead (lab) or follower (body frame)."""

    def __init__(self, nodes, weights, force=(0, 0, 0), moment=(0, 0, 0), follower=False,
                 scale=None, name="nodal"):
        self.nodes = np.asarray(nodes, np.int64)
        self.weights = np.asarray(weights, float)
        self.force = _finite_vec(force, "force")
        self.moment = _finite_vec(moment, "moment")
        self.follower = bool(follower)
        self.scale = scale or (lambda lam: lam)
        self.name = name
        if self.weights.shape != self.nodes.shape or not np.all(np.isfinite(self.weights)):
            raise LoadError(f"load {name}: weights must be finite, one per node")

    def evaluate(self, g, lam, n):
        s = self.scale(lam)
        f = np.zeros((n, 6))
        w = self.weights[:, None] * s
        if self.follower:
            np.add.at(f, self.nodes, np.concatenate([w * self.force, w * self.moment], 1))
            return f, None, None
        Rt = np.swapaxes(g[self.nodes, :3, :3], 1, 2)
        Fb = w * (Rt @ self.force)
        Mb = w * (Rt @ self.moment)
        np.add.at(f, self.nodes, np.concatenate([Fb, Mb], 1))
        Kn = np.zeros((n, 6, 6))
        blk = np.zeros((len(self.nodes), 6, 6))
        blk[:, :3, 3:] = -se3.hat3(Fb)
        blk[:, 3:, 3:] = -se3.hat3(Mb)
        np.add.at(Kn, self.nodes, blk)
        return f, Kn, None

    def total(self, lam):
        s = self.scale(lam)
        return s * self.weights.sum() * self.force, s * self.weights.sum() * self.moment


class SurfaceLoad:
    """Distributed load over the elements ``elements`` (default: all).

    dead: ``q`` is a lab vector per unit reference area (fixed-direction pressure, gravity).
    follower: ``q`` is a scalar pressure per unit current area along the current normal
    a_1 x a_2 (positive toward the frames' +d3 side).
    """

    def __init__(self, mesh, q, follower=False, elements=None, scale=None, name="surface"):
        self.mesh = mesh
        self.follower = bool(follower)
        self.scale = scale or (lambda lam: lam)
        self.name = name
        self.elements = np.arange(mesh.n_elements) if elements is None else np.asarray(elements)
        self.N, self.dN = shape_functions()
        if self.follower:
            q = float(q)
            if not np.isfinite(q):
                raise LoadError(f"load {name}: pressure must be finite, got {q}")
            self.p = q
        else:
            self.q = _finite_vec(q, "surface load")
            X = mesh.X[mesh.quads[self.elements]]                      # (m,4,3)
            a = np.einsum("qai,mij->mqaj", self.dN, X)                 # (m,q,2,3)
            j0 = np.linalg.norm(np.cross(a[:, :, 0], a[:, :, 1]), axis=-1)
            self.node_w = np.einsum("qi,mq->mi", self.N, j0)           # int N_i dA, (m,4)

    def evaluate(self, g, lam, n):
        s = self.scale(lam)
        quads = self.mesh.quads[self.elements]
        f = np.zeros((n, 6))
        if not self.follower:
            F = s * self.node_w[..., None] * self.q                      # (m,4,3) lab
            Rt = np.swapaxes(g[quads, :3, :3], -1, -2)
            Fb = np.einsum("maij,maj->mai", Rt, F)
            for k in range(3):
                f[:, k] += np.bincount(quads.ravel(), weights=Fb[..., k].ravel(), minlength=n)
            Kn = np.zeros((n, 6, 6))
            blk = -se3.hat3(Fb)                                          # (m,4,3,3)
            for i in range(3):
                for j in range(3):
                    Kn[:, i, 3 + j] += np.bincount(quads.ravel(), weights=blk[..., i, j].ravel(), minlength=n)
            return f, Kn, None
        p = s * self.p
        phi = g[quads, :3, 3]                                            # (m,4,3)
        R = g[quads, :3, :3]
        a = np.einsum("qai,mij->mqaj", self.dN, phi)                     # (m,q,2,3)
        nrm = np.cross(a[:, :, 0], a[:, :, 1])                          # (m,q,3)
        F = p * np.einsum("qi,mqk->mik", self.N, nrm)                    # (m,4,3) lab
        Fb = np.einsum("maji,maj->mai", R, F)                            # R^T F
        for k in range(3):
            f[:, k] += np.bincount(quads.ravel(), weights=Fb[..., k].ravel(), minlength=n)
        # load stiffness: -d(R_i^T F_i)/d eta; rotation part on node i, position part couples i, j
        m = len(quads)
        Ke = np.zeros((m, 4, 4, 6, 6))
        idx = np.arange(4)
        Ke[:, idx, idx, :3, 3:] = -se3.hat3(Fb)
        A1, A2 = se3.hat3(a[:, :, 0]), se3.hat3(a[:, :, 1])               # (m,q,3,3)
        # dF_i/dphi_j = p int N_i (-dN_j/dx hat(a2) + dN_j/dy hat(a1)) dxi
        dF = p * (np.einsum("qi,qj,mqkl->mijkl", self.N, -self.dN[:, 0], A2)
                  + np.einsum("qi,qj,mqkl->mijkl", self.N, self.dN[:, 1], A1))
        Ke[..., :3, :3] = -np.einsum("miak,mijab,mjbc->mijkc", R, dF, R)
        return f, None, (self.elements, Ke)
