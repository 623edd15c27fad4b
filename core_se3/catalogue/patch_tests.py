"""Patch tests of shell elements (MacNeal and Harder 1985): the boundary nodes of a flat patch
follow an exact constant-strain field, the interior nodes are free, and the linear solution
(``Problem.solve_linear``) must reproduce the field at the interior nodes.

Fields (x, y in the plane of the patch, eps = 1e-3), nodal dofs (u, w, rotation vector):

* membrane: u = eps (x + y/2), v = eps (y + x/2), no rotation;
* bending: w = eps (x^2 + x y + y^2)/2, rotations theta_x = dw/dy, theta_y = -dw/dx (no shear);
* drilling: the membrane field turned by the rotation omega = eps about the normal,
  u = eps (x + y/2) - omega y, v = eps (y + x/2) + omega x, theta_z = omega.

The patches: MacNeal and Harder's five elements in 0.24 x 0.12 (E 1e6, nu 0.25, t 0.001), and
random convex patches of 3 x 3 elements (:func:`random_patch`).
"""
from __future__ import annotations

import numpy as np

from ..fem import Material
from ..mesh import Mesh, frames_from
from ..model import Problem
from ..solvers.linear import linear_state

__all__ = ["PATCH_FIELDS", "flat_mesh", "mh_patch", "random_patch", "patch_field", "patch_test", "turned_frames"]

PATCH_FIELDS = ("membrane", "bending", "drilling")
EPS = 1e-3


def flat_mesh(X, quads):
    """A flat mesh in the x-y plane (frames = identity) of points X (n, 2) and quads."""
    n = len(X)
    X3 = np.c_[np.asarray(X, float), np.zeros(n)]
    return Mesh(frames_from(X3, np.tile([1.0, 0, 0], (n, 1)), np.tile([0, 0, 1.0], (n, 1))),
                np.asarray(quads))


def mh_patch():
    """MacNeal and Harder's patch: (mesh, boundary node ids)."""
    X = [[0, 0], [.24, 0], [.24, .12], [0, .12], [.04, .02], [.18, .03], [.16, .08], [.08, .08]]
    quads = [[4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [7, 6, 2, 3], [0, 4, 7, 3]]
    return flat_mesh(X, quads), np.arange(4)


def turned_frames(mesh, angles):
    """The flat ``mesh`` with its nodal frames turned about the normal by ``angles`` (n,) [rad]:
    the same quads, d1 = (cos a, sin a, 0).  The element's answer depends on this choice where
    the angles differ from node to node (docs/ELEMENTS.md, "Nodal frames").

    Example
    -------
    >>> import numpy as np
    >>> mesh, bnd = mh_patch()
    >>> m = turned_frames(mesh, np.full(mesh.n_nodes, 0.3))        # all alike: exact still
    >>> bool(patch_test(m, bnd, "membrane") < 1e-8)
    True
    """
    X, a = mesh.X, np.asarray(angles, float)
    d1 = np.c_[np.cos(a), np.sin(a), np.zeros_like(a)]
    return Mesh(frames_from(X, d1, np.tile([0.0, 0.0, 1.0], (len(X), 1))), mesh.quads)


def _convex(X, quads):
    P = X[quads]                                            # (m, 4, 2)
    e = np.roll(P, -1, axis=1) - P
    cr = e[:, :, 0] * np.roll(e, -1, axis=1)[:, :, 1] - e[:, :, 1] * np.roll(e, -1, axis=1)[:, :, 0]
    return bool(np.all(cr > 0))


def random_patch(rng, n=3, amp=0.3):
    """A random convex patch: an n x n grid of the unit square, every node moved by up to
    ``amp`` of the spacing in each direction (resampled until every quad is strictly convex).
    Returns (mesh, boundary node ids)."""
    ids = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    quads = np.stack([ids[:-1, :-1], ids[:-1, 1:], ids[1:, 1:], ids[1:, :-1]], -1).reshape(-1, 4)
    x, y = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    X0 = np.c_[x.ravel(), y.ravel()]
    while True:
        X = X0 + amp / n * rng.uniform(-1, 1, X0.shape)
        if _convex(X, quads):
            break
    bnd = np.unique(np.concatenate([ids[0], ids[-1], ids[:, 0], ids[:, -1]]))
    return flat_mesh(X, quads), bnd


def patch_field(kind, X):
    """Exact nodal increments eta (n, 6) of the field ``kind`` at points X (n, >= 2)."""
    x, y = X[:, 0], X[:, 1]
    eta = np.zeros((len(X), 6))
    if kind in ("membrane", "drilling"):
        om = EPS if kind == "drilling" else 0.0
        eta[:, 0] = EPS * (x + y / 2) - om * y
        eta[:, 1] = EPS * (y + x / 2) + om * x
        eta[:, 5] = om
    elif kind == "bending":
        eta[:, 2] = EPS * (x * x + x * y + y * y) / 2
        eta[:, 3] = EPS * (y + x / 2)
        eta[:, 4] = -EPS * (x + y / 2)
    else:
        raise ValueError(f"unknown patch field {kind!r}; choose one of {PATCH_FIELDS}")
    return eta


def patch_test(mesh, boundary, kind, material=None, element="default", backend=None):
    """Interior error of the patch test ``kind``: max |eta - eta_exact| over the interior
    nodes, translations divided by EPS times the patch size and rotations by EPS.

    Example
    -------
    >>> mesh, bnd = mh_patch()
    >>> [bool(patch_test(mesh, bnd, k) < 1e-8) for k in PATCH_FIELDS]
    [True, True, True]
    """
    material = material or Material(1.0e6, 0.25, 0.001)
    p = Problem(mesh, material, element=element, backend=backend)
    exact = patch_field(kind, mesh.X)
    # the nodal increments in the nodes' own frames (the field is given in the lab)
    R0 = mesh.g0[:, :3, :3]
    local = np.concatenate([np.einsum("nji,nj->ni", R0, exact[:, :3]), np.einsum("nji,nj->ni", R0, exact[:, 3:])], 1)
    # the boundary on the field times lam: linear in lam, so the linear analysis' chord is its
    # linearisation (a constant target is not linear in lam, and linear analysis warns of it)
    p.prescribe(boundary, lambda lam: linear_state(mesh.g0[boundary], lam * local[boundary]))
    res = p.solve_linear()
    inner = np.setdiff1d(np.arange(mesh.n_nodes), boundary)
    g = res.final.g[inner]
    du = np.abs(g[:, :3, 3] - mesh.X[inner] - exact[inner, :3]).max()
    R = np.swapaxes(R0[inner], 1, 2) @ g[:, :3, :3]
    from ..lie import log_so3
    dw = np.abs(log_so3(R) - local[inner, 3:]).max()
    size = np.ptp(mesh.X, axis=0).max()
    return max(du / (EPS * size), dw / EPS)
