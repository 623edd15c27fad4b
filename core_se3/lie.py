"""Lie-group algebra of SO(3) and SE(3), batched over leading array axes (the bottom layer).

Conventions (see ``docs/CONVENTIONS.md``):

* a twist is ``xi = (v, w)`` -- translational part first, rotational part second (seed eq. E6);
* ``hat(xi) = [[hat3(w), v], [0, 0]]`` and ``exp(hat(xi)) = [[exp(hat3(w)), J_l(w) v], [0, 1]]``
  (seed eq. E6-1, with the seed's script-T equal to the left Jacobian ``J_l``);
* left trivialisation: strains are ``(g^-1 dg)^vee``, variations are ``g <- g exp(eta)``;
* ``dexp(xi)`` is the operator with ``(exp(-xi) d exp(xi))^vee = dexp(xi) dxi``, i.e.
  ``exp(xi + dxi) = exp(xi) exp(dexp(xi) dxi)``; ``dexp(xi) = sum_k (-1)^k/(k+1)! ad_xi^k``;
* ``Ad``, ``ad`` and ``adt`` (the seed's ad-tilde, ``adt(gamma) xi = ad(xi)^T gamma``) follow
  seed eqs. E6-2, E6-2s and E6-2ss.

Singularities: ``exp`` is smooth everywhere; ``log`` has its cut at rotation angle pi (it is
correct *at* pi, where the axis sign is a free choice); ``dexp_inv`` is singular at angles
2 pi n, n >= 1.  Every function accepts arrays with arbitrary leading axes ``(...)``.

All coefficient functions switch to Taylor series in theta^2 below ``_SERIES`` so that they are
accurate to round-off near theta = 0 and stay complex-analytic (the element uses complex-step
differentiation of ``dexp_inv``).

Units: translational parts (v, positions) in the model's length unit, rotations in radians.
The examples run in this module's namespace (``from core_se3.lie import *``, NumPy as ``np``).
"""
from __future__ import annotations

from math import factorial

import numpy as np

__all__ = [
    "hat3", "vee3", "hat", "vee", "exp_so3", "log_so3", "exp", "log", "inv", "compose", "relative",
    "dexp", "dexp_inv", "dexp_inv_T_apply", "dexp_so3", "dexp_inv_so3", "Ad", "ad", "adt", "rotation_angle",
    "mean_rotation", "cross",
]

_SERIES = 1.0  # below this theta the series branch is used (closed forms are exact above)

# Bernoulli numbers |B_2n|, n = 1..10, for the series of c(theta) = (1 - theta/2 cot(theta/2))/theta^2
_B2N = [1 / 6, 1 / 30, 1 / 42, 1 / 30, 5 / 66, 691 / 2730, 7 / 6, 3617 / 510, 43867 / 798,
        174611 / 330]
_NTERMS = 10


def _series(coeffs, s):
    """sum_k coeffs[k] s^k (Horner, >= 2 coefficients) for an array s (real or complex)."""
    out = s * coeffs[-1] + coeffs[-2]
    for c in coeffs[-3::-1]:
        out = out * s + c
    return out


# Series in s = theta^2 of the scalar coefficient functions.
_A = [(-1) ** k / factorial(2 * k + 2) for k in range(_NTERMS)]            # (1-cos)/th^2
_S = [(-1) ** k / factorial(2 * k + 1) for k in range(_NTERMS)]            # sin/th
_Bc = [(-1) ** k / factorial(2 * k + 3) for k in range(_NTERMS)]           # (th-sin)/th^3
_dA = [(-1) ** k * 2 * k / factorial(2 * k + 2) for k in range(1, _NTERMS)]  # a'(th)/th
_dB = [(-1) ** k * 2 * k / factorial(2 * k + 3) for k in range(1, _NTERMS)]  # b'(th)/th
_C = [_B2N[n - 1] / factorial(2 * n) for n in range(1, _NTERMS + 1)]        # c(th)
_dC = [2 * (n - 1) * _B2N[n - 1] / factorial(2 * n) for n in range(2, _NTERMS + 1)]  # c'/th


def _coef(s, series, closed):
    """Coefficient as a function of s = theta^2: series below _SERIES, closed form above (only
    the branch in use where all entries lie on one side: half the calls on small arrays)."""
    small = np.abs(s.real if np.iscomplexobj(s) else s) < _SERIES ** 2
    if small.all():
        return _series(series, s)
    if not small.any():
        return closed(s, np.sqrt(s))
    s_big = np.where(small, 4.0, s)  # dummy value keeps the closed form finite on the small branch
    return np.where(small, _series(series, s), closed(s_big, np.sqrt(s_big)))


def hat3(w):
    """(..., 3) -> (..., 3, 3) skew matrix with hat3(w) @ y = w x y.

    Example
    -------
    >>> hat3([1.0, 2.0, 3.0]).tolist()
    [[0.0, -3.0, 2.0], [3.0, 0.0, -1.0], [-2.0, 1.0, 0.0]]
    """
    w = np.asarray(w)
    out = np.zeros(w.shape[:-1] + (3, 3), dtype=w.dtype)    # six entry writes: no stacking
    out[..., 0, 1], out[..., 0, 2] = -w[..., 2], w[..., 1]
    out[..., 1, 0], out[..., 1, 2] = w[..., 2], -w[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -w[..., 1], w[..., 0]
    return out


def vee3(W):
    """(..., 3, 3) skew matrix -> (..., 3) vector (uses the skew part of W).

    Example
    -------
    >>> vee3(hat3([1.0, 2.0, 3.0])).tolist()
    [1.0, 2.0, 3.0]
    """
    return 0.5 * np.stack([W[..., 2, 1] - W[..., 1, 2], W[..., 0, 2] - W[..., 2, 0],
                           W[..., 1, 0] - W[..., 0, 1]], -1)


def hat(xi):
    """(..., 6) twist (v, w) -> (..., 4, 4) element of se(3) (seed eq. E5-11).

    Example
    -------
    >>> (hat([1.0, 2.0, 3.0, 0.0, 0.0, 0.5]) + 0.0).tolist()
    [[0.0, -0.5, 0.0, 1.0], [0.5, 0.0, 0.0, 2.0], [0.0, 0.0, 0.0, 3.0], [0.0, 0.0, 0.0, 0.0]]
    """
    xi = np.asarray(xi)
    out = np.zeros(xi.shape[:-1] + (4, 4), dtype=xi.dtype)
    out[..., :3, :3] = hat3(xi[..., 3:])
    out[..., :3, 3] = xi[..., :3]
    return out


def vee(X):
    """(..., 4, 4) element of se(3) -> (..., 6) twist (v, w) (seed eq. E6).

    Example
    -------
    >>> vee(hat([1.0, 2.0, 3.0, 0.1, 0.2, 0.3])).tolist()
    [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]
    """
    return np.concatenate([X[..., :3, 3], vee3(X[..., :3, :3])], -1)


def exp_so3(w):
    """Rodrigues: exp(hat3(w)) = I + sin(t)/t W + (1-cos t)/t^2 W^2, t = |w|.

    Parameters: w (..., 3) rotation vector [rad].  Returns: (..., 3, 3) rotation matrix.

    Example
    -------
    >>> (exp_so3([0.0, 0.0, np.pi / 2]).round(12) + 0.0).tolist()      # quarter turn about z
    [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    """
    w = np.asarray(w)
    s = np.einsum("...i,...i->...", w, w)
    W = hat3(w)
    a = _coef(s, _S, lambda s, t: np.sin(t) / t)
    b = _coef(s, _A, lambda s, t: (1 - np.cos(t)) / s)
    return np.eye(3) + a[..., None, None] * W + b[..., None, None] * (W @ W)


def rotation_angle(R):
    """Rotation angle in [0, pi] of R (..., 3, 3), robust near 0 and pi (atan2 of |sin| and cos).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import lie
    >>> float(np.round(lie.rotation_angle(lie.exp_so3([0.0, 0.0, 2.0])), 12))
    2.0
    """
    sinv = vee3(R)
    c = 0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0)
    return np.arctan2(np.linalg.norm(sinv, axis=-1), c)


def log_so3(R):
    """Rotation vector w with exp_so3(w) = R and |w| <= pi.

    Uses the skew part of R away from pi and the symmetric part near pi, where the skew part
    carries no information on the axis; at exactly pi the axis sign is a free choice.

    Parameters: R (..., 3, 3) rotation matrices.  Returns: (..., 3) rotation vectors [rad].

    Example
    -------
    >>> log_so3(exp_so3([0.3, -0.2, 0.1])).round(12).tolist(), log_so3(exp_so3([0.0, 0.0, np.pi])).tolist()
    ([0.3, -0.2, 0.1], [0.0, 0.0, 3.141592653589793])
    """
    R = np.asarray(R, dtype=float)
    sinv = vee3(R)                                         # sin(t) n
    c = np.clip(0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0), -1.0, 1.0)
    t = np.arctan2(np.linalg.norm(sinv, axis=-1), c)
    s = t * t
    fac = _coef(s, _S, lambda s, t: np.sin(t) / t)         # sin(t)/t
    near_pi = c < -0.5
    if not near_pi.any():                                  # every angle below 2 pi / 3
        return sinv / fac[..., None]
    fac_safe = np.where(near_pi, 1.0, fac)
    w_regular = sinv / fac_safe[..., None]
    # near pi: n n^T = (R + R^T - 2 c I) / (2 (1 - c)); take the best-conditioned column
    S = 0.5 * (R + np.swapaxes(R, -1, -2)) - c[..., None, None] * np.eye(3)
    S = S / np.where(near_pi, 1.0 - c, 1.0)[..., None, None]
    d = np.diagonal(S, axis1=-2, axis2=-1)
    k = np.argmax(d, axis=-1)
    col = np.take_along_axis(S, k[..., None, None], axis=-1)[..., 0]
    n = col / np.sqrt(np.maximum(np.take_along_axis(d, k[..., None], -1), 1e-300))
    sign = np.where(np.einsum("...i,...i->...", n, sinv) < 0, -1.0, 1.0)
    w_pi = (sign * t)[..., None] * n
    return np.where(near_pi[..., None], w_pi, w_regular)


def dexp_so3(w):
    """Right Jacobian J_r(w) = I - (1-cos t)/t^2 W + (t - sin t)/t^3 W^2 = dexp restricted to SO(3).

    Parameters: w (..., 3) rotation vector [rad].  Returns: (..., 3, 3) J_r(w), with
    exp_so3(w + dw) = exp_so3(w) exp_so3(J_r(w) dw) to first order in dw.

    Example
    -------
    >>> w, dw = np.array([0.4, 0.5, -0.6]), 1e-7 * np.array([-4.0, 5.0, 6.0])
    >>> np.allclose(exp_so3(w + dw), exp_so3(w) @ exp_so3(dexp_so3(w) @ dw), rtol=0, atol=1e-12)
    True
    """
    w = np.asarray(w)
    s = np.einsum("...i,...i->...", w, w)
    W = hat3(w)
    a = _coef(s, _A, lambda s, t: (1 - np.cos(t)) / s)
    b = _coef(s, _Bc, lambda s, t: (t - np.sin(t)) / (s * t))
    return np.eye(3) - a[..., None, None] * W + b[..., None, None] * (W @ W)


def _c_closed(s, t):
    return (1.0 - 0.5 * t / np.tan(0.5 * t)) / s


def _dc_closed(s, t):
    sh = np.sin(0.5 * t)
    return -2.0 / (s * s) + 1.0 / (2.0 * s * t * np.tan(0.5 * t)) + 1.0 / (4.0 * s * sh * sh)


def dexp_inv_so3(w):
    """Inverse right Jacobian J_r^-1(w) = I + W/2 + c(t) W^2, c = (1 - t/2 cot(t/2))/t^2.

    Parameters: w (..., 3) rotation vector [rad], |w| != 2 pi n.  Returns: (..., 3, 3) J_r^-1(w).

    Example
    -------
    >>> w = np.array([0.4, 0.5, -0.6])
    >>> np.allclose(dexp_inv_so3(w) @ dexp_so3(w), np.eye(3), rtol=0, atol=1e-14)
    True
    """
    w = np.asarray(w)
    s = np.einsum("...i,...i->...", w, w)
    W = hat3(w)
    c = _coef(s, _C, _c_closed)
    return np.eye(3) + 0.5 * W + c[..., None, None] * (W @ W)


def exp(xi):
    """exp: se(3) -> SE(3), (..., 6) -> (..., 4, 4) (seed eq. E6-1).

    Example
    -------
    >>> g = exp([0.0, -np.pi, 0.0, 0.0, 0.0, np.pi])   # half turn about the z axis through (1, 0, 0)
    >>> (g[:3, 3].round(12) + 0.0).tolist()               # carries the origin to (2, 0, 0)
    [2.0, 0.0, 0.0]
    """
    xi = np.asarray(xi, dtype=float)
    v, w = xi[..., :3], xi[..., 3:]
    out = np.zeros(xi.shape[:-1] + (4, 4))
    out[..., :3, :3] = exp_so3(w)
    Jl = np.swapaxes(dexp_so3(w), -1, -2)  # J_l = J_r^T
    out[..., :3, 3] = np.einsum("...ij,...j->...i", Jl, v)
    out[..., 3, 3] = 1.0
    return out


def log(g):
    """log: SE(3) -> se(3), (..., 4, 4) -> (..., 6) with rotation angle <= pi.

    Example
    -------
    >>> g = np.eye(4); g[:3, :3] = exp_so3([0.0, 0.0, np.pi / 2]); g[:3, 3] = (1.0, -1.0, 0.0)
    >>> (log(g) / (np.pi / 2)).round(12).tolist()   # quarter turn about z through (1, 0, 0): v = -w x q
    [0.0, -1.0, 0.0, 0.0, 0.0, 1.0]
    """
    g = np.asarray(g, dtype=float)
    w = log_so3(g[..., :3, :3])
    Jl_inv = np.swapaxes(dexp_inv_so3(w), -1, -2)  # J_l^-1 = J_r^-T
    v = np.einsum("...ij,...j->...i", Jl_inv, g[..., :3, 3])
    return np.concatenate([v, w], -1)


def inv(g):
    """Group inverse of (..., 4, 4) SE(3) matrices, [R^T, -R^T p].

    Example
    -------
    >>> g = exp([1.0, 2.0, 3.0, 0.1, 0.2, 0.3])
    >>> np.allclose(inv(g) @ g, np.eye(4), rtol=0, atol=1e-14)
    True
    """
    g = np.asarray(g)
    out = np.zeros_like(g)
    Rt = np.swapaxes(g[..., :3, :3], -1, -2)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, g[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def compose(g, h):
    """Group product g h (batched matrix product).

    Parameters: g, h (..., 4, 4) frames (broadcast).  Returns: (..., 4, 4) g h.

    Example
    -------
    >>> a, b = [0.0, 0.0, 1.0, 0.0, 0.0, 0.5], [0.0, 0.0, 2.0, 0.0, 0.0, 0.25]   # one screw axis
    >>> np.allclose(compose(exp(a), exp(b)), exp(np.add(a, b)), rtol=0, atol=1e-14)
    True
    """
    return np.asarray(g) @ np.asarray(h)


def relative(g_a, g_b):
    """g_a^-1 g_b = [[R_a^T R_b, R_a^T (p_b - p_a)], [0, 1]], the positions differenced first.

    The same product as ``inv(g_a) @ g_b`` without its round-off: that forms -R_a^T p_a and
    adds R_a^T p_b, two vectors of size |p| whose sum is of size |p_b - p_a|, and so loses
    eps |p| (a part 1e6 lengths from the origin and turned: 1e-10 on a unit edge, 2e-6 of a
    small displacement).  The difference p_b - p_a of nearby positions is exact.

    Parameters: g_a, g_b (..., 4, 4) frames (broadcast).  Returns: (..., 4, 4) g_a^-1 g_b.

    Example
    -------
    >>> g_a = np.eye(4); g_a[:3, :3] = exp_so3([0.3, -0.2, 0.1]); g_a[:3, 3] = (1.0e8, 2.0e8, 0.0)
    >>> g_b = g_a.copy(); g_b[0, 3] += 0.25                   # a quarter further along x
    >>> exact = g_a[:3, :3].T @ [0.25, 0.0, 0.0]
    >>> float(np.abs(relative(g_a, g_b)[:3, 3] - exact).max()), bool(np.abs((inv(g_a) @ g_b)[:3, 3] - exact).max() > 1e-9)
    (0.0, True)
    """
    g_a, g_b = np.asarray(g_a), np.asarray(g_b)
    Ra = g_a[..., :3, :3]
    shape = np.broadcast_shapes(g_a.shape, g_b.shape)
    out = np.zeros(shape, dtype=np.result_type(g_a, g_b))
    out[..., :3, :3] = np.swapaxes(Ra, -1, -2) @ g_b[..., :3, :3]
    out[..., :3, 3] = np.einsum("...ji,...j->...i", Ra, g_b[..., :3, 3] - g_a[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def _twist_parts(xi):
    """(|w|^2, w.v, hat3(w), hat3(v)) of twists xi = (v, w) (..., 6): what dexp and dexp_inv share."""
    xi = np.asarray(xi)
    v, w = xi[..., :3], xi[..., 3:]
    return (np.einsum("...i,...i->...", w, w), np.einsum("...i,...i->...", w, v), hat3(w), hat3(v))


def _block(A, B):
    """[[A, B], [0, A]] as (..., 6, 6)."""
    shape = np.broadcast_shapes(A.shape, B.shape)
    out = np.zeros(shape[:-2] + (6, 6), dtype=np.result_type(A, B))
    out[..., :3, :3] = A
    out[..., 3:, 3:] = A
    out[..., :3, 3:] = B
    return out


def dexp(xi):
    """dexp(xi) = sum_k (-1)^k/(k+1)! ad_xi^k, (..., 6) -> (..., 6, 6).

    Block form [[J_r(w), D J_r(w)[v]], [0, J_r(w)]]: the off-diagonal block of an analytic
    function of the block-triangular ad_xi is the directional derivative of that function.

    Example
    -------
    >>> xi, d = np.array([0.1, -0.2, 0.3, 0.4, 0.5, -0.6]), 1e-7 * np.array([1.0, -2, 3, -4, 5, 6])
    >>> np.allclose(exp(xi + d), exp(xi) @ exp(dexp(xi) @ d), rtol=0, atol=1e-12)
    True
    """
    s, wv, W, V = _twist_parts(xi)
    a = _coef(s, _A, lambda s, t: (1 - np.cos(t)) / s)
    b = _coef(s, _Bc, lambda s, t: (t - np.sin(t)) / (s * t))
    da = _coef(s, _dA, lambda s, t: (t * np.sin(t) - 2.0 * (1 - np.cos(t))) / (s * s))
    db = _coef(s, _dB, lambda s, t: (1 - np.cos(t)) / (s * s) - 3.0 * (t - np.sin(t)) / (s * s * t))
    e = lambda x: x[..., None, None]
    W2 = W @ W
    Jr = np.eye(3) - e(a) * W + e(b) * W2
    dJ = -e(da * wv) * W - e(a) * V + e(db * wv) * W2 + e(b) * (V @ W + W @ V)
    return _block(Jr, dJ)


def dexp_inv(xi, both=False):
    """Inverse of dexp: ``dxi = dexp_inv(xi) (exp(-xi) d exp(xi))^vee``; singular at |w| = 2 pi n.

    Parameters: xi (..., 6) twist, |w| != 2 pi n.  Returns: (..., 6, 6) dexp(xi)^-1 (closed form);
    with ``both``, (dexp_inv(xi), dexp_inv(-xi)) at the cost of one: they differ only in the sign
    of the terms odd in xi (W/2, V/2), since c, c' and w.v are even.

    Example
    -------
    >>> xi = np.array([0.1, -0.2, 0.3, 0.4, 0.5, -0.6])
    >>> Lp, Lm = dexp_inv(xi, both=True)
    >>> np.allclose(Lp @ dexp(xi), np.eye(6), rtol=0, atol=1e-14), np.allclose(Lm @ dexp(-xi), np.eye(6))
    (True, True)
    """
    s, wv, W, V = _twist_parts(xi)
    c = _coef(s, _C, _c_closed)
    dc = _coef(s, _dC, _dc_closed)
    e = lambda x: x[..., None, None]
    W2 = W @ W
    even_A = np.eye(3) + e(c) * W2                 # L = [[A, B], [0, A]] as in dexp_inv_T_apply
    even_B = e(dc * wv) * W2 + e(c) * (V @ W + W @ V)
    Lp = _block(even_A + 0.5 * W, even_B + 0.5 * V)
    return (Lp, _block(even_A - 0.5 * W, even_B - 0.5 * V)) if both else Lp


def dexp_inv_T_apply(xi, f):
    """dexp_inv(xi)^T f without forming the matrix (closed vector form; complex-safe):

    with L = [[A, B], [0, A]], A^T f = f - w x f / 2 + c w x (w x f),
    B^T f = -v x f / 2 + c'(w.v)/t w x (w x f) + c [w x (v x f) + v x (w x f)], with a x (b x f)
    = b (a.f) - f (a.b) expanded: w x (v x f) + v x (w x f) = v (w.f) + w (v.f) - 2 (w.v) f.

    Parameters: xi (..., 6) twists, f (..., 6) wrenches (arrays, real or complex).  Returns: (..., 6).

    Example
    -------
    >>> xi, f = np.array([0.1, -0.2, 0.3, 0.4, 0.5, -0.6]), np.array([1.0, 2, 3, 4, 5, 6])
    >>> np.allclose(dexp_inv_T_apply(xi, f), dexp_inv(xi).T @ f, rtol=0, atol=1e-13)
    True
    """
    v, w = xi[..., :3], xi[..., 3:]
    fv, fw = f[..., :3], f[..., 3:]
    dot = lambda a, b: np.einsum("...i,...i->...", a, b)[..., None]   # no conjugation: complex-safe
    s = dot(w, w)
    wv = dot(w, v)
    c = _coef(s, _C, _c_closed)
    dc = _coef(s, _dC, _dc_closed)
    wfv = dot(w, fv)
    wwfv = w * wfv - s * fv                                   # w x (w x fv)
    top = fv - 0.5 * cross(w, fv) + c * wwfv
    bot = (-0.5 * cross(v, fv) + (dc * wv) * wwfv + c * (v * wfv + w * dot(v, fv) - 2.0 * wv * fv)
           + fw - 0.5 * cross(w, fw) + c * (w * dot(w, fw) - s * fw))
    return np.concatenate([top, bot], -1)


def cross(a, b):
    """Cross product a x b over the last axis that keeps a complex dtype and broadcasts (faster
    than np.cross on small batches).

    Parameters: a, b (..., 3) arrays (not lists).  Returns: (..., 3) a x b.

    Example
    -------
    >>> cross(np.array([1.0, 0.0, 0.0]), np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 2.0]])).tolist()
    [[0.0, 0.0, 1.0], [0.0, -2.0, 0.0]]
    """
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    x = a1 * b2 - a2 * b1
    out = np.empty(x.shape + (3,), dtype=x.dtype)          # three writes: no stacking
    out[..., 0], out[..., 1], out[..., 2] = x, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
    return out


def Ad(g):
    """Adjoint Ad_g = [[R, hat(p) R], [0, R]] (seed eq. E6-2), (..., 4, 4) -> (..., 6, 6).

    Example
    -------
    >>> g, xi = exp([1.0, 2.0, 3.0, 0.1, 0.2, 0.3]), np.array([0.5, -1.0, 0.2, 0.3, 0.0, -0.4])
    >>> np.allclose(Ad(g) @ xi, vee(g @ hat(xi) @ inv(g)), rtol=0, atol=1e-14)
    True
    """
    g = np.asarray(g)
    R = g[..., :3, :3]
    return _block(R, hat3(g[..., :3, 3]) @ R)


def ad(xi):
    """ad_xi = [[hat(w), hat(v)], [0, hat(w)]] (seed eq. E6-2s); ad_xi eta = [xi, eta]^vee.

    Parameters: xi (..., 6) twists.  Returns: (..., 6, 6) ad_xi.

    Example
    -------
    >>> a, b = np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3]), np.array([0.5, -1.0, 0.2, 0.3, 0.0, -0.4])
    >>> np.allclose(ad(a) @ b, vee(hat(a) @ hat(b) - hat(b) @ hat(a)), rtol=0, atol=1e-14)
    True
    """
    xi = np.asarray(xi)
    return _block(hat3(xi[..., 3:]), hat3(xi[..., :3]))


def adt(gamma):
    """ad-tilde of a wrench gamma = (n, m): adt(gamma) xi = ad(xi)^T gamma (seed eq. E6-2ss).

    Parameters: gamma (..., 6) wrenches (force n, moment m).  Returns: (..., 6, 6) adt(gamma).

    Example
    -------
    >>> f, xi = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]), np.array([0.5, -1.0, 0.2, 0.3, 0.0, -0.4])
    >>> np.allclose(adt(f) @ xi, ad(xi).T @ f, rtol=0, atol=1e-14)
    True
    """
    gamma = np.asarray(gamma)
    N, M = hat3(gamma[..., :3]), hat3(gamma[..., 3:])
    out = np.zeros(gamma.shape[:-1] + (6, 6), dtype=gamma.dtype)
    out[..., :3, 3:] = N
    out[..., 3:, :3] = N
    out[..., 3:, 3:] = M
    return out


def mean_rotation(R):
    """Rotation nearest (Frobenius) to the mean of rotation matrices R (..., k, 3, 3) -> (..., 3, 3).

    The polar factor U V^T of the mean, with the sign of the last singular direction flipped where
    needed so that det = +1 (Moakher's chordal L2 mean).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import lie
    >>> R = lie.exp_so3(np.array([[0, 0, 0.1], [0, 0, 0.3]]))
    >>> np.allclose(lie.mean_rotation(R), lie.exp_so3([0, 0, 0.2]))
    True
    """
    U, _, Vt = np.linalg.svd(np.asarray(R, float).mean(-3))
    Q = U @ Vt
    flip = np.linalg.det(Q) < 0
    if np.any(flip):
        U[..., :, -1] *= np.where(flip, -1.0, 1.0)[..., None]
        Q = U @ Vt
    return Q
