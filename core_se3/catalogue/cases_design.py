"""Design cases with exact answers (data; the runner is ``catalogue.family_design``): the
hard-magnetic cantilever of ``magnetic-cantilever`` (Zhao et al. 2019, L = 17.2 mm,
h = 0.42 mm, w = 5 mm, Br = 0.143 T along the axis) with nu = 0, so that the beam elastica is
its exact answer.  Units N, mm, MPa, T."""
from __future__ import annotations

from .case import Case, add_case
from .cases_magnetic import E_ZHAO

__all__ = []

_UNITS = dict(E="MPa", h="mm", L="mm", width="mm", Br="T", theta_deg="deg", angle_deg="deg", start_deg="deg",
              q="1 (A Br Ba L^2/(mu0 E I))", max_iter="1")

add_case(Case(
    name="design-tip-angle",
    description="Design: the field magnitude Ba (perpendicular to Br) that turns the tip of the Zhao cantilever "
                "(nu = 0) by theta_deg; exact answer from the hard-magnetic elastica",
    geometry="strip",
    params=dict(theta_deg=45.0, E=E_ZHAO, h=0.42, L=17.2, width=5.0, Br=0.143, max_iter=30.0),
    units=_UNITS, mesh=(0, 1), steps=10, loads=(),
    load_name="Ba", load_unit="T", load_value=lambda p, lam: lam,
    notes="Start: the small-deflection answer theta = q/2. Exact: q(theta) of 3_magnetic_perpendicular_field "
          "(elastica.json), inverted to 1e-12; Ba = q mu0 E h^2/(12 Br L^2). nx = 0: the seed's choice (zhao_nx).",
    extra=dict(family="design"),
))

add_case(Case(
    name="design-field-direction",
    description="Design: the direction in the x-z plane of a field of fixed magnitude (dimensionless load q) that "
                "puts the cantilever's tip at the point the elastica reaches with the field at angle_deg",
    geometry="strip",
    params=dict(angle_deg=135.0, q=5.0, start_deg=100.0, E=E_ZHAO, h=0.42, L=17.2, width=5.0, Br=0.143,
                max_iter=30.0),
    units=_UNITS, mesh=(0, 1), steps=10, loads=(),
    load_name="Ba", load_unit="T", load_value=lambda p, lam: lam,
    notes="The target point: the tip of the field-angle elastica th'' + q sin(psi - th) = 0 at psi = angle_deg "
          "(catalogue.family_design.magnetic_elastica, shooting to 1e-12; at 135 deg it matches "
          "3_magnetic_field_135deg). Exact answer: angle_deg.",
    extra=dict(family="design"),
))
