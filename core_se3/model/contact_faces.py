"""Face samples of the contact surface (``model.contact``): the obstacle's closest point on each
contact face, so that an obstacle smaller than an element, or a curved one touching a face
between its nodes, is felt (docs/CONTACT.md "Face samples").

The contact face of element e is the bilinear surface x(xi) = sum_a N_a(xi) x_a through its four
contact points x_a = phi_a + c_a d3_a.  Its sample is the minimiser xi* of d(x(xi)) over the
square [-1, 1]^2 (projected Newton); it carries a constraint of its own when it lies off the
corners (interior, or on an edge with one free coordinate), its gap is below those of the face's
nodes and the restricted Hessian M = J^T H J + n . x_{,xi eta} (J = dx/dxi) is positive definite.
On a plane d is bilinear on the face, so its minimum is at a corner and no sample is taken (the
nodes suffice, and the nodal sampling's freedom from over-constraint is kept).

With F = A p n the contact force at x(xi*), the generalised forces and tangent on node a are

    f_a = N_a B_a^T R_a^T F,
    -df_a/deta_b = -N_a N_b B_a^T R_a^T S R_b B_b - delta_ab N_a B_a^T [0, hat(R_a^T F)]
                   + A p G_a^T M^-1 G_b,                         S = A (p' n n^T + p H),
    G_a = dN_a/dxi (n^T R_a B_a) + N_a J^T H R_a B_a             (2 x 6: d(grad_xi d)/deta_a),

the last term from the motion of xi* (d(xi*)/deta_b = -M^-1 G_b; at the minimiser grad_xi d = 0,
so p does not move with xi* to first order).  Restricted to the free coordinates on an edge.

Example
-------
>>> import numpy as np
>>> from core_se3.model import make_obstacle
>>> ball = make_obstacle("sphere", centre=(0.5, 0.5, 1.0), radius=0.9)
>>> xq = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]], float)
>>> s = face_minima(ball, xq, 0.0)
>>> s["xi"].round(9).tolist(), round(float(s["d"][0]), 9), s["ok"].tolist()    # under the ball's pole
([[0.0, 0.0]], 0.1, [True])
"""
from __future__ import annotations

import numpy as np

from .. import lie
from .contact_law import E3

__all__ = ["face_minima", "face_shape", "face_wrench"]

CORNERS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])


def face_shape(xi):
    """Bilinear N (m, 4) and dN/dxi (m, 4, 2) at parametric points xi (m, 2).

    Example
    -------
    >>> N, dN = face_shape(np.zeros((1, 2)))
    >>> N.tolist(), dN[0, :, 0].tolist()
    ([[0.25, 0.25, 0.25, 0.25]], [-0.25, 0.25, 0.25, -0.25])
    """
    a, b = CORNERS[:, 0], CORNERS[:, 1]
    u, v = xi[:, :1], xi[:, 1:]
    N = 0.25 * (1 + a * u) * (1 + b * v)
    dN = np.stack([0.25 * a * (1 + b * v), 0.25 * b * (1 + a * u)], -1)
    return N, dN


RULED_CURVATURE = 1e-2
"""A face coordinate along which the obstacle's curvature M_jj is at most this fraction of the
face's tr M is *ruled* (a cylinder's axis or a box's edge lying across the face)."""


def _flat(M, G, J, line=None, tol=1e-9):
    """The face coordinates (m, 2) held where they are (m, 2 bool): those along which d is flat
    to second order at the iterate, no slope (|dd/dxi_j| <= tol |x_,j|) and no curvature
    (M_jj <= tol tr M), e.g. along the axis of a cylinder lying across the face: the minimiser is
    a line there, and the round-off's sign of the slope sent it to xi_j = +1 or -1 at every
    evaluation (a roller across a strip jumped from edge to edge of the face and Newton stalled
    at a residual of 0.5 at first contact).

    With ``line`` [length], also the *ruled* ones: M_jj <= RULED_CURVATURE tr M and
    |dd/dxi_j| + M_jj / 2 <= line, where d changes by at most ``line`` from the face's middle
    line to its edge.
    The contact is then a line across the face, whose minimiser along it is set by the slope
    alone; a point sample sent to the lower end tilts the face the other way by its own force,
    and its next iterate sends it to the other end (a roller of radius 0.06 pressed into a
    clamped plate between its node lines alternated so, and Newton stalled at every cut-back).
    The sample keeps its coordinate; :func:`face_minima` reports the depth of the line's lower
    end in ``d_low``."""
    edge = np.sqrt(np.einsum("mij,mij->mj", J, J))
    diag = M[:, [0, 1], [0, 1]]
    tr = np.abs(diag).sum(1, keepdims=True)
    flat = (np.abs(G) <= tol * edge) & (np.abs(diag) <= tol * tr)
    if line is None:
        return flat
    # curved across (tr M > 0): not a flat part of the obstacle (a box's face), where the
    # minimum lies at a corner and the nodes carry the contact as on a plane
    ruled = (np.abs(diag) <= RULED_CURVATURE * tr) & (tr > 0) & (np.abs(G) + 0.5 * np.abs(diag) <= line)
    return flat | ruled


def _descend(obstacle, xq, lam, xi, step, dnH, slope, halvings=12):
    """The iterate xi + a step (clipped to the square), a = 1, 1/2, 1/4, ... the first at which d
    decreases by at least 1e-4 of its first-order prediction (Armijo; slope (m, 2): dd/dxi), per
    face (xi itself where none does or the step is no descent; a move of at most 1e-8 is taken),
    with its (d, n, H); dnH: those at xi.  The step is scaled, not clipped per coordinate, to
    length 1: clipping turned a Newton step (-7.6, 0.46) into an ascent (-1, 0.46)."""
    d, n, H = dnH
    a = np.ones(len(xi))
    todo = np.einsum("mj,mj->m", slope, step) < 0        # else no descent along the step: xi stays
    xi, d, n, H = xi.copy(), d.copy(), n.copy(), H.copy()
    for _ in range(halvings + 1):
        new = np.clip(xi[todo] + a[todo, None] * step[todo], -1.0, 1.0)
        dt, nt, Ht = obstacle.evaluate(np.einsum("ma,mai->mi", face_shape(new)[0], xq[todo]), lam)
        move = new - xi[todo]
        pred = np.einsum("mj,mj->m", slope[todo], move)
        # a step of 1e-8 is Newton's last (quadratic convergence): taken as it is
        tiny = np.abs(move).max(1, initial=0.0) <= 1e-8
        ok = tiny | ((pred < 0) & (dt <= d[todo] + 1e-4 * pred))
        idx = np.nonzero(todo)[0]
        xi[idx[ok]], d[idx[ok]], n[idx[ok]], H[idx[ok]] = new[ok], dt[ok], nt[ok], Ht[ok]
        todo[idx[ok]] = False
        a[todo] *= 0.5
        if not todo.any():
            break
    return xi, d, n, H


def face_minima(obstacle, xq, lam, iters=16, line=None):
    """The obstacle's closest point on each bilinear face with corners xq (m, 4, 3) at lam
    (``line`` [length]: the ruled coordinates' hold, :func:`_flat`; None: exact minima).

    Projected Newton from the face's centre, each step halved (up to 12 times) until d
    decreases enough (Armijo; else the iterate stays): seen from afar a ball's d on the face is cone-like, its
    curvature along the direction to the ball ~ z^2 / rho^3, so a full Newton step from an offset
    r beyond the height z lands at -r^3 / z^2: the iterate swung between the face's centre and a
    corner (a ball of radius 0.05 under the point (0.25, 0.25) of a 1 x 1 face was never found,
    and rose through the plate with zero force and no error).

    Returns a dict of arrays: xi (m, 2), x (m, 3), d (m,), n (m, 3), H (m, 3, 3), N (m, 4),
    dN (m, 4, 2), J (m, 3, 2), Minv (m, 2, 2) (the inverse Hessian on the free coordinates, 0 on
    a fixed one), ok (m,) (the sample carries a constraint: module docstring), d_low (m,): d at
    the lower end of the lines held in the face, d + sum_j min(0, G_j D + M_jj D^2 / 2) over
    the held interior coordinates and their two ends D = +-1 - xi_j.
    """
    m = len(xq)
    xi = np.zeros((m, 2))
    x_ab = 0.25 * np.einsum("a,mai->mi", CORNERS[:, 0] * CORNERS[:, 1], xq)      # d2x/dxi deta
    d, n, H = obstacle.evaluate(np.einsum("ma,mai->mi", face_shape(xi)[0], xq), lam)
    for _ in range(iters):
        N, dN = face_shape(xi)
        J = np.einsum("maj,mai->mij", dN, xq)
        G = np.einsum("mij,mi->mj", J, n)
        M = np.einsum("mij,mik,mkl->mjl", J, H, J)
        M[:, 0, 1] += np.einsum("mi,mi->m", n, x_ab)
        M[:, 1, 0] = M[:, 0, 1]
        # a bound coordinate stays fixed while its gradient pushes outward (projected Newton), and
        # one along which d is flat (a line of minima) stays where it is
        fixed = ((np.abs(xi) >= 1.0) & (G * np.sign(xi) < 0)) | _flat(M, G, J, line)
        # a ruled line met away from its middle (the iterate came over a flat part, a box's side)
        # goes to its middle, within ``line`` of its lower end's depth
        off = fixed & ~_flat(M, G, J) & (np.abs(xi) < 1.0) & (xi != 0.0)
        if off.any():
            xi = np.where(off, 0.0, xi)
            d, n, H = obstacle.evaluate(np.einsum("ma,mai->mi", face_shape(xi)[0], xq), lam)
            continue
        Mf = np.where(fixed[:, :, None] | fixed[:, None, :], 0.0, M)
        Mf[:, [0, 1], [0, 1]] = np.where(fixed, 1.0, Mf[:, [0, 1], [0, 1]])
        Gf = np.where(fixed, 0.0, G)
        tr = np.abs(Mf[:, 0, 0]) + np.abs(Mf[:, 1, 1])
        det = Mf[:, 0, 0] * Mf[:, 1, 1] - Mf[:, 0, 1] ** 2
        pd = (Mf[:, 0, 0] > 0) & (det > 1e-12 * tr ** 2)
        # Newton where M is positive definite, else a bounded gradient step
        step = np.where(pd[:, None], -np.linalg.solve(np.where(pd[:, None, None], Mf, np.eye(2)), Gf[:, :, None])[:, :, 0],
                        -0.5 * np.sign(Gf))
        xi, d, n, H = _descend(obstacle, xq, lam, xi, step / np.maximum(1.0, np.abs(step).max(1, keepdims=True)),
                               (d, n, H), Gf)
    N, dN = face_shape(xi)
    x = np.einsum("ma,mai->mi", N, xq)
    J = np.einsum("maj,mai->mij", dN, xq)
    d, n, H = obstacle.evaluate(x, lam)
    M = np.einsum("mij,mik,mkl->mjl", J, H, J)
    M[:, 0, 1] += np.einsum("mi,mi->m", n, x_ab)
    M[:, 1, 0] = M[:, 0, 1]
    G = np.einsum("mij,mi->mj", J, n)
    inner = np.abs(xi) < 1.0 - 1e-12
    free = inner & ~_flat(M, G, J, line)
    held = inner & ~free
    ends = np.stack([-1.0 - xi, 1.0 - xi])                        # the held lines' two ends
    rise = G * ends + 0.5 * M[:, [0, 1], [0, 1]] * ends ** 2
    d_low = d + np.where(held, np.minimum(rise.min(0), 0.0), 0.0).sum(1)
    Mf = np.where(free[:, :, None] & free[:, None, :], M, 0.0)
    Mf[:, [0, 1], [0, 1]] = np.where(free, Mf[:, [0, 1], [0, 1]], 1.0)
    det = Mf[:, 0, 0] * Mf[:, 1, 1] - Mf[:, 0, 1] ** 2
    scale = np.einsum("mij,mij->m", J, J)
    pd = (Mf[:, 0, 0] > 0) & (Mf[:, 1, 1] > 0) & (det > 1e-12 * (Mf[:, 0, 0] + Mf[:, 1, 1]) ** 2)
    Minv = np.zeros((m, 2, 2))
    good = pd & free.any(1)
    Minv[good] = np.linalg.inv(Mf[good])
    Minv[~(free[:, :, None] & free[:, None, :])] = 0.0
    d_nodes = obstacle.evaluate(xq.reshape(-1, 3), lam)[0].reshape(m, 4).min(1)
    ok = good & (d < d_nodes - 1e-12 * np.sqrt(scale))
    return dict(xi=xi, x=x, d=d, n=n, H=H, N=N, dN=dN, J=J, Minv=Minv, ok=ok, d_low=d_low)


def face_wrench(R, c, A, s, p, dp):
    """Generalised forces (m, 4, 6) and blocks -df_a/deta_b (m, 4, 4, 6, 6) of the face samples
    (R (m, 4, 3, 3) frames and c (m, 4) offsets of the face nodes, A (m,) areas, s: the
    :func:`face_minima` dict of those faces, p, dp (m,): the law; module docstring)."""
    m = len(A)
    B = np.zeros((m, 4, 3, 6))
    B[..., :3] = np.eye(3)
    B[..., 3:] = -c[:, :, None, None] * lie.hat3(E3)
    RB = R @ B                                                    # (m, 4, 3, 6): dx_a / deta_a
    n, H, N, dN, J = s["n"], s["H"], s["N"], s["dN"], s["J"]
    F = (A * p)[:, None] * n
    f = N[:, :, None] * np.einsum("maij,mi->maj", RB, F)
    S = (A * dp)[:, None, None] * n[:, :, None] * n[:, None, :] + (A * p)[:, None, None] * H
    K = -np.einsum("ma,mb,maik,mij,mbjl->mabkl", N, N, RB, S, RB)
    Fb = np.einsum("maji,mj->mai", R, F)                          # R_a^T F
    Bt = np.swapaxes(B, 2, 3)
    Z = np.zeros((m, 4, 3, 6))
    Z[..., 3:] = lie.hat3(Fb.reshape(-1, 3)).reshape(m, 4, 3, 3)
    diag = -N[:, :, None, None] * (Bt @ Z)
    idx = np.arange(4)
    K[:, idx, idx] += diag
    nRB = np.einsum("mi,maik->mak", n, RB)
    JH = np.einsum("mij,mik->mjk", J, H)                          # (m, 2, 3): J^T H
    G = dN[..., None] * nRB[:, :, None, :] + N[:, :, None, None] * np.einsum("mjk,makl->majl", JH, RB)
    K += (A * p)[:, None, None, None, None] * np.einsum("maji,mjk,mbkl->mabil", G, s["Minv"], G)
    return f, K
