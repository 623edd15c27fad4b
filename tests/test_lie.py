"""SE(3) algebra (issue 2, "What to build" item 2): identities and finite differences.

Conventions under test (core_se3/lie.py): twist xi = (v, w), translational part first;
left trivialisation; ``exp(xi + dxi) = exp(xi) exp(dexp(xi) dxi)``.

Tolerances.  Pure algebra on O(1) numbers is held to a few hundred ulps (1e-13 absolute on
O(1) entries; the observed errors are 1e-16 .. 1e-15).  Central finite differences with step
h = 1e-6 have truncation error h^2/6 |f'''| ~ 1e-13 and round-off eps |f| / h ~ 1e-10 for the
O(1..10) arguments used here (observed 1e-10 .. 6e-10), so they are held to 1e-8 relative.
"""
import numpy as np
import pytest

from core_se3 import lie

EPS = np.finfo(float).eps
ALG_TOL = 1e-13      # round-off of O(1) matrix products and trig functions (observed <= 1.4e-15)
FD_H = 1e-6
FD_TOL = 1e-8        # h = 1e-6 central differences: round-off ~ eps/h ~ 1e-10, truncation ~ h^2


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _twists(rng, n, angle, vscale=1.0):
    """n random twists whose rotation part has exactly the given angle."""
    v = vscale * rng.normal(size=(n, 3))
    w = angle * _unit(rng.normal(size=(n, 3)))
    return np.concatenate([v, w], 1)


def _rand_g(rng, shape=()):
    xi = rng.normal(size=shape + (6,)) * np.array([1, 1, 1, 2, 2, 2])
    return lie.exp(xi)


# ----------------------------------------------------------------------------- hat / vee ---

def test_hat_vee_round_trips_and_cross_product():
    rng = np.random.default_rng(10)
    w = rng.normal(size=(2, 3, 3))
    y = rng.normal(size=(2, 3, 3))
    W = lie.hat3(w)
    assert W.shape == (2, 3, 3, 3)
    assert np.array_equal(lie.vee3(W), w)                      # exact (no arithmetic but /2*2)
    assert np.array_equal(W, -np.swapaxes(W, -1, -2))          # skew
    # hat3(w) y = w x y (a few ulps of the products)
    assert np.abs(np.einsum("...ij,...j->...i", W, y) - np.cross(w, y)).max() < ALG_TOL
    xi = rng.normal(size=(2, 3, 6))
    X = lie.hat(xi)
    assert X.shape == (2, 3, 4, 4)
    assert np.array_equal(lie.vee(X), xi)
    assert np.array_equal(X[..., 3, :], np.zeros((2, 3, 4)))
    assert np.array_equal(X[..., :3, 3], xi[..., :3])          # v first: translational part
    assert np.array_equal(lie.vee3(X[..., :3, :3]), xi[..., 3:])


def test_batched_shapes_match_pointwise_evaluation():
    """Every function accepts leading axes (2, 3) and acts entry by entry (bitwise the same up
    to the order of floating-point operations: held to ALG_TOL)."""
    rng = np.random.default_rng(11)
    xi = rng.normal(size=(2, 3, 6)) * 1.5
    g = lie.exp(xi)
    gam = rng.normal(size=(2, 3, 6))
    funcs = {
        "exp": (lie.exp, xi, (4, 4)),
        "log": (lie.log, g, (6,)),
        "dexp": (lie.dexp, xi, (6, 6)),
        "dexp_inv": (lie.dexp_inv, xi, (6, 6)),
        "exp_so3": (lie.exp_so3, xi[..., 3:], (3, 3)),
        "log_so3": (lie.log_so3, g[..., :3, :3], (3,)),
        "dexp_so3": (lie.dexp_so3, xi[..., 3:], (3, 3)),
        "dexp_inv_so3": (lie.dexp_inv_so3, xi[..., 3:], (3, 3)),
        "Ad": (lie.Ad, g, (6, 6)),
        "ad": (lie.ad, xi, (6, 6)),
        "adt": (lie.adt, gam, (6, 6)),
        "inv": (lie.inv, g, (4, 4)),
    }
    for name, (f, arg, tail) in funcs.items():
        out = f(arg)
        assert out.shape == (2, 3) + tail, name
        for i in range(2):
            for j in range(3):
                assert np.abs(out[i, j] - f(arg[i, j])).max() < ALG_TOL, name


# ------------------------------------------------------------------------------ exp / log ---

@pytest.mark.parametrize("angle", [1e-12, 1e-8, 1e-4, 0.3, 1 - 1e-9, 1.0, 1 + 1e-9, 2.0, 3.0,
                                   np.pi - 1e-6, np.pi - 1e-9])
def test_exp_log_round_trip(angle):
    rng = np.random.default_rng(int(1e3 * angle) + 1)
    xi = _twists(rng, 40, angle)
    back = lie.log(lie.exp(xi))
    # log(exp(xi)) = xi for |w| < pi: relative round-off (observed <= 3e-16 of |xi|, and the
    # rotation part relative to its own size, below)
    assert np.abs(back - xi).max() <= ALG_TOL * np.abs(xi).max()
    rot_err = np.linalg.norm(back[:, 3:] - xi[:, 3:], axis=1) / angle
    assert rot_err.max() < 1e-12, rot_err.max()   # relative, even at angle 1e-12 (series branch)


def test_exp_log_at_exactly_pi():
    """log at angle exactly pi: the angle is pi, the axis sign is free, exp(log g) = g."""
    rng = np.random.default_rng(12)
    n = _unit(rng.normal(size=(50, 3)))
    n[0] = [0, 0, 1.0]                    # axis-aligned cases: the largest diagonal is exact
    n[1] = [1.0, 0, 0]
    n[2] = _unit(np.array([1.0, -1.0, 0]))
    R = 2 * np.einsum("ni,nj->nij", n, n) - np.eye(3)          # rotation by exactly pi about n
    g = np.zeros((50, 4, 4))
    g[:, :3, :3] = R
    g[:, :3, 3] = rng.normal(size=(50, 3))
    g[:, 3, 3] = 1.0
    xi = lie.log(g)
    angle = np.linalg.norm(xi[:, 3:], axis=1)
    assert np.abs(angle - np.pi).max() < 10 * EPS * np.pi       # observed 1.3e-15
    axis_dot = np.abs(np.einsum("ni,ni->n", xi[:, 3:] / angle[:, None], n))
    assert np.abs(axis_dot - 1).max() < ALG_TOL
    assert np.abs(lie.exp(xi) - g).max() < ALG_TOL             # observed 1.1e-15


@pytest.mark.parametrize("delta", [1e-6, 1e-8, 1e-10, 1e-12, 1e-14, 0.0])
def test_log_so3_accurate_near_pi(delta):
    """Within 1e-8 of pi the skew part carries no axis information; the symmetric part must."""
    rng = np.random.default_rng(13)
    n = _unit(rng.normal(size=(50, 3)))
    R = lie.exp_so3((np.pi - delta) * n)
    w = lie.log_so3(R)
    assert np.abs(lie.exp_so3(w) - R).max() < 1e-12            # observed <= 9e-16
    assert np.abs(np.linalg.norm(w, axis=1) - (np.pi - delta)).max() < 1e-12
    if delta >= 1e-12:
        # off the cut the axis sign is determined (the skew part sin(delta) n still exceeds its
        # round-off ~1e-16 by 1e4), and log must pick it: log(exp(w)) = w
        assert np.abs(w - (np.pi - delta) * n).max() < 1e-12


@pytest.mark.parametrize("angle", [7.0, 10 * np.pi, 20 * np.pi, 20 * np.pi + 0.3, 1e3])
def test_exp_large_angle_is_proper_se3(angle):
    rng = np.random.default_rng(14)
    xi = _twists(rng, 20, angle)
    g = lie.exp(xi)
    R = g[:, :3, :3]
    assert np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3)).max() < ALG_TOL
    assert np.abs(np.linalg.det(R) - 1).max() < ALG_TOL
    assert np.array_equal(g[:, 3], np.tile([0, 0, 0, 1.0], (20, 1)))
    # the logarithm returns an equivalent twist with angle <= pi that reproduces g
    back = lie.log(g)
    assert np.linalg.norm(back[:, 3:], axis=1).max() <= np.pi + 1e-12
    assert np.abs(lie.exp(back) - g).max() < 1e-12 * max(1.0, np.abs(g).max())
    # exp is a one-parameter subgroup: exp(xi) = exp(xi/2)^2 (no cut at any angle)
    h = lie.exp(0.5 * xi)
    assert np.abs(h @ h - g).max() < 1e-12 * max(1.0, np.abs(g).max())


def test_exp_matches_matrix_series():
    """exp(hat xi) against the truncated matrix power series (independent of Rodrigues)."""
    rng = np.random.default_rng(15)
    for angle in [1e-7, 0.5, 2.0, 3.0]:
        xi = _twists(rng, 1, angle)[0]
        X = lie.hat(xi)
        S, term = np.eye(4), np.eye(4)
        for k in range(1, 60):
            term = term @ X / k
            S = S + term
        assert np.abs(lie.exp(xi) - S).max() < ALG_TOL


# --------------------------------------------------------------------------- dexp / dexp_inv --

@pytest.mark.parametrize("angle", [1e-9, 1e-3, 0.7, 1.0, 2.0, 3.0, 3.1, 5.0, 9.0, 20 * np.pi + 1])
def test_dexp_against_finite_differences(angle):
    """dexp(xi) d = d/dh log(exp(-xi) exp(xi + h d)) at h = 0 (central differences)."""
    rng = np.random.default_rng(16)
    xi = _twists(rng, 1, angle)[0]
    D = lie.dexp(xi)
    gi = lie.inv(lie.exp(xi))
    Dfd = np.zeros((6, 6))
    for k in range(6):
        d = np.zeros(6)
        d[k] = FD_H
        Dfd[:, k] = (lie.log(gi @ lie.exp(xi + d)) - lie.log(gi @ lie.exp(xi - d))) / (2 * FD_H)
    err = np.abs(D - Dfd).max() / np.abs(D).max()
    # observed 7e-11 .. 6e-10; FD bound ~ eps |xi| / h
    assert err < FD_TOL * max(1.0, np.linalg.norm(xi) / 10), err


def test_dexp_equals_series_in_ad():
    """dexp(xi) = sum_k (-1)^k/(k+1)! ad_xi^k (the defining series) for moderate angles."""
    rng = np.random.default_rng(17)
    for angle in [1e-6, 0.4, 1.0, 2.5]:
        xi = _twists(rng, 1, angle)[0]
        A = lie.ad(xi)
        S, term = np.zeros((6, 6)), np.eye(6)
        for k in range(0, 80):
            S = S + term / np.prod(np.arange(1, k + 2, dtype=float))
            term = -term @ A
        assert np.abs(lie.dexp(xi) - S).max() < ALG_TOL


@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-9, 1e-4, 0.5, 1 - 1e-9, 1.0, 1 + 1e-9, 2.0,
                                   np.pi, 4.0, 6.0])
def test_dexp_inv_is_inverse(angle):
    rng = np.random.default_rng(18)
    xi = _twists(rng, 20, angle) if angle > 0 else np.concatenate(
        [rng.normal(size=(20, 3)), np.zeros((20, 3))], 1)
    D, Di = lie.dexp(xi), lie.dexp_inv(xi)
    # products of O(1) matrices (cond(dexp) <= ~10 below angle 6): observed <= 8e-16
    tol = ALG_TOL if angle < 5 else 1e-11
    assert np.abs(Di @ D - np.eye(6)).max() < tol
    assert np.abs(D @ Di - np.eye(6)).max() < tol
    # so(3) blocks as well
    Dr, Dri = lie.dexp_so3(xi[:, 3:]), lie.dexp_inv_so3(xi[:, 3:])
    assert np.abs(Dri @ Dr - np.eye(3)).max() < tol


@pytest.mark.parametrize("angle", [1 - 1e-9, 1 + 1e-9, 0.5, 1.2])
def test_series_and_closed_form_branches_agree(angle, monkeypatch):
    """At the series switch (|w| = 1) both branches, evaluated at the SAME argument, agree to
    1e-13: the 10-term series in theta^2 truncates at ~theta^20/22! (~1e-21 at theta = 1;
    the Bernoulli series of dexp_inv converges like (theta/2pi)^18 ~ 1e-15 at theta = 1, so it
    is only exercised up to 1.2, where it is ~1e-14) and the closed forms lose no more than a
    few ulps at theta ~ 1.  Observed differences: <= 7e-16 at 1 -+ 1e-9, 8e-15 at 1.2."""
    rng = np.random.default_rng(19)
    xi = _twists(rng, 10, angle)
    funcs = [lie.exp, lie.log, lie.dexp, lie.dexp_inv, lie.exp_so3, lie.dexp_so3, lie.dexp_inv_so3,
             lie.log_so3]
    args = [xi, lie.exp(xi), xi, xi, xi[:, 3:], xi[:, 3:], xi[:, 3:], lie.exp_so3(xi[:, 3:])]
    default = [f(a) for f, a in zip(funcs, args)]
    # flip the branch: series everywhere below 2 (it converges there) or closed form everywhere
    monkeypatch.setattr(lie, "_SERIES", 2.0 if angle >= 1.0 else 1e-30)
    flipped = [f(a) for f, a in zip(funcs, args)]
    for f, a, b in zip(funcs, default, flipped):
        assert np.abs(a - b).max() < 1e-13, (f.__name__, np.abs(a - b).max())


def test_dexp_continuous_across_series_switch():
    """Values just below and above |w| = 1 differ only by the O(2e-9) change of argument."""
    rng = np.random.default_rng(20)
    n = _unit(rng.normal(size=3))
    v = rng.normal(size=3)
    lo = np.concatenate([v, (1 - 1e-9) * n])
    hi = np.concatenate([v, (1 + 1e-9) * n])
    for f in (lie.dexp, lie.dexp_inv, lie.exp):
        # |f'| <= ~2 (1 + |v|): a jump between branches would be >> 2e-9 * that
        assert np.abs(f(hi) - f(lo)).max() < 2e-9 * 2 * (1 + np.linalg.norm(v)) + ALG_TOL


def test_dexp_inv_complex_step_matches_fd():
    """The element differentiates dexp_inv by complex step: it must be complex-analytic on both
    branches.  Complex step (h = 1e-30) is exact to round-off; the FD reference has ~1e-10."""
    rng = np.random.default_rng(21)
    for angle in [0.3, 1 - 1e-6, 1 + 1e-6, 1.5, 3.0, 5.0]:
        xi = _twists(rng, 1, angle)[0]
        for k in range(6):
            e = np.zeros(6)
            e[k] = 1.0
            cs = lie.dexp_inv(xi + 1e-30j * e).imag / 1e-30
            fd = (lie.dexp_inv(xi + FD_H * e) - lie.dexp_inv(xi - FD_H * e)) / (2 * FD_H)
            assert np.abs(cs - fd).max() < FD_TOL * max(np.abs(fd).max(), 1.0)


# ---------------------------------------------------------------------- singularity at 2 pi --

def test_dexp_inv_singular_at_two_pi_while_exp_smooth():
    rng = np.random.default_rng(22)
    n = _unit(rng.normal(size=3))
    v = rng.normal(size=3)
    norms = []
    for d in [1e-2, 1e-3, 1e-4]:
        xi = np.concatenate([v, (2 * np.pi - d) * n])
        norms.append(np.linalg.norm(lie.dexp_inv(xi), 2))
        # dexp loses rank at 2 pi: its smallest singular value -> 0
        assert np.linalg.svd(lie.dexp(xi), compute_uv=False).min() < 2 * d
    # the norm blows up (~1/d^2 from the translation block, at least ~1/d): observed
    # 3.4e4, 3.4e6, 3.4e8 (and 2.2 at angle 3); smallest singular value of dexp 3e-5 .. 3e-9
    assert norms[1] > 10 * norms[0] and norms[2] > 10 * norms[1], norms
    assert norms[2] > 1e6
    # far from 2 pi n it is modest
    assert np.linalg.norm(lie.dexp_inv(np.concatenate([v, 3.0 * n])), 2) < 100
    # exp is smooth through 2 pi: its central-difference Jacobian is bounded and continuous
    jac = []
    for t in [2 * np.pi - 1e-4, 2 * np.pi, 2 * np.pi + 1e-4]:
        xi = np.concatenate([v, t * n])
        jac.append(np.stack([(lie.exp(xi + FD_H * e) - lie.exp(xi - FD_H * e)) / (2 * FD_H)
                             for e in np.eye(6)], -1))
    # observed: max |J| = 0.12 scale, |J(+1e-4) - J(-1e-4)| = 2.7e-5 scale
    scale = 1 + np.linalg.norm(v)
    assert max(np.abs(J).max() for J in jac) < 2 * scale
    # second derivative bounded by ~scale: a change of 1e-4 moves the Jacobian by <~ 1e-4 scale
    assert np.abs(jac[2] - jac[0]).max() < 4e-4 * scale
    assert np.abs(jac[1] - jac[0]).max() < 2e-4 * scale


# ------------------------------------------------------------------------- Ad, ad, adt -------

def test_Ad_homomorphism_inverse_and_conjugation():
    rng = np.random.default_rng(23)
    g, h = _rand_g(rng, (2, 3)), _rand_g(rng, (2, 3))
    scale = np.abs(lie.Ad(g)).max() * np.abs(lie.Ad(h)).max()
    assert np.abs(lie.Ad(g @ h) - lie.Ad(g) @ lie.Ad(h)).max() < ALG_TOL * scale
    assert np.abs(lie.Ad(lie.inv(g)) - np.linalg.inv(lie.Ad(g))).max() < ALG_TOL * scale
    assert np.abs(lie.Ad(lie.inv(g)) @ lie.Ad(g) - np.eye(6)).max() < ALG_TOL * scale
    assert np.abs(lie.inv(g) @ g - np.eye(4)).max() < ALG_TOL * np.abs(g).max()
    xi = rng.normal(size=(2, 3, 6))
    lhs = g @ lie.exp(xi) @ lie.inv(g)
    rhs = lie.exp(np.einsum("...ij,...j->...i", lie.Ad(g), xi))
    assert np.abs(lhs - rhs).max() < ALG_TOL * np.abs(lhs).max() * 10
    # infinitesimal version: g hat(xi) g^-1 = hat(Ad_g xi)
    lhs = g @ lie.hat(xi) @ lie.inv(g)
    rhs = lie.hat(np.einsum("...ij,...j->...i", lie.Ad(g), xi))
    assert np.abs(lhs - rhs).max() < ALG_TOL * scale


def test_ad_is_the_lie_bracket_and_adt_its_transpose():
    rng = np.random.default_rng(24)
    xi, eta, gam = (rng.normal(size=(2, 3, 6)) for _ in range(3))
    X, Y = lie.hat(xi), lie.hat(eta)
    bracket = lie.vee(X @ Y - Y @ X)
    assert np.abs(np.einsum("...ij,...j->...i", lie.ad(xi), eta) - bracket).max() < ALG_TOL
    # adt(gamma) xi = ad(xi)^T gamma
    lhs = np.einsum("...ij,...j->...i", lie.adt(gam), xi)
    rhs = np.einsum("...ji,...j->...i", lie.ad(xi), gam)
    assert np.abs(lhs - rhs).max() < ALG_TOL
    # ad is the derivative of Ad: Ad_{exp(t xi)} = expm(t ad_xi) -> central FD at t = 0
    t = FD_H
    dAd = (lie.Ad(lie.exp(t * xi)) - lie.Ad(lie.exp(-t * xi))) / (2 * t)
    assert np.abs(dAd - lie.ad(xi)).max() < FD_TOL * np.abs(lie.ad(xi)).max()
    # Ad of exp equals the exponential of ad (dexp's block structure relies on it)
    A = lie.ad(xi[0, 0])
    S, term = np.eye(6), np.eye(6)
    for k in range(1, 60):
        term = term @ A / k
        S = S + term
    assert np.abs(lie.Ad(lie.exp(xi[0, 0])) - S).max() < ALG_TOL * np.abs(S).max()
