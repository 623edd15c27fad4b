"""Exact finite in-plane bending of a Cosserat-membrane strip (the closed form behind the
``inplane-rollup`` case).

A strip of width w (|Y| <= w/2) bent in its plane by end couples M takes the state
(Rivlin's finite bending of a block, here for the project's resultant law of
``fem.material``): the material line X = const becomes a ray, the line Y = const the circle
of radius r(Y), the frame R is the polar rotation R_z(kappa X) and the drilling curvature is
kappa.  The membrane strains are diagonal, e_11 = kappa r - 1 (hoop), e_22 = r' - 1 (radial),
and the law W = C/2 [(e_11^2 + e_22^2) + 2 nu e_11 e_22] (C = E h / (1 - nu^2)) gives the
linear equation r'' = kappa^2 r - (1 + nu) kappa with traction-free edges n_22(+-w/2) = 0:

    r(Y)    = (1 + nu)/kappa + (sinh(kappa Y) - nu cosh(kappa Y)) / (kappa cosh(kappa w/2)),
    n_11(Y) = E h sinh(kappa Y) / cosh(kappa w/2)         (hoop force per length, zero sum),
    M(kappa) = int n_11 r dY + drilling D (1 - nu) w kappa
             = E h (sinh(kappa w) - kappa w) / (2 kappa^2 cosh^2(kappa w/2))
               + drilling D (1 - nu) w kappa,                 D = E h^3 / (12 (1 - nu^2)).

For small kappa w the membrane part is E h w^3 kappa / 12 (the beam's "membrane circle");
it then softens: the strip thins (r' < 1) and its inner fibres shorten toward zero length.
The membrane moment has a maximum, 0.08585 E h w^2 at kappa w = 1.84 (``limit_moment``):
under a larger couple, with a drilling modulus too small to carry the rest, the strip has no
equilibrium at all.  That is why the seed's in-plane roll-up to 4 pi (M = 2 pi k EI / L with
k = 2, i.e. kappa w = 4 pi w / L = 1.257 in beam theory: 0.1047 E h w^2) cannot be reached
with a drilling modulus small enough to leave the membrane circle within 1 % (see
``drilling_for_rotation``).
"""
from __future__ import annotations

import math

__all__ = ["finite_bending_moment", "limit_moment", "drilling_for_rotation"]


def _membrane(kappa, E, h, w):
    x = kappa * w
    if abs(x) < 1e-3:                       # series of (sinh x - x) / (2 x^2 cosh^2(x/2)) w^2
        return E * h * w ** 3 * kappa / 12.0 * (1.0 - x * x / 20.0)
    return E * h * w * w * (math.sinh(x) - x) / (2.0 * x * x * math.cosh(0.5 * x) ** 2)


def finite_bending_moment(kappa, E, nu, h, w, drilling=0.0):
    """The end couple M [force x length] that bends the strip to the uniform curvature kappa
    (module docstring; exact for the resultant law of ``fem.Material``).

    Parameters
    ----------
    kappa : float
        Rotation of the cross-sections per reference length [1/length].
    E, nu, h : float
        Young's modulus, Poisson's ratio, thickness (as ``Material``).
    w : float
        Width of the strip [length].
    drilling : float, optional
        ``Material.drilling``: factor on the drilling-curvature modulus D (1 - nu).

    Returns
    -------
    float

    Example
    -------
    >>> E, h, w = 1200.0, 1.0, 1.0
    >>> round(finite_bending_moment(1e-4, E, 0.0, h, w) / (E * h * w ** 3 / 12 * 1e-4), 6)   # beam limit
    1.0
    >>> round(finite_bending_moment(4 * math.pi / 10, E, 0.0, h, w) / (E * h * w ** 3 / 12 * 4 * math.pi / 10), 4)
    0.7464
    """
    D = E * h ** 3 / (12.0 * (1.0 - nu ** 2))
    return _membrane(kappa, E, h, w) + drilling * D * (1.0 - nu) * w * kappa


def limit_moment(E, nu, h, w, drilling=0.0):
    """(M_max, kappa at M_max): the first maximum of M(kappa) along increasing curvature, the
    limit point of a load-controlled path from the flat strip.  A small drilling factor moves
    it a little; a large one (about 0.1 and more for nu = 0) makes M monotone, and then
    ``(inf, None)`` is returned.

    Example
    -------
    >>> M, k = limit_moment(1.0, 0.0, 1.0, 1.0)
    >>> round(M, 5), round(k, 2)                  # 0.08585 E h w^2 at kappa w = 1.84
    (0.08585, 1.84)
    >>> limit_moment(1.0, 0.0, 1.0, 1.0, drilling=1.0)
    (inf, None)
    """
    # golden-section search on kappa w in (0.5, 8): M is unimodal there or increasing
    a, b = 0.5 / w, 8.0 / w
    top = b
    gr = (math.sqrt(5.0) - 1.0) / 2.0
    f = lambda k: -finite_bending_moment(k, E, nu, h, w, drilling)
    c, d = b - gr * (b - a), a + gr * (b - a)
    for _ in range(100):
        if f(c) < f(d):
            b = d
        else:
            a = c
        c, d = b - gr * (b - a), a + gr * (b - a)
    k = 0.5 * (a + b)
    if k > top * (1.0 - 1e-6):
        return math.inf, None
    return finite_bending_moment(k, E, nu, h, w, drilling), k


def drilling_for_rotation(M, kappa, E, nu, h, w):
    """The drilling factor for which the couple M bends the strip to kappa (the rest of M
    beyond the membrane's finite-bending moment carried by the drilling curvature).

    Example
    -------
    The seed's roll-up to 4 pi (k = 2, L = 10, w = h = 1, E = 1200, nu = 0) under the beam
    couple M = 4 pi EI / L: only a drilling factor of 0.2536 makes its tip turn by 4 pi, and it
    stiffens the small-load circle by a quarter:

    >>> E, L = 1200.0, 10.0
    >>> kappa = 4 * math.pi / L
    >>> round(drilling_for_rotation(E / 12 * kappa, kappa, E, 0.0, 1.0, 1.0), 4)
    0.2536
    """
    D = E * h ** 3 / (12.0 * (1.0 - nu ** 2))
    return (M - _membrane(kappa, E, h, w)) / (D * (1.0 - nu) * w * kappa)
