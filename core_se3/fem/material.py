"""Isotropic linear-elastic Cosserat shell resultant law (seed eqs. E45-1, E45-2, corrected).

Strains at a point are the differences of left-trivialised twists, eps_a = zeta_a - zeta0_a =
(c_a, k_a) (translational, rotational), in the body frame of the material point; A_a are the
reference tangent vectors (translational parts of zeta0_a) and n the unit normal.

    membrane   e_ab = c_a . A_b                       (unsymmetrised, as the seed)
    shear      g_a  = c_a . n
    bending    K_ab = (n x k_a) . A_b                 (curvature; corrects the seed's E45-2)
    drilling   d_a  = k_a . n

    W = 1/2 [ Eh/(1-nu^2) H(e, e) + ks G h A^ab g_a g_b + D H(K, K) + D (1-nu) A^ab d_a d_b ]
    H(x, y) = nu (A^ab x_ab)(A^cd y_cd) + (1-nu) A^ac A^bd x_ab y_cd,   D = E h^3 / (12 (1-nu^2))

The seed applies H directly to the wryness components, which gives a cylindrical bending
stiffness D (1 - nu) and loses the Poisson coupling; writing bending on K restores the plate
law D[(1-nu) K:K + nu (tr K)^2].  W is per unit reference area [energy/length^2]; the
transverse-shear factor is 1 by default, as the seed's law gives.  ``Material.classical_shell``
(``classical=True``) is the Reissner-Mindlin law for comparisons with classical shells: H on the
symmetrised curvature (K_ab + K_ba)/2, the shear factor 5/6 and 1 % of the drilling modulus
(``CLASSICAL_DRILLING``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from ..errors import MaterialError, MeshError

__all__ = ["Material", "RegionMaterial", "ResultantLaw", "law_matrix", "strain_operators", "CLASSICAL_DRILLING",
           "SHEAR_STABILISATION_FLOOR", "STIFFNESS_RANGE", "stiffness_range_error", "E_RANGE_PA"]

#: Young's moduli of real solids [Pa]: soft gels (10 Pa) .. tungsten carbide (700 GPa).  A
#: scenario's E, and a magnet's mu0 against the material's E (the mu0 of tesla units fixes the
#: stress unit: MU0 for Pa, MU0 * 1e6 for MPa), are checked against it.
E_RANGE_PA = (10.0, 7e11)

#: the classical-shell law's factor on the drilling-curvature modulus (Material.classical_shell)
CLASSICAL_DRILLING = 0.01
#: the default floor c of the shear stabilisation's factor (Material.shear_stabilisation_floor)
SHEAR_STABILISATION_FLOOR = 0.05
#: the range of E h and E h^3/12 that double precision solves: below, the squares in the residual's
#: norms underflow (a strip at E = 1e-155, h = 0.1 had a singular tangent); above, the tangent
#: overflows (E = 1e308, h = 100: a non-finite residual); E h = 1e299 solved, to 9e-12
STIFFNESS_RANGE = (1e-150, 1e300)


def stiffness_range_error(E, h):
    """A message when the membrane stiffness E h or the bending stiffness E h^3/12 lies outside
    STIFFNESS_RANGE (E or h in units far from the problem's: the stiffness under- or overflows,
    and the solve fails with a singular tangent or no convergence), else None.

    Example
    -------
    >>> stiffness_range_error(1.2e6, 0.1) is None, stiffness_range_error(1.2e6, 1e-120)[:43]
    (True, 'the bending stiffness E h^3/12 = 0 (E = 1.2')
    """
    lo, hi = STIFFNESS_RANGE
    for what, value in (("membrane stiffness E h", E * h), ("bending stiffness E h^3/12", E * h ** 3 / 12)):
        if not lo <= value <= hi:
            return (f"the {what} = {value:g} (E = {E:g}, h = {h:g}) lies outside {lo:g} .. {hi:g}, where double "
                    "precision can solve it (it under- or overflows): give E and h in units near the problem's "
                    "scale (e.g. N, mm, MPa)")
    return None


@runtime_checkable
class ResultantLaw(Protocol):
    """What an element needs of a material: the 12x12 resultant stiffness at points.

    ``resultant_matrix(A1, A2) -> (Dmat, j0)`` with A1, A2 (..., 3) the reference tangents; see
    :meth:`Material.resultant_matrix`.  :class:`Material` (one law) and :class:`RegionMaterial`
    (a law per element) implement it.  A law whose stiffness depends on the element size (the
    shear stabilisation) says so by a true ``mesh_dependent`` attribute and then takes
    ``size=`` (the element size at the points, see :func:`law_matrix`).

    It is a runtime-checkable Protocol: any object with such a method is accepted (a user law,
    e.g. an orthotropic one, needs no base class).  A law the same in every in-plane direction
    says so by a true ``in_plane_isotropic`` attribute (:class:`Material`, :class:`RegionMaterial`
    of them): the default element may then build its frames turned about the normal from the
    user's (``mesh.gauge``); a law without it keeps the user's d1 as its material axis.

    Example
    -------
    >>> isinstance(Material(1.0e3, 0.3, 0.01), ResultantLaw), isinstance(object(), ResultantLaw)
    (True, False)
    """

    def resultant_matrix(self, A1, A2):
        ...


@dataclass(frozen=True)
class Material:
    """E [force/length^2], nu [-], h [length], shear_factor ks [-] (1 = the seed's law),
    drilling [-]: factor on the seed's drilling-curvature modulus D (1 - nu) (1 = the seed),
    rho [mass/length^3]: density, for gravity (optional).

    The drilling-curvature term is a micro-polar stiffness of the Cosserat surface: it adds
    drilling * D (1 - nu) w to the in-plane bending stiffness E h w^3 / 12 of a strip of width
    w, negligible when h << w, equal to it when h = w.  With drilling = 0 the drilling rotation
    is still tied to the in-plane rotation by the membrane law's skew part (2 G h).

    An isotropic linear-elastic resultant law (module docstring, seed eqs. E45-1, E45-2 with
    bending on the curvature K); frozen, so it can be shared and compared.  Invalid values raise
    :class:`~core_se3.errors.MaterialError`.

    Parameters
    ----------
    E : float
        Young's modulus [force/length^2], > 0.
    nu : float
        Poisson's ratio [-], in (-1, 0.5).
    h : float
        Thickness [length], > 0.
    shear_factor : float, optional
        Transverse-shear factor ks [-], > 0 (1 = the seed's law; 5/6 the usual Mindlin value).
    drilling : float, optional
        Factor on the drilling-curvature modulus D (1 - nu) [-], >= 0 (1 = the seed).
    rho : float or None, optional
        Density [mass/length^3], >= 0; needed only by gravity.
    classical : bool, optional
        False (the default): the seed's Cosserat bending law, H on the curvature K_ab itself,
        so its skew part (K_12 - K_21, the twist's rotation about the normal's gradient)
        carries energy too.  True: the classical (Reissner-Mindlin) shell, bending on the
        symmetrised curvature (K_ab + K_ba)/2 only; :meth:`classical_shell` also sets the shear
        factor 5/6.  Measured differences (docs/ELEMENTS.md): the thick strip's torsion constant
        (the Cosserat law's is about 20 % above Saint-Venant's) and Raasch's hook.
    shear_stabilisation : float, optional
        alpha >= 0 of Lyly, Stenberg and Vihinen's shear stabilisation (0, the default: off):
        on an element of size L (its longest reference edge) the transverse-shear modulus is
        ks G h * max(h^2 / (h^2 + alpha L^2), c), which tends to ks G h as the mesh is refined.
        It makes coarse meshes of moderately thick shells converge faster (Kratos' thick quad
        uses alpha = 0.1 without a floor); docs/ELEMENTS.md measures it.  Not for large
        deformations or concentrated (contact) forces on thin shells: there the floor's softer shear
        shows (Sze's pinched cylinder 16x16 deviates 13.9 % from its reference curve, default 3.2 %).
    shear_stabilisation_floor : float, optional
        c in [0, 1], the floor of that factor (default ``SHEAR_STABILISATION_FLOOR`` = 0.05; only
        with shear_stabilisation > 0).  Without it (c = 0) the factor falls to h^2 / (alpha L^2)
        on thin shells, the transverse shear becomes bending-order stiff and coarse thin meshes
        spuriously flexible (the thin roof 16x16 at R/h 1e5 1.124 of its converged deflection,
        the hemisphere 3x3 1.051); with c = 0.05 the thickness sweeps are the default element's
        and the thick coarse meshes keep the gain (benchmarks/results/capped_stabilisation.md).

    Attributes
    ----------
    G : float
        Shear modulus E / (2 (1 + nu)).
    D : float
        Plate bending stiffness E h^3 / (12 (1 - nu^2)) [force x length].
    C : float
        Membrane stiffness E h / (1 - nu^2) [force/length].

    Example
    -------
    >>> m = Material(E=1.2e6, nu=0.0, h=0.1)
    >>> round(m.D, 9), round(m.C, 9)
    (100.0, 120000.0)
    >>> Material(E=-1.0, nu=0.3, h=0.1)
    Traceback (most recent call last):
    ...
    core_se3.errors.MaterialError: Young's modulus E must be > 0, got -1.0
    """
    E: float
    nu: float
    h: float
    shear_factor: float = 1.0
    drilling: float = 1.0
    rho: float | None = None
    classical: bool = False
    shear_stabilisation: float = 0.0
    shear_stabilisation_floor: float = SHEAR_STABILISATION_FLOOR

    def __post_init__(self):
        for name in ("E", "nu", "h", "shear_factor", "drilling", "shear_stabilisation", "shear_stabilisation_floor"):
            v = getattr(self, name)
            if isinstance(v, (bool, np.bool_)):
                # True is the number 1 to Python: shear_stabilisation=True would be alpha = 1 (ten times
                # Kratos' 0.1), shear_stabilisation_floor=True the floor 1 (no stabilisation at all)
                raise MaterialError(f"material parameter {name} must be a finite number, got {v!r} (a boolean): "
                                    f"give its value" + (", e.g. shear_stabilisation=0.1" if name == "shear_stabilisation"
                                                         else ""))
            if not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(v):
                raise MaterialError(f"material parameter {name} must be a finite number, got {v!r}")
        if self.E <= 0:
            raise MaterialError(f"Young's modulus E must be > 0, got {self.E}")
        if not -1.0 < self.nu < 0.5:
            raise MaterialError(f"Poisson's ratio nu must lie in (-1, 0.5), got {self.nu}")
        if self.h <= 0:
            raise MaterialError(f"thickness h must be > 0, got {self.h}")
        if stiffness_range_error(self.E, self.h):
            raise MaterialError(stiffness_range_error(self.E, self.h))
        if self.shear_factor <= 0:
            raise MaterialError(f"shear factor must be > 0, got {self.shear_factor}")
        if self.drilling < 0:
            raise MaterialError(f"drilling factor must be >= 0, got {self.drilling}")
        if self.shear_stabilisation < 0:
            raise MaterialError(f"shear_stabilisation (alpha) must be >= 0, got {self.shear_stabilisation}")
        if not 0.0 <= self.shear_stabilisation_floor <= 1.0:
            raise MaterialError(f"shear_stabilisation_floor (c) must lie in [0, 1], got {self.shear_stabilisation_floor}")
        if not isinstance(self.classical, (bool, np.bool_)):
            raise MaterialError(f"classical must be True or False, got {self.classical!r}")
        if self.rho is not None and (isinstance(self.rho, bool) or not isinstance(self.rho, (int, float, np.floating, np.integer))
                                     or not math.isfinite(self.rho) or self.rho < 0):
            raise MaterialError(f"density rho must be a finite number >= 0 (or None), got {self.rho!r}")

    @classmethod
    def classical_shell(cls, E, nu, h, **kw):
        """The classical (Reissner-Mindlin) shell law: bending on the symmetrised curvature, the
        shear factor 5/6 and ``drilling = CLASSICAL_DRILLING`` (0.01; all may be overridden by
        keywords).

        A classical shell has no energy in the drilling rotation's gradient.  The seed's drilling
        curvature (modulus D (1 - nu)) is a micro-polar stiffness: it stiffens the in-plane
        bending of a strip of width w by about h^2 / ((1 + nu) w^2) (the twisted beam's
        out-of-plane load 1.8 % stiff at 48x8, MacNeal and Harder's straight cantilever 19 %).
        1 % of it keeps that below 0.02 % on the course and keeps the free patch's drilling
        pattern off zero energy (at drilling = 0 a free curved or distorted patch has a seventh
        zero mode).  docs/ELEMENTS.md has the numbers.

        Example
        -------
        >>> m = Material.classical_shell(1.0e3, 0.3, 0.01)
        >>> m.classical, round(m.shear_factor, 12), m.drilling
        (True, 0.833333333333, 0.01)
        """
        kw.setdefault("shear_factor", 5.0 / 6.0)
        kw.setdefault("drilling", CLASSICAL_DRILLING)
        return cls(E, nu, h, classical=True, **kw)

    @property
    def G(self):
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def D(self):
        """Plate bending stiffness E h^3 / (12 (1 - nu^2))."""
        return self.E * self.h ** 3 / (12.0 * (1.0 - self.nu ** 2))

    @property
    def C(self):
        """Membrane stiffness E h / (1 - nu^2)."""
        return self.E * self.h / (1.0 - self.nu ** 2)

    @property
    def mesh_dependent(self):
        """True if the stiffness depends on the element size (``shear_stabilisation`` > 0)."""
        return self.shear_stabilisation > 0

    def restricted(self, elements):
        """The law of some elements: the same (one law for all).

        Example
        -------
        >>> m = Material(1.0e3, 0.3, 0.01)
        >>> m.restricted(slice(0, 5)) is m
        True
        """
        return self

    #: the law is the same in every in-plane direction (``ResultantLaw``; ``mesh.gauge``)
    in_plane_isotropic = True

    def resultant_matrix(self, A1, A2, size=None):
        """12x12 stiffness on (eps_1, eps_2) at points with reference tangents A1, A2 (..., 3).

        ``size`` (broadcastable to A1.shape[:-1]) [length]: the element size at the points,
        needed with ``shear_stabilisation`` > 0 (the shear modulus times h^2 / (h^2 + alpha
        size^2)), ignored otherwise.

        Returns (Dmat, j0): ``W = 1/2 eps^T Dmat eps`` per unit reference area, and the area
        element j0 = |A1 x A2| that turns the parameter measure into reference area.

        Example
        -------
        >>> import numpy as np
        >>> D, j0 = Material(1.0e3, 0.0, 0.01).resultant_matrix(np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
        >>> D.shape, float(j0), float(D[0, 0])            # D[0, 0] = C = E h on e_11 (nu = 0)
        ((12, 12), 1.0, 10.0)
        """
        ops, Ainv, j0 = strain_operators(A1, A2)
        Mm, Ms, Mb, Md = ops
        if self.classical:                       # bending on (K_ab + K_ba)/2
            Mb = _SYM @ Mb
        nu = self.nu
        H = (nu * np.einsum("...ab,...cd->...abcd", Ainv, Ainv)
             + (1 - nu) * np.einsum("...ac,...bd->...abcd", Ainv, Ainv))
        H = H.reshape(H.shape[:-4] + (4, 4))
        Dm = self.C * H
        Db = self.D * H
        Ds = self.shear_factor * self.G * self.h * Ainv
        if self.mesh_dependent:                  # Lyly, Stenberg and Vihinen (1993)
            if size is None:
                raise MaterialError("shear_stabilisation needs the element size: evaluate the law through "
                                    "fem.law_matrix(law, A1, A2, size) or an element")
            Ds = Ds * self.shear_scale(size)[..., None, None]
        Dd = self.drilling * self.D * (1 - nu) * Ainv
        T = lambda M: np.swapaxes(M, -1, -2)
        Dmat = (T(Mm) @ Dm @ Mm + T(Ms) @ Ds @ Ms + T(Mb) @ Db @ Mb + T(Md) @ Dd @ Md)
        return Dmat, j0

    def shear_scale(self, size):
        """max(h^2 / (h^2 + alpha size^2), c): the factor of the transverse-shear modulus on
        elements of size ``size`` [length] (Lyly, Stenberg and Vihinen 1993, CMAME 110, 343-357;
        the floor c = ``shear_stabilisation_floor`` keeps thin shells' shear at membrane order).

        Example
        -------
        >>> law = Material(1.0, 0.3, 0.1, shear_stabilisation=0.1)
        >>> [round(float(law.shear_scale(L)), 12) for L in (1.0, 10.0)]        # L/h 10: the floor
        [0.090909090909, 0.05]
        """
        h2 = self.h * self.h
        lsv = h2 / (h2 + self.shear_stabilisation * np.square(np.asarray(size, float)))
        return np.maximum(lsv, self.shear_stabilisation_floor)

    def energy_density(self, eps, A1, A2, size=None):
        """W per unit reference area for strains eps (..., 12) (``size`` as in resultant_matrix)."""
        Dmat, _ = self.resultant_matrix(A1, A2, size)
        return 0.5 * np.einsum("...i,...ij,...j->...", eps, Dmat, eps)


def law_matrix(law, A1, A2, size):
    """(Dmat, j0) of a law at points with reference tangents A1, A2 on elements of size ``size``
    (broadcastable to A1.shape[:-1]): the size goes to laws that use it (``mesh_dependent``),
    so user laws with the two-argument ``resultant_matrix`` keep working.

    Example
    -------
    >>> import numpy as np
    >>> law = Material(1.0e3, 0.0, 0.1, shear_stabilisation=0.1)
    >>> D, _ = law_matrix(law, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), 1.0)
    >>> round(float(D[2, 2] / (law.G * law.h)), 6)                # ks G h * h^2 / (h^2 + 0.1)
    0.090909
    """
    if getattr(law, "mesh_dependent", False):
        return law.resultant_matrix(A1, A2, size=size)
    return law.resultant_matrix(A1, A2)


# the symmetrising projector on (x_11, x_12, x_21, x_22)
_SYM = np.array([[1.0, 0, 0, 0], [0, 0.5, 0.5, 0], [0, 0.5, 0.5, 0], [0, 0, 0, 1.0]])


def strain_operators(A1, A2):
    """Linear maps from eps = (eps_1, eps_2) in R^12 to the membrane, shear, bending, drilling
    measures (shapes (...,4,12), (...,2,12), (...,4,12), (...,2,12)), with A^ab and j0.

    Parameters
    ----------
    A1, A2 : (..., 3) array_like
        Reference tangent vectors (the translational parts of zeta0_1, zeta0_2) in the body
        frame, not parallel.

    Returns
    -------
    ops : tuple of ndarray
        (Mm, Ms, Mb, Md): e_ab = c_a . A_b, g_a = c_a . n, K_ab = (n x k_a) . A_b, d_a = k_a . n.
    Ainv : (..., 2, 2) ndarray
        The inverse metric A^ab.
    j0 : (...) ndarray
        The area element |A1 x A2|.  Parallel or zero tangents raise
        :class:`~core_se3.errors.MeshError`.

    Example
    -------
    >>> (Mm, Ms, Mb, Md), Ainv, j0 = strain_operators([1.0, 0, 0], [0, 2.0, 0])
    >>> Mm.shape, Ms.shape, Ainv.tolist(), float(j0)
    ((4, 12), (2, 12), [[1.0, 0.0], [0.0, 0.25]], 2.0)
    """
    A1 = np.asarray(A1, float)
    A2 = np.asarray(A2, float)
    A = np.stack([A1, A2], -2)                                   # (..., 2, 3)
    cross = np.cross(A1, A2)
    j0 = np.linalg.norm(cross, axis=-1)
    if np.any(~np.isfinite(j0)) or np.any(j0 <= 1e-14 * (np.linalg.norm(A1, axis=-1) * np.linalg.norm(A2, axis=-1) + 1e-300)):
        raise MeshError("degenerate reference geometry: tangent vectors A1, A2 are parallel or zero "
                        "(zero-area or collapsed element)")
    n = cross / j0[..., None]
    Amet = np.einsum("...ai,...bi->...ab", A, A)
    # the 2x2 inverse in closed form (det = |A1 x A2|^2 = j0^2 > 0, checked above); a batched
    # LAPACK inverse of many 2x2 blocks costs milliseconds of call overhead
    Ainv = np.empty_like(Amet)
    Ainv[..., 0, 0], Ainv[..., 1, 1] = Amet[..., 1, 1], Amet[..., 0, 0]
    Ainv[..., 0, 1], Ainv[..., 1, 0] = 0.0 - Amet[..., 0, 1], 0.0 - Amet[..., 1, 0]
    Ainv /= (Amet[..., 0, 0] * Amet[..., 1, 1] - Amet[..., 0, 1] * Amet[..., 1, 0])[..., None, None]
    shape = A1.shape[:-1]
    Mm = np.zeros(shape + (4, 12))
    Mb = np.zeros(shape + (4, 12))
    Ms = np.zeros(shape + (2, 12))
    Md = np.zeros(shape + (2, 12))
    Axn = np.cross(A, n[..., None, :])                           # A_b x n, (..., 2, 3)
    for a in range(2):
        for b in range(2):
            Mm[..., 2 * a + b, 6 * a:6 * a + 3] = A[..., b, :]
            Mb[..., 2 * a + b, 6 * a + 3:6 * a + 6] = Axn[..., b, :]   # (n x k).A = k.(A x n)
        Ms[..., a, 6 * a:6 * a + 3] = n
        Md[..., a, 6 * a + 3:6 * a + 6] = n
    return (Mm, Ms, Mb, Md), Ainv, j0


class RegionMaterial:
    """A material that differs per element (e.g. per region): ``materials`` (k distinct
    Material), ``index`` (m,) into them.

    The element asks ``resultant_matrix(A1, A2)`` at the Gauss points of all elements at once
    (A1, A2 of shape (m, ..., 3)); this class answers with each element's own law, grouped by
    distinct material so that the work stays batched:
    W_e = 1/2 eps^T D(E_e, nu_e, h_e, ks_e, drilling_e) eps on element e.  Scalar properties
    (E, nu, h, ...) are available when they are the same on every element; otherwise reading
    one raises MaterialError (loads that need h per element, such as gravity or magnetisation,
    must then be built per region with that region's h).

    Parameters
    ----------
    materials : sequence of Material
        The distinct laws.
    index : (m,) array of int
        The law of every element (an index into ``materials``).

    Example
    -------
    >>> import numpy as np
    >>> law = RegionMaterial.from_regions(4, Material(1.0, 0.3, 0.1), {(2, 3): Material(2.0, 0.3, 0.1)})
    >>> law.per_element("E").tolist(), law.h
    ([1.0, 1.0, 2.0, 2.0], 0.1)
    >>> law.E
    Traceback (most recent call last):
    ...
    core_se3.errors.MaterialError: E differs between regions ([1.0, 2.0]); use per_element('E')
    """

    def __init__(self, materials, index):
        self.materials = list(materials)
        raw = np.asarray(index)
        if not self.materials or any(not isinstance(m, Material) for m in self.materials):
            raise MaterialError("RegionMaterial needs a list of core_se3.Material")
        # (0.5 was read as law 0 and True as law 1, silently; an empty index was a bare ValueError)
        if raw.ndim != 1 or raw.size == 0 or raw.dtype.kind not in "iuf" or not np.all(np.isfinite(raw)) \
                or not np.array_equal(raw, np.round(raw)):
            raise MaterialError(f"RegionMaterial index must give one law per element, whole numbers 0 .. "
                                f"{len(self.materials) - 1}, got {raw.ravel()[:6].tolist()} (shape {raw.shape})")
        self.index = raw.astype(np.int64)
        if self.index.min() < 0 or self.index.max() >= len(self.materials):
            raise MaterialError(f"RegionMaterial index must give one law per element: 0 .. {len(self.materials) - 1} "
                                f"for {len(self.materials)} materials, got {self.index.min()} .. {self.index.max()}")

    #: every law is in-plane isotropic (``ResultantLaw``): the materials are :class:`Material`
    in_plane_isotropic = True

    @classmethod
    def from_regions(cls, n_elements, base, regions):
        """``base`` everywhere except on the element sets of ``regions`` {ids: Material}."""
        mats, index = [base], np.zeros(n_elements, np.int64)
        seen = np.zeros(n_elements, bool)
        for ids, mat in regions.items() if isinstance(regions, dict) else regions:
            ids = np.asarray(ids, np.int64)
            if np.any(seen[ids]):
                raise MaterialError("material regions overlap: an element would get two materials")
            seen[ids] = True
            if mat not in mats:
                mats.append(mat)
            index[ids] = mats.index(mat)
        return cls(mats, index)

    def __len__(self):
        return len(self.index)

    def per_element(self, name):
        """Property ``name`` (E, nu, h, ...) of every element, (m,)."""
        return np.array([getattr(m, name) for m in self.materials])[self.index]

    def _uniform(self, name):
        vals = {getattr(m, name) for m in self.materials if np.any(self.index == self.materials.index(m))}
        if len(vals) != 1:
            raise MaterialError(f"{name} differs between regions ({sorted(vals, key=repr)}); use per_element({name!r})")
        return vals.pop()

    E = property(lambda self: self._uniform("E"))
    nu = property(lambda self: self._uniform("nu"))
    h = property(lambda self: self._uniform("h"))
    shear_factor = property(lambda self: self._uniform("shear_factor"))
    classical = property(lambda self: self._uniform("classical"))
    drilling = property(lambda self: self._uniform("drilling"))
    rho = property(lambda self: self._uniform("rho"))
    shear_stabilisation = property(lambda self: self._uniform("shear_stabilisation"))
    shear_stabilisation_floor = property(lambda self: self._uniform("shear_stabilisation_floor"))

    @property
    def mesh_dependent(self):
        """True if any of the laws depends on the element size."""
        return any(m.mesh_dependent for m in self.materials)

    def restricted(self, elements):
        """The law of the elements ``elements`` (a slice or index array) only.

        Example
        -------
        >>> import numpy as np
        >>> r = RegionMaterial([Material(1.0, 0.0, 0.1), Material(2.0, 0.0, 0.1)], np.array([0, 1, 1]))
        >>> r.restricted(slice(1, 3)).per_element("E").tolist()
        [2.0, 2.0]
        """
        return RegionMaterial(self.materials, self.index[elements])

    def resultant_matrix(self, A1, A2, size=None):
        """(Dmat, j0) as Material.resultant_matrix, each element (leading axis) with its own law."""
        A1 = np.asarray(A1, float)
        A2 = np.asarray(A2, float)
        if size is not None:
            size = np.broadcast_to(np.asarray(size, float), A1.shape[:-1])
        if A1.shape[0] != len(self.index):
            raise MaterialError(f"RegionMaterial has a law for {len(self.index)} elements, the mesh (or its part) "
                                f"{A1.shape[0]}: give its index one law per element of the mesh")
        D = np.empty(A1.shape[:-1] + (12, 12))
        j0 = np.empty(A1.shape[:-1])
        for k, mat in enumerate(self.materials):
            sel = self.index == k
            if np.any(sel):
                D[sel], j0[sel] = mat.resultant_matrix(A1[sel], A2[sel], None if size is None else size[sel])
        return D, j0
