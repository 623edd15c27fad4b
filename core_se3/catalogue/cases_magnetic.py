"""Hard-magnetic catalogue cases (data only; the runner is ``catalogue.family_magnetic``).

Units: N, mm, MPa, T (so mu0 = 4 pi 1e-7 * 1e6 in these units, see ``fields.MU0``).  Strips lie
in the x-y plane (normal +z), clamped on x0; B^r_0 along +x (the beam axis) unless stated;
the applied field lies in the x-z plane at ``field_angle_deg`` from +x (90: perpendicular,
along +z; 180: antiparallel).  The planar references map as in ``cases``: u -> ux, v -> uz.

Zhao et al. 2019 (JMPS 124) beams: shear modulus 303 kPa and Lame lambda = 7300 kPa, i.e.
E = mu (3 lambda + 2 mu)/(lambda + mu) = 0.8969 MPa and nu = lambda / (2 (lambda + mu)) = 0.4801;
E is the primary parameter (``--set nu=0`` keeps E).
"""
from __future__ import annotations

from .case import Case, CaseLoad, add_case

__all__ = ["ZHAO_BEAMS", "zhao_nx", "MU_ZHAO", "LAMBDA_ZHAO", "GRAVITY_PHASE", "gravity_scale", "field_scale"]

GRAVITY_PHASE = 0.2     # magnetic-plate: lam in [0, 0.2] hangs the plate, lam in [0.2, 1] ramps the field


def gravity_scale(lam):
    return min(1.0, lam / GRAVITY_PHASE)


def field_scale(lam):
    return max(0.0, (lam - GRAVITY_PHASE) / (1.0 - GRAVITY_PHASE))

MU_ZHAO, LAMBDA_ZHAO = 0.303, 7.3                      # MPa
E_ZHAO = MU_ZHAO * (3 * LAMBDA_ZHAO + 2 * MU_ZHAO) / (LAMBDA_ZHAO + MU_ZHAO)
NU_ZHAO = LAMBDA_ZHAO / (2 * (LAMBDA_ZHAO + MU_ZHAO))

# (L, h) [mm] of the four beams and the elements along the length (seed s6.2: 30, 15, 15, 10
# elements for L/h = 41, 20.5, 17.5 (sic: 20.5), 10).
ZHAO_BEAMS = ((11.0, 1.1, 10), (19.2, 1.1, 15), (17.2, 0.84, 15), (17.2, 0.42, 30))


def zhao_nx(L, h):
    """Elements along the length for a beam of slenderness L/h (the seed's choice)."""
    r = L / h
    return 10 if r < 15 else (15 if r < 30 else 30)


_UNITS = dict(E="MPa", nu="1", h="mm", L="mm", width="mm", Br="T", Ba_max="T",
              field_angle_deg="deg", tilt_deg="deg", load_max="1 (A Br Ba L^2/(mu0 E I))",
              rho="t/mm^3", g="mm/s^2", Br_angle_deg="deg", fingers="1", finger_length="mm",
              finger_width="mm", palm="mm")

add_case(Case(
    name="magnetic-cantilever",
    description="Zhao et al. 2019 hard-magnetic cantilever (w = 5 mm, Br = 0.143 T along the axis) in a "
                "uniform field up to Ba_max at field_angle_deg; the beam is chosen by --set L=... h=...",
    geometry="strip",
    params=dict(E=E_ZHAO, nu=NU_ZHAO, h=0.42, L=17.2, width=5.0, Br=0.143, Ba_max=0.05,
                field_angle_deg=90.0),
    units=_UNITS, mesh=(0, 2), steps=20,
    loads=(CaseLoad("magnetic", None, (1.0, 0.0, 0.0), lambda p: p["Br"]),),
    load_name="Ba", load_unit="T", load_value=lambda p, lam: lam * p["Ba_max"],
    reference=None,
    notes="nx = 0 in the default mesh means the seed's choice for the beam (zhao_nx). References: "
          "nu = 0 -> 3_magnetic_perpendicular_field (90 deg) or 3_magnetic_field_135deg (135 deg), master "
          "curves in A Br Ba L^2/(mu0 E I); nu != 0 -> 3_magnetic_zhao2019_L..mm_h..mm, whose 'tip' "
          "(beam stiffness E w h^3/12) and 'tip_plate' (D w) bracket the plate strip.",
    extra=dict(family="magnetic"),
))

add_case(Case(
    name="magnetic-antiparallel",
    description="The Zhao beam with the field antiparallel to Br: buckling at A Br Ba L^2/(mu0 E I) = "
                "pi^2/4 (tangent-eigenvalue monitor), post-buckling traced with a tilted field (tilt_deg) "
                "that is then removed; field up to load_max (dimensionless).",
    geometry="strip",
    params=dict(E=E_ZHAO, nu=0.0, h=0.42, L=17.2, width=5.0, Br=0.143, load_max=10.0,
                field_angle_deg=180.0, tilt_deg=0.5),
    units=_UNITS, mesh=(0, 1), steps=40,
    loads=(CaseLoad("magnetic", None, (1.0, 0.0, 0.0), lambda p: p["Br"]),),
    load_name="A Br Ba L^2/(mu0 E I)", load_unit="1", load_value=lambda p, lam: lam * p["load_max"],
    reference=None,
    notes="Reference 3_magnetic_antiparallel_field (elastica; critical load pi^2/4). The imperfection is a "
          "tilt of the field by tilt_deg from antiparallel toward +z (picks the branch with v > 0).",
    extra=dict(family="magnetic"),
))

add_case(Case(
    name="magnetic-plate",
    description="The seed's experiment: a 40 x 30 x 0.7 mm Mold Star 31T + NdFeB plate magnetised through "
                "the thickness, clamped along a 30 mm edge at the top (x0), hanging in the y-z plane under gravity (-z), in a "
                "vertical field (+z) Ba = 9.5 mT (in the plate's plane); sample A (default) or B (--set sample=2).",
    geometry="strip",
    params=dict(E=0.0, nu=0.49, h=0.7, L=40.0, width=30.0, Br=0.0, Ba_max=9.5e-3,
                rho=0.0, g=9810.0, sample=1.0),
    units=dict(_UNITS, sample="1 = A (E = 1.19 E0, Br = 2.5 mT), 2 = B (E = 1.45 E0, Br = 6.8 mT)",
               E="MPa (0: the sample's)", Br="T (0: the sample's)", rho="t/mm^3 (0: the sample's)"),
    mesh=(16, 12), steps=25,
    loads=(CaseLoad("magnetic", None, (0.0, 0.0, 1.0), lambda p: p["Br"]),),
    load_name="Ba", load_unit="T", load_value=lambda p, lam: field_scale(lam) * p["Ba_max"],
    reference=None,
    notes="The seed's measured data are not available: this is a prediction. The load factor first "
          "hangs the plate under gravity (lam in [0, 0.2], 5 of the 25 steps), then ramps the field (lam in "
          "[0.2, 1]). E0 = 324.054 kPa (Mold Star 31T, seed s6.2); the seed "
          "states 1.19 E0 and 1.45 E0 for 6 % and 12 % particles, its eq. E85 would give 1.177 and 1.430. "
          "Density: rule of mixtures with NdFeB 7.5 g/cm^3 and an assumed silicone 1.1 g/cm^3 "
          "(not checked against the data sheet): 1.48 (A, 6 %) and 1.87 g/cm^3 (B, 12 %); "
          "'rho' overrides. nu = 0.49: a nearly incompressible elastomer.",
    extra=dict(family="magnetic"),
))

add_case(Case(
    name="magnetic-gripper",
    description="A flat four-finger magnetic gripper (cross-shaped, palm clamped at its centre) whose "
                "fingers are magnetised radially outward and, alike, down through the thickness (programmed, "
                "non-uniform Br: opposite in-plane senses on opposite fingers); a uniform field along +z closes them.",
    geometry="strip",
    params=dict(E=1.45 * 0.324054, nu=0.45, h=0.7, finger_length=20.0, finger_width=6.0, palm=6.0,
                Br=6.8e-3, Ba_max=0.06, Br_angle_deg=45.0),
    units=_UNITS, mesh=(10, 3), steps=20,
    loads=(CaseLoad("magnetic", None, (0.0, 0.0, 1.0), lambda p: p["Br"]),),
    load_name="Ba", load_unit="T", load_value=lambda p, lam: lam * p["Ba_max"],
    reference=None,
    notes="Magnetisation of a finger: Br (cos a e_out - sin a e_z) with e_out the finger's outward axis "
          "and a = Br_angle_deg; in the field along +z the couple Br Ba cos a (e_out x e_z) turns each finger up about its "
          "root (its tip rises and moves inward: u = (-15.7, 0, +16.6) mm at 0.06 T), so the four fingers "
          "close like a hand (before, this note said a field along -z, which turns them down). mesh = (elements "
          "along a finger, across it).",
    extra=dict(family="magnetic"),
))
