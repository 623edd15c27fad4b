"""Resultant law (issue 2, "What to build" item 4): validation, plate bending, invariance.

Strain vector eps = (c_1, k_1, c_2, k_2) in R^12: c_a translational, k_a rotational strain of
parameter direction a, in the body frame (core_se3/material.py).  With A_1 = e1, A_2 = e2
(normal e3) the curvature is K_ab = (e3 x k_a) . A_b, so bending about the width axis e2 in
direction 1 is k_1 = kappa e2 (K_11 = -kappa), and in direction 2 it is k_2 = -kappa e1
(K_22 = -kappa).  The generalised stress is s = dW/d eps = Dmat eps.

All checks are algebraic identities on O(1)..O(1e5) numbers: relative tolerance 1e-12 (a
few hundred ulps; observed errors are at the 1e-16 level).
"""
import math

import numpy as np
import pytest

from core_se3.errors import CoreSE3Error, MaterialError, MeshError
from core_se3.fem import Material, strain_operators

REL = 1e-12   # algebraic identities: round-off of a 12x12 quadratic form (observed ~1e-16)
e1, e2, e3 = np.eye(3)


def _eps(c1=(0, 0, 0), k1=(0, 0, 0), c2=(0, 0, 0), k2=(0, 0, 0)):
    return np.concatenate([c1, k1, c2, k2]).astype(float)


def _close(a, b, rel=REL):
    return abs(a - b) <= rel * max(abs(a), abs(b), 1e-300)


# --------------------------------------------------------------------------- validation ----

@pytest.mark.parametrize("kw", [
    dict(E=0.0), dict(E=-1.0), dict(E=float("nan")), dict(E=float("inf")), dict(E=-float("inf")),
    dict(nu=-1.0), dict(nu=-1.5), dict(nu=0.5), dict(nu=0.7), dict(nu=float("nan")),
    dict(h=0.0), dict(h=-0.1), dict(h=float("nan")), dict(h=float("inf")),
    dict(shear_factor=0.0), dict(shear_factor=float("nan")),
    dict(E="1e6"), dict(h=None),
])
def test_invalid_material_raises(kw):
    args = dict(E=1e6, nu=0.3, h=0.1)
    args.update(kw)
    with pytest.raises(MaterialError) as exc:
        Material(**args)
    assert isinstance(exc.value, CoreSE3Error) and isinstance(exc.value, ValueError)
    # the message names the offending parameter
    assert list(kw)[0] in str(exc.value) or {"E": "Young", "nu": "Poisson", "h": "thickness",
                                              "shear_factor": "shear"}[list(kw)[0]] in str(exc.value)


@pytest.mark.parametrize("nu", [-0.999, -0.5, 0.0, 0.3, 0.499])
def test_valid_material_and_stiffnesses(nu):
    m = Material(2.0e5, nu, 0.02)
    assert _close(m.D, 2.0e5 * 0.02 ** 3 / (12 * (1 - nu ** 2)))
    assert _close(m.C, 2.0e5 * 0.02 / (1 - nu ** 2))
    assert _close(m.G, 2.0e5 / (2 * (1 + nu)))
    # Dmat is symmetric positive definite for every admissible nu (H >= min(1-nu, 1+nu) > 0)
    rng = np.random.default_rng(1)
    A1, A2 = rng.normal(size=3), rng.normal(size=3)
    Dm, j0 = m.resultant_matrix(A1, A2)
    assert np.abs(Dm - Dm.T).max() <= REL * np.abs(Dm).max()
    assert np.linalg.eigvalsh(Dm).min() > 0
    assert _close(j0, np.linalg.norm(np.cross(A1, A2)))


# ----------------------------------------------------------------------- plate law ----------

def test_cylindrical_bending_moment_is_D_kappa_and_poisson_coupling():
    """nu = 0.3: M_1 = dW/dkappa = D kappa (the seed's literal law would give D (1 - nu) kappa,
    30 % less) and the transverse moment is nu D kappa."""
    m = Material(2.1e5, 0.3, 0.1)
    kappa = 0.7
    Dm, j0 = m.resultant_matrix(e1, e2)
    assert _close(j0, 1.0)
    eps = _eps(k1=kappa * e2)
    s = Dm @ eps
    M1 = s @ _eps(k1=e2)                          # d W / d kappa   (eps = kappa * _eps(k1=e2))
    M2 = s @ _eps(k2=-e1)                         # d W / d kappa_2 (eps_2 = kappa_2 * _eps(k2=-e1))
    assert _close(M1, m.D * kappa), (M1, m.D * kappa)
    assert not _close(M1, m.D * (1 - m.nu) * kappa, 0.1)
    assert _close(M2, m.nu * m.D * kappa), (M2, m.nu * m.D * kappa)
    # energy: W = D kappa^2 / 2, and dW/dkappa by central differences of the quadratic
    # (exact for a quadratic up to round-off eps W / dk ~ 1e-12 relative at dk = 1e-4 kappa)
    W = m.energy_density(eps, e1, e2)
    assert _close(W, 0.5 * m.D * kappa ** 2)
    dk = 1e-4 * kappa
    dW = (m.energy_density(_eps(k1=(kappa + dk) * e2), e1, e2)
          - m.energy_density(_eps(k1=(kappa - dk) * e2), e1, e2)) / (2 * dk)
    assert _close(dW, m.D * kappa, 1e-9)
    # bending in direction 2 (about e1) is the same law
    s2 = Dm @ _eps(k2=-kappa * e1)
    assert _close(s2 @ _eps(k2=-e1), m.D * kappa)
    assert _close(s2 @ _eps(k1=e2), m.nu * m.D * kappa)
    # the all-round (spherical) state is stiffer by (1 + nu): M = D (1 + nu) kappa
    s3 = Dm @ _eps(k1=kappa * e2, k2=-kappa * e1)
    assert _close(s3 @ _eps(k1=e2), m.D * (1 + m.nu) * kappa)


def test_membrane_shear_drilling_stiffnesses():
    m = Material(7.0e4, 0.3, 0.05)
    Dm, _ = m.resultant_matrix(e1, e2)
    ex, gam, d = 1e-3, 2e-3, 0.4
    s = Dm @ _eps(c1=ex * e1)                                 # uniaxial membrane strain
    assert _close(s @ _eps(c1=e1), m.E * m.h / (1 - m.nu ** 2) * ex)
    assert _close(s @ _eps(c2=e2), m.nu * m.E * m.h / (1 - m.nu ** 2) * ex)
    s = Dm @ _eps(c1=gam * e3)                                # transverse shear, factor 1
    assert _close(s @ _eps(c1=e3), m.G * m.h * gam)
    assert np.abs(s - s @ _eps(c1=e3) * _eps(c1=e3)).max() <= REL * abs(s).max()  # uncoupled
    s = Dm @ _eps(c1=gam * e2)                                # e_12 alone (unsymmetrised law)
    assert _close(s @ _eps(c1=e2), m.C * (1 - m.nu) * gam)    # C (1 - nu) = 2 G h
    # engineering in-plane shear gamma (e_12 = e_21 = gamma/2): W = G h gamma^2 / 2
    W = m.energy_density(_eps(c1=gam / 2 * e2, c2=gam / 2 * e1), e1, e2)
    assert _close(W, 0.5 * m.G * m.h * gam ** 2)
    s = Dm @ _eps(k1=d * e3)                                  # drilling, D (1 - nu)
    assert _close(s @ _eps(k1=e3), m.D * (1 - m.nu) * d)
    ms = Material(7.0e4, 0.3, 0.05, shear_factor=5 / 6)
    s = ms.resultant_matrix(e1, e2)[0] @ _eps(c2=gam * e3)
    assert _close(s @ _eps(c2=e3), 5 / 6 * m.G * m.h * gam)


def test_energy_matches_independent_plate_law():
    """Orthonormal A: W = 1/2 [C((1-nu) e:e + nu (tr e)^2) + G h |g|^2
    + D((1-nu) K:K + nu (tr K)^2) + D (1-nu) |d|^2] with K_ab = (n x k_a).A_b."""
    rng = np.random.default_rng(2)
    m = Material(3.0e4, 0.27, 0.07)
    eps = rng.normal(size=(5, 12))
    c = [eps[:, 0:3], eps[:, 6:9]]
    k = [eps[:, 3:6], eps[:, 9:12]]
    A = [e1, e2]
    e = np.array([[c[a] @ A[b] for b in range(2)] for a in range(2)])        # (2,2,5)
    K = np.array([[np.cross(e3, k[a]) @ A[b] for b in range(2)] for a in range(2)])
    g = np.array([c[a] @ e3 for a in range(2)])
    d = np.array([k[a] @ e3 for a in range(2)])
    nu = m.nu
    W = 0.5 * (m.C * ((1 - nu) * (e ** 2).sum((0, 1)) + nu * (e[0, 0] + e[1, 1]) ** 2)
               + m.G * m.h * (g ** 2).sum(0)
               + m.D * ((1 - nu) * (K ** 2).sum((0, 1)) + nu * (K[0, 0] + K[1, 1]) ** 2)
               + m.D * (1 - nu) * (d ** 2).sum(0))
    Wm = m.energy_density(eps, np.tile(e1, (5, 1)), np.tile(e2, (5, 1)))
    assert Wm.shape == (5,)
    assert np.abs(Wm - W).max() <= REL * np.abs(W).max()


# ------------------------------------------------------------------------ invariance --------

def _rot(axis, angle):
    from core_se3 import lie
    return lie.exp_so3(angle * np.asarray(axis, float) / np.linalg.norm(axis))


def test_invariance_under_rotation_of_the_body_frame():
    """Rotating the in-plane body frame about the normal (all body components x -> Q^T x,
    A_a, c_a, k_a alike) leaves W and j0 unchanged; so does any rotation of the whole frame."""
    rng = np.random.default_rng(3)
    m = Material(1.0e5, 0.3, 0.1)
    for _ in range(5):
        A1, A2 = rng.normal(size=3), rng.normal(size=3)          # general (skew) tangents
        eps = rng.normal(size=12)
        n = np.cross(A1, A2)
        W = m.energy_density(eps, A1, A2)
        _, j0 = m.resultant_matrix(A1, A2)
        for Q in (_rot(n, rng.uniform(-np.pi, np.pi)), _rot(rng.normal(size=3), 2.5)):
            Qt = Q.T
            epsr = np.concatenate([Qt @ eps[3 * i:3 * i + 3] for i in range(4)])
            Wr = m.energy_density(epsr, Qt @ A1, Qt @ A2)
            _, j0r = m.resultant_matrix(Qt @ A1, Qt @ A2)
            assert _close(Wr * j0r, W * j0), (Wr, W)
            assert _close(j0r, j0)


@pytest.mark.parametrize("J", [
    [[1.0, 0.0], [0.0, 1.0]],
    [[2.0, 0.0], [0.0, 0.5]],          # scaling
    [[1.0, 0.7], [0.0, 1.0]],          # skew
    [[0.3, -1.2], [0.8, 0.9]],         # general
    [[0.0, 1.0], [1.0, 0.0]],          # swap: det < 0, the normal flips
    [[1.5, 0.4], [0.2, -0.6]],         # det < 0
])
def test_invariance_under_reparametrisation(J):
    """A'_a = J_ab A_b, eps'_a = J_ab eps_b: W is a density per unit reference area, so
    W' j0' = W j0 |det J| (equivalently W' = W) for skewed, scaled or flipped parameters."""
    J = np.asarray(J)
    rng = np.random.default_rng(4)
    m = Material(1.0e5, 0.3, 0.1)
    for _ in range(5):
        A = rng.normal(size=(2, 3))
        eps = rng.normal(size=(2, 6))
        Ap = J @ A
        epsp = J @ eps
        W = m.energy_density(eps.ravel(), A[0], A[1])
        Wp = m.energy_density(epsp.ravel(), Ap[0], Ap[1])
        j0 = m.resultant_matrix(A[0], A[1])[1]
        j0p = m.resultant_matrix(Ap[0], Ap[1])[1]
        # the map eps -> eps' has condition number cond(J) <= ~4: allow 10 x REL
        assert _close(j0p, j0 * abs(np.linalg.det(J)), 10 * REL)
        assert _close(Wp * j0p, W * j0 * abs(np.linalg.det(J)), 10 * REL), (Wp, W)


def test_bending_moment_independent_of_in_plane_orientation():
    """Cylindrical bending about an in-plane axis at angle t to A_1 (orthonormal A rotated by
    t about the normal) still gives M = D kappa along that axis and nu D kappa across."""
    m = Material(2.1e5, 0.3, 0.1)
    kappa = 0.3
    for t in [0.0, 0.4, 1.1, 2.9]:
        Q = _rot(e3, t)
        A1, A2 = Q @ e1, Q @ e2
        Dm, _ = m.resultant_matrix(A1, A2)
        # bending of the line along A1 about the axis A2, written with parameter direction 1
        s = Dm @ _eps(k1=kappa * A2)
        assert _close(s @ _eps(k1=A2), m.D * kappa)
        assert _close(s @ _eps(k2=-A1), m.nu * m.D * kappa)


# ------------------------------------------------------------------------ degeneracy --------

@pytest.mark.parametrize("A1,A2", [
    (e1, 2.5 * e1), (e1, -e1), (e1, np.zeros(3)), (np.zeros(3), e2), (e1, e1 + 1e-16 * e2),
    (e1, np.array([np.nan, 0, 0])),
])
def test_degenerate_tangents_raise_mesh_error(A1, A2):
    m = Material(1.0e5, 0.3, 0.1)
    with pytest.raises(MeshError):
        m.resultant_matrix(A1, A2)
    with pytest.raises(MeshError):
        m.energy_density(np.zeros(12), A1, A2)
    with pytest.raises(MeshError):
        strain_operators(np.stack([e1, A1]), np.stack([e2, A2]))     # one bad point in a batch
    assert math.isfinite(m.resultant_matrix(e1, e2)[1])


@pytest.mark.parametrize("index", [[0.5] * 8, [True] * 8, [], [[0] * 8]])
def test_a_region_material_index_that_is_no_list_of_law_ids_is_refused(index):
    """RegionMaterial([A, B], [0.5] * 8) was read as law 0 everywhere and [True] * 8 as law 1
    (the strip twice as stiff: tip 1.615 against 3.007), silently; an empty index was a bare
    ValueError of np.min."""
    from core_se3 import RegionMaterial
    with pytest.raises(MaterialError, match="RegionMaterial index must give one law per element"):
        RegionMaterial([Material(1.2e6, 0.0, 0.1), Material(2.4e6, 0.0, 0.1)], index)
