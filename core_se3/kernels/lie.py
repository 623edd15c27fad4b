"""Scalar SE(3)/SO(3) kernels (numba) for the compiled backend: the coefficient series, log, exp,
dexp_inv and dexp_inv(psi)^T F with its Jacobian, on single 3-vectors, twists and 4x4 frames.

They mirror ``core_se3.lie`` to round-off: every coefficient function of t switches to its
Taylor series in s = t^2 below s = 1 with the same coefficients, so the kernels are accurate
near t = 0 and agree with the reference up to the log's cut at t = pi.  Conventions as in
``lie``: a twist is xi = (v, w), translation first; left trivialisation; dexp_inv(xi) =
[[A, B], [0, A]] with A = I + W/2 + c(t) W^2, B = V/2 + c'(t)/t (w.v) W^2 + c(t) (V W + W V),
c(t) = (1 - t/2 cot(t/2)) / t^2, t = |w|, W = hat(w), V = hat(v).
"""
from __future__ import annotations

from math import atan2, cos, factorial, sin, sqrt, tan

import numpy as np
from numba import njit

# ------------------------------------------------------------------------------------------
# Coefficient series (identical to se3.py: Horner in s = theta^2, 10 terms, switch at s = 1)
# ------------------------------------------------------------------------------------------
_NT = 10
_B2N = [1 / 6, 1 / 30, 1 / 42, 1 / 30, 5 / 66, 691 / 2730, 7 / 6, 3617 / 510, 43867 / 798,
        174611 / 330]
_S = np.array([(-1) ** k / factorial(2 * k + 1) for k in range(_NT)])           # sin t / t
_A = np.array([(-1) ** k / factorial(2 * k + 2) for k in range(_NT)])           # (1-cos t)/t^2
_BC = np.array([(-1) ** k / factorial(2 * k + 3) for k in range(_NT)])          # (t-sin t)/t^3
_C = np.array([_B2N[n - 1] / factorial(2 * n) for n in range(1, _NT + 1)])       # c(t)
_DC = np.array([2 * (n - 1) * _B2N[n - 1] / factorial(2 * n) for n in range(2, _NT + 1)])  # c'/t
# c''-type coefficient (d/dt (c'(t)/t)) / t = 2 d/ds of the *truncated* _DC series: the exact
# derivative of the reference's own definition (which element.py differentiates by complex step)
_DDC = np.array([2.0 * k * _DC[k] for k in range(1, len(_DC))])


@njit(cache=True)
def _horner(coeffs, s):
    out = coeffs[-1]
    for k in range(len(coeffs) - 2, -1, -1):
        out = out * s + coeffs[k]
    return out


@njit(cache=True)
def coef_sinc(s):
    """sin(t)/t as a function of s = t^2."""
    if s < 1.0:
        return _horner(_S, s)
    t = sqrt(s)
    return sin(t) / t


@njit(cache=True)
def coef_cosc(s):
    """(1 - cos t)/t^2."""
    if s < 1.0:
        return _horner(_A, s)
    return (1.0 - cos(sqrt(s))) / s


@njit(cache=True)
def coef_sinc3(s):
    """(t - sin t)/t^3."""
    if s < 1.0:
        return _horner(_BC, s)
    t = sqrt(s)
    return (t - sin(t)) / (s * t)


@njit(cache=True)
def coef_c(s):
    """c(t) = (1 - t/2 cot(t/2))/t^2 (the W^2 coefficient of dexp_inv)."""
    if s < 1.0:
        return _horner(_C, s)
    t = sqrt(s)
    return (1.0 - 0.5 * t / tan(0.5 * t)) / s


@njit(cache=True)
def coef_dc(s):
    """c'(t)/t = -2/s^2 + 1/(2 s t tan(t/2)) + 1/(4 s sin^2(t/2))."""
    if s < 1.0:
        return _horner(_DC, s)
    t = sqrt(s)
    sh = sin(0.5 * t)
    return -2.0 / (s * s) + 1.0 / (2.0 * s * t * tan(0.5 * t)) + 1.0 / (4.0 * s * sh * sh)


@njit(cache=True)
def coef_ddc(s):
    """(d/dt (c'(t)/t))/t = 8/s^3 - 3/(2 s^2 t tan h) - 3/(4 s^2 sin^2 h) - cos h/(4 s t sin^3 h),
    h = t/2 (derivative of coef_dc; series branch: derivative of its truncated series)."""
    if s < 1.0:
        return _horner(_DDC, s)
    t = sqrt(s)
    h = 0.5 * t
    sh = sin(h)
    return (8.0 / (s * s * s) - 3.0 / (2.0 * s * s * t * tan(h)) - 3.0 / (4.0 * s * s * sh * sh)
            - cos(h) / (4.0 * s * t * sh * sh * sh))


# ------------------------------------------------------------------------------------------
# SO(3) / SE(3) kernels on small arrays (out-parameters, no allocation)
# ------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def log_so3(R, w):
    """w (3,) <- log(R) with |w| <= pi, the algorithm of se3.log_so3: the skew part of R away
    from pi (w = sin(t) n / (sin t / t)); for cos t < -1/2 the symmetric part,
    n n^T = (R + R^T - 2 c I) / (2 (1 - c)), best-conditioned column, sign from the skew part."""
    s0 = 0.5 * (R[2, 1] - R[1, 2])
    s1 = 0.5 * (R[0, 2] - R[2, 0])
    s2 = 0.5 * (R[1, 0] - R[0, 1])
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    c = min(max(c, -1.0), 1.0)
    t = atan2(sqrt(s0 * s0 + s1 * s1 + s2 * s2), c)
    if c < -0.5:
        inv = 1.0 / (1.0 - c)
        d0 = (R[0, 0] - c) * inv
        d1 = (R[1, 1] - c) * inv
        d2 = (R[2, 2] - c) * inv
        if d0 >= d1 and d0 >= d2:
            k, dk = 0, d0
        elif d1 >= d2:
            k, dk = 1, d1
        else:
            k, dk = 2, d2
        nrm = 1.0 / sqrt(max(dk, 1e-300))
        n0 = (0.5 * (R[0, k] + R[k, 0]) - (c if k == 0 else 0.0)) * inv * nrm
        n1 = (0.5 * (R[1, k] + R[k, 1]) - (c if k == 1 else 0.0)) * inv * nrm
        n2 = (0.5 * (R[2, k] + R[k, 2]) - (c if k == 2 else 0.0)) * inv * nrm
        sg = -1.0 if n0 * s0 + n1 * s1 + n2 * s2 < 0 else 1.0
        w[0], w[1], w[2] = sg * t * n0, sg * t * n1, sg * t * n2
    else:
        fac = coef_sinc(t * t)
        w[0], w[1], w[2] = s0 / fac, s1 / fac, s2 / fac


@njit(cache=True)
def cross3(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True, inline="always")
def log_se3(g_a, g_b, R, psi):
    """psi (6,) <- log(g_a^-1 g_b) = (J_l^-1(w) p, w), R = R_a^T R_b, p = R_a^T (p_b - p_a),
    J_l^-1 p = p - w x p / 2 + c(t) w x (w x p).  R (3,3) is scratch."""
    for i in range(3):
        for j in range(3):
            R[i, j] = g_a[0, i] * g_b[0, j] + g_a[1, i] * g_b[1, j] + g_a[2, i] * g_b[2, j]
    d0 = g_b[0, 3] - g_a[0, 3]
    d1 = g_b[1, 3] - g_a[1, 3]
    d2 = g_b[2, 3] - g_a[2, 3]
    p0 = g_a[0, 0] * d0 + g_a[1, 0] * d1 + g_a[2, 0] * d2
    p1 = g_a[0, 1] * d0 + g_a[1, 1] * d1 + g_a[2, 1] * d2
    p2 = g_a[0, 2] * d0 + g_a[1, 2] * d1 + g_a[2, 2] * d2
    log_so3(R, psi[3:])
    w0, w1, w2 = psi[3], psi[4], psi[5]
    c = coef_c(w0 * w0 + w1 * w1 + w2 * w2)
    x0, x1, x2 = cross3(w0, w1, w2, p0, p1, p2)
    y0, y1, y2 = cross3(w0, w1, w2, x0, x1, x2)
    psi[0] = p0 - 0.5 * x0 + c * y0
    psi[1] = p1 - 0.5 * x1 + c * y1
    psi[2] = p2 - 0.5 * x2 + c * y2


@njit(cache=True)
def exp_se3(xi, g):
    """g (4,4) <- exp(xi) = [[I + a W + b W^2, (I + b W + d W^2) v], [0, 1]] with
    a = sin t/t, b = (1-cos t)/t^2, d = (t - sin t)/t^3 (se3.exp: J_l = J_r^T)."""
    w0, w1, w2 = xi[3], xi[4], xi[5]
    s = w0 * w0 + w1 * w1 + w2 * w2
    a = coef_sinc(s)
    b = coef_cosc(s)
    d = coef_sinc3(s)
    W = ((0.0, -w2, w1), (w2, 0.0, -w0), (-w1, w0, 0.0))
    for i in range(3):
        for j in range(3):
            W2 = (w0 if i == 0 else w1 if i == 1 else w2) * (w0 if j == 0 else w1 if j == 1 else w2)
            if i == j:
                W2 -= s
            g[i, j] = (1.0 if i == j else 0.0) + a * W[i][j] + b * W2
    v0, v1, v2 = xi[0], xi[1], xi[2]
    x0, x1, x2 = cross3(w0, w1, w2, v0, v1, v2)
    y0, y1, y2 = cross3(w0, w1, w2, x0, x1, x2)
    g[0, 3] = v0 + b * x0 + d * y0
    g[1, 3] = v1 + b * x1 + d * y1
    g[2, 3] = v2 + b * x2 + d * y2
    g[3, 0] = g[3, 1] = g[3, 2] = 0.0
    g[3, 3] = 1.0


@njit(cache=True)
def fill_L(psi, c, dc, sign, scale, out):
    """out (6,6) <- scale * dexp_inv(sign * psi) = scale [[A, B], [0, A]] with
    A = I + sign W/2 + c W^2, B = sign V/2 + dc (w.v) W^2 + c (V W + W V)
    (W^2 = w w^T - s I, V W + W V = w v^T + v w^T - 2 (w.v) I)."""
    v0, v1, v2, w0, w1, w2 = psi[0], psi[1], psi[2], psi[3], psi[4], psi[5]
    s = w0 * w0 + w1 * w1 + w2 * w2
    wv = w0 * v0 + w1 * v1 + w2 * v2
    h = 0.5 * sign
    for i in range(3):
        wi = w0 if i == 0 else w1 if i == 1 else w2
        vi = v0 if i == 0 else v1 if i == 1 else v2
        for j in range(3):
            wj = w0 if j == 0 else w1 if j == 1 else w2
            vj = v0 if j == 0 else v1 if j == 1 else v2
            W2 = wi * wj
            VW = wi * vj + vi * wj
            if i == j:
                W2 -= s
                VW -= 2.0 * wv
            a = scale * ((1.0 if i == j else 0.0) + c * W2)
            b = scale * (dc * wv * W2 + c * VW)
            out[i, j] = a
            out[i + 3, j + 3] = a
            out[i, j + 3] = b
            out[i + 3, j] = 0.0
    # skew parts: sign/2 hat(w) on A, sign/2 hat(v) on B
    hs = scale * h
    out[0, 1] -= hs * w2
    out[0, 2] += hs * w1
    out[1, 0] += hs * w2
    out[1, 2] -= hs * w0
    out[2, 0] -= hs * w1
    out[2, 1] += hs * w0
    out[3, 4] -= hs * w2
    out[3, 5] += hs * w1
    out[4, 3] += hs * w2
    out[4, 5] -= hs * w0
    out[5, 3] -= hs * w1
    out[5, 4] += hs * w0
    out[0, 4] -= hs * v2
    out[0, 5] += hs * v1
    out[1, 3] += hs * v2
    out[1, 5] -= hs * v0
    out[2, 3] -= hs * v1
    out[2, 4] += hs * v0


@njit(cache=True)
def dexp_inv_se3(psi, out):
    """out (6,6) <- dexp_inv(psi) (se3.dexp_inv)."""
    s = psi[3] * psi[3] + psi[4] * psi[4] + psi[5] * psi[5]
    fill_L(psi, coef_c(s), coef_dc(s), 1.0, 1.0, out)


@njit(cache=True)
def dexp_inv_T_apply(psi, c, dc, sign, F, out, scale):
    """out (6,) <- scale * dexp_inv(sign psi)^T F (closed vector form of se3.dexp_inv_T_apply):
    top = f_v - w' x f_v/2 + c w x (w x f_v),
    bot = -v' x f_v/2 + dc (w.v) w x (w x f_v) + c [w x (v x f_v) + v x (w x f_v)]
          + f_w - w' x f_w/2 + c w x (w x f_w),        (w', v') = sign (w, v)."""
    v0, v1, v2, w0, w1, w2 = psi[0], psi[1], psi[2], psi[3], psi[4], psi[5]
    f0, f1, f2, m0, m1, m2 = F[0], F[1], F[2], F[3], F[4], F[5]
    wv = w0 * v0 + w1 * v1 + w2 * v2
    a0, a1, a2 = cross3(w0, w1, w2, f0, f1, f2)        # w x fv
    b0, b1, b2 = cross3(w0, w1, w2, a0, a1, a2)        # w x (w x fv)
    e0, e1, e2 = cross3(v0, v1, v2, f0, f1, f2)        # v x fv
    p0, p1, p2 = cross3(w0, w1, w2, e0, e1, e2)        # w x (v x fv)
    q0, q1, q2 = cross3(v0, v1, v2, a0, a1, a2)        # v x (w x fv)
    k0, k1, k2 = cross3(w0, w1, w2, m0, m1, m2)        # w x fw
    l0, l1, l2 = cross3(w0, w1, w2, k0, k1, k2)        # w x (w x fw)
    h = 0.5 * sign
    out[0] = scale * (f0 - h * a0 + c * b0)
    out[1] = scale * (f1 - h * a1 + c * b1)
    out[2] = scale * (f2 - h * a2 + c * b2)
    dw = dc * wv
    out[3] = scale * (-h * e0 + dw * b0 + c * (p0 + q0) + m0 - h * k0 + c * l0)
    out[4] = scale * (-h * e1 + dw * b1 + c * (p1 + q1) + m1 - h * k1 + c * l1)
    out[5] = scale * (-h * e2 + dw * b2 + c * (p2 + q2) + m2 - h * k2 + c * l2)


@njit(cache=True)
def hat_add(M, i0, j0, x0, x1, x2, s):
    """M[i0:i0+3, j0:j0+3] += s hat(x)."""
    M[i0, j0 + 1] -= s * x2
    M[i0, j0 + 2] += s * x1
    M[i0 + 1, j0] += s * x2
    M[i0 + 1, j0 + 2] -= s * x0
    M[i0 + 2, j0] -= s * x1
    M[i0 + 2, j0 + 1] += s * x0


@njit(cache=True)
def ddw_add(M, i0, j0, w0, w1, w2, f0, f1, f2, s):
    """M[i0:, j0:] += s d/dw [w x (w x f)] = s [(w.f) I + w f^T - 2 f w^T]."""
    wf = w0 * f0 + w1 * f1 + w2 * f2
    for i in range(3):
        wi = w0 if i == 0 else w1 if i == 1 else w2
        fi = f0 if i == 0 else f1 if i == 1 else f2
        for j in range(3):
            wj = w0 if j == 0 else w1 if j == 1 else w2
            fj = f0 if j == 0 else f1 if j == 1 else f2
            M[i0 + i, j0 + j] += s * ((wf if i == j else 0.0) + wi * fj - 2.0 * fi * wj)


@njit(cache=True)
def outer_add(M, i0, j0, a0, a1, a2, b0, b1, b2, s):
    """M[i0:, j0:] += s a b^T."""
    M[i0, j0] += s * a0 * b0
    M[i0, j0 + 1] += s * a0 * b1
    M[i0, j0 + 2] += s * a0 * b2
    M[i0 + 1, j0] += s * a1 * b0
    M[i0 + 1, j0 + 1] += s * a1 * b1
    M[i0 + 1, j0 + 2] += s * a1 * b2
    M[i0 + 2, j0] += s * a2 * b0
    M[i0 + 2, j0 + 1] += s * a2 * b1
    M[i0 + 2, j0 + 2] += s * a2 * b2


@njit(cache=True)
def dexp_inv_T_jacobian(psi, c, dc, ddc, F, J):
    """J (6,6) <- d (dexp_inv(psi)^T F) / d psi, analytically (element.py takes it by complex
    step).  With m = dexp_inv_T_apply(psi, F) = (top, bot), c = c(s), dc w = grad c, ddc w =
    grad dc and d/dw [w x (w x f)] = (w.f) I + w f^T - 2 f w^T =: D(f):

      d top/dv = 0,
      d top/dw = hat(f_v)/2 + (w x w x f_v)(dc w)^T + c D(f_v),
      d bot/dv = hat(f_v)/2 + dc (w x w x f_v) w^T - c hat(w) hat(f_v) - c hat(w x f_v),
      d bot/dw = (w.v)(w x w x f_v)(ddc w)^T + dc (w x w x f_v) v^T + dc (w.v) D(f_v)
                 + (w x (v x f_v) + v x (w x f_v))(dc w)^T - c [hat(v x f_v) + hat(v) hat(f_v)]
                 + hat(f_w)/2 + (w x w x f_w)(dc w)^T + c D(f_w).
    """
    v0, v1, v2, w0, w1, w2 = psi[0], psi[1], psi[2], psi[3], psi[4], psi[5]
    f0, f1, f2, m0, m1, m2 = F[0], F[1], F[2], F[3], F[4], F[5]
    wv = w0 * v0 + w1 * v1 + w2 * v2
    wf = w0 * f0 + w1 * f1 + w2 * f2
    vf = v0 * f0 + v1 * f1 + v2 * f2
    a0, a1, a2 = cross3(w0, w1, w2, f0, f1, f2)        # w x fv
    b0, b1, b2 = cross3(w0, w1, w2, a0, a1, a2)        # w x (w x fv)
    e0, e1, e2 = cross3(v0, v1, v2, f0, f1, f2)        # v x fv
    p0, p1, p2 = cross3(w0, w1, w2, e0, e1, e2)        # w x (v x fv)
    q0, q1, q2 = cross3(v0, v1, v2, a0, a1, a2)        # v x (w x fv)
    l0, l1, l2 = cross3(w0, w1, w2, *cross3(w0, w1, w2, m0, m1, m2))   # w x (w x fw)
    for i in range(6):
        for j in range(6):
            J[i, j] = 0.0
    # top / w
    hat_add(J, 0, 3, f0, f1, f2, 0.5)
    outer_add(J, 0, 3, b0, b1, b2, w0, w1, w2, dc)
    ddw_add(J, 0, 3, w0, w1, w2, f0, f1, f2, c)
    # bot / v: -c hat(w) hat(fv) = -c (fv w^T - (w.fv) I)
    hat_add(J, 3, 0, f0, f1, f2, 0.5)
    outer_add(J, 3, 0, b0, b1, b2, w0, w1, w2, dc)
    outer_add(J, 3, 0, f0, f1, f2, w0, w1, w2, -c)
    J[3, 0] += c * wf
    J[4, 1] += c * wf
    J[5, 2] += c * wf
    hat_add(J, 3, 0, a0, a1, a2, -c)
    # bot / w: -c hat(v) hat(fv) = -c (fv v^T - (v.fv) I)
    outer_add(J, 3, 3, b0, b1, b2, w0, w1, w2, wv * ddc)
    outer_add(J, 3, 3, b0, b1, b2, v0, v1, v2, dc)
    ddw_add(J, 3, 3, w0, w1, w2, f0, f1, f2, dc * wv)
    outer_add(J, 3, 3, p0 + q0, p1 + q1, p2 + q2, w0, w1, w2, dc)
    hat_add(J, 3, 3, e0, e1, e2, -c)
    outer_add(J, 3, 3, f0, f1, f2, v0, v1, v2, -c)
    J[3, 3] += c * vf
    J[4, 4] += c * vf
    J[5, 5] += c * vf
    hat_add(J, 3, 3, m0, m1, m2, 0.5)
    outer_add(J, 3, 3, l0, l1, l2, w0, w1, w2, dc)
    ddw_add(J, 3, 3, w0, w1, w2, m0, m1, m2, c)


@njit(cache=True)
def ad_exp_minus(psi, Ad):
    """Ad (6,6) <- Ad_{exp(-psi)} = [[R, hat(t) R], [0, R]], (R, t) = exp(-psi) (se3.Ad, se3.exp)."""
    v0, v1, v2, w0, w1, w2 = -psi[0], -psi[1], -psi[2], -psi[3], -psi[4], -psi[5]
    s = w0 * w0 + w1 * w1 + w2 * w2
    a = coef_sinc(s)
    b = coef_cosc(s)
    d = coef_sinc3(s)
    for i in range(3):
        wi = w0 if i == 0 else w1 if i == 1 else w2
        for j in range(3):
            wj = w0 if j == 0 else w1 if j == 1 else w2
            Ad[i, j] = (1.0 if i == j else 0.0) + b * (wi * wj - (s if i == j else 0.0))
    Ad[0, 1] -= a * w2
    Ad[0, 2] += a * w1
    Ad[1, 0] += a * w2
    Ad[1, 2] -= a * w0
    Ad[2, 0] -= a * w1
    Ad[2, 1] += a * w0
    x0, x1, x2 = cross3(w0, w1, w2, v0, v1, v2)
    y0, y1, y2 = cross3(w0, w1, w2, x0, x1, x2)
    t0, t1, t2 = v0 + b * x0 + d * y0, v1 + b * x1 + d * y1, v2 + b * x2 + d * y2
    for j in range(3):
        r0, r1, r2 = Ad[0, j], Ad[1, j], Ad[2, j]
        h0, h1, h2 = cross3(t0, t1, t2, r0, r1, r2)     # hat(t) R[:, j]
        Ad[0, j + 3], Ad[1, j + 3], Ad[2, j + 3] = h0, h1, h2
        for i in range(3):
            Ad[i + 3, j + 3] = Ad[i, j]
            Ad[i + 3, j] = 0.0


@njit(cache=True)
def retract(g, eta, out):
    """out[i] = g[i] exp(eta[i]) for nodal frames g (n, 4, 4) and twists eta (n, 6): the
    exponential update of a Newton iteration (the paper's Algorithm 1, g <- g exp(eta))."""
    h = np.empty((4, 4))
    for i in range(g.shape[0]):
        exp_se3(eta[i], h)
        for r in range(3):
            for c in range(4):
                acc = g[i, r, 3] if c == 3 else 0.0
                for k in range(3):
                    acc += g[i, r, k] * h[k, c]
                out[i, r, c] = acc
        out[i, 3, 0] = out[i, 3, 1] = out[i, 3, 2] = 0.0
        out[i, 3, 3] = 1.0


@njit(cache=True)
def geodesic_point(g_a, g_b, t, out):
    """out (4,4) <- g_a exp(t log(g_a^-1 g_b)): the point at parameter t of the SE(3) geodesic
    from g_a (t = 0) to g_b (t = 1) (a probe between two nodes)."""
    R = np.empty((3, 3))
    psi = np.empty(6)
    log_se3(g_a, g_b, R, psi)
    for i in range(6):
        psi[i] *= t
    h = np.empty((4, 4))
    exp_se3(psi, h)
    for r in range(3):
        for c in range(4):
            acc = g_a[r, 3] if c == 3 else 0.0
            for k in range(3):
                acc += g_a[r, k] * h[k, c]
            out[r, c] = acc
    out[3, 0] = out[3, 1] = out[3, 2] = 0.0
    out[3, 3] = 1.0
