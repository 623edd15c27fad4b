"""Contact catalogue cases (data only; the builder, runner and measures are in
``catalogue.family_contact``; the derivations in docs/CONTACT.md).

* ``contact-lift``: a heavy strip (dead pressure q per unit area, its weight) lying flat on a rigid
  plane, the end x0 lifted by lam delta (its translations prescribed, its rotation free).  Small
  deflection: lifted length l = (24 EI delta / q_l)^(1/4), lift force q_l l / 2 and a point
  reaction q_l l / 2 at the detachment line (q_l = q w); large deflection: the elastica with a
  free detachment point (``data/contact_lift_elastica.json``).
* ``contact-propped``: a cantilever under uniform pressure q with a rigid plane a gap g below its
  tip: no contact while q_l L^4 / (8 EI) < g, then the tip reaction R = 3 EI (q_l L^4/(8 EI) - g) / L^3.
* ``magnetic-gripper-grasp``: the four-finger gripper of ``magnetic-gripper`` closing on a rigid
  sphere (radius ``radius``) held ``gap`` above its palm's top face.

Units: consistent (the strips: length 1, E 1.2e6; the gripper: N, mm, MPa, T).  EI = E w h^3 / 12
(nu = 0: the plate strip is the beam).
"""
from __future__ import annotations

from .case import Case, CaseLoad, add_case

__all__ = ["LIFT_PARAMS", "PROPPED_PARAMS"]

_STRIP = dict(E="force/length^2", nu="1", h="length", L="length", width="length",
              q="force/length^2 (downward, per unit area)", delta="length", g="length")

# q_l L^3 / EI = 20 (the elastica table's Q): EI = 1.2e6 * 0.05 * 1e-6 / 12 = 5e-3, q_l = 0.1, q = 2
LIFT_PARAMS = dict(E=1.2e6, nu=0.0, h=0.01, L=1.0, width=0.05, q=2.0, delta=0.01)
# q_l L^4 / (8 EI) = 2 g at lam = 1: contact from lam = 0.5 on
PROPPED_PARAMS = dict(E=1.2e6, nu=0.0, h=0.01, L=1.0, width=0.05, q=0.016, g=0.01)

add_case(Case(
    name="contact-lift",
    description="A heavy strip (dead pressure q) on a rigid plane, the end x0 lifted by delta, its rotation "
                "free: lifted length and lift force vs (24 EI delta / q_l)^(1/4) and the elastica.",
    geometry="strip", params=LIFT_PARAMS, units=_STRIP, mesh=(80, 1), steps=2,
    loads=(CaseLoad("pressure", None, (0.0, 0.0, -1.0), lambda p: p["q"]),
           CaseLoad("edge_lift", "x0", (0.0, 0.0, 1.0), lambda p: p["delta"])),
    load_name="delta", load_unit="length", load_value=lambda p, lam: lam * p["delta"],
    supports=(("lift", "x0"),), probe="lifted_end",
    notes="The weight is constant (scale 1) and the lift grows with the load factor. Measures per step: "
          "lifted_length (the detachment located between nodes from the gap field), lift_force (the "
          "reaction at x0), against the small-deflection formula and contact_lift_elastica.json.",
    extra=dict(family="contact"),
))

add_case(Case(
    name="contact-propped",
    description="A cantilever under uniform pressure q with a rigid plane a gap g below its tip: tip "
                "reaction R = 3 EI (q_l L^4 / (8 EI) - g) / L^3 once it touches.",
    geometry="strip", params=PROPPED_PARAMS, units=_STRIP, mesh=(40, 1), steps=10,
    loads=(CaseLoad("pressure", None, (0.0, 0.0, -1.0), lambda p: p["q"]),),
    load_name="q", load_unit="force/length^2", load_value=lambda p, lam: lam * p["q"],
    notes="Tip-only contact holds for q_l L^4 / (72 EI) <= g < q_l L^4 / (8 EI) (docs/CONTACT.md).",
    extra=dict(family="contact"),
))

add_case(Case(
    name="magnetic-gripper-grasp",
    description="The four-finger magnetic gripper (magnetic-gripper) closing in its field on a rigid sphere "
                "of radius `radius` held `gap` above the palm: the fingers stop on the sphere.",
    geometry="strip",
    params=dict(E=1.45 * 0.324054, nu=0.45, h=0.7, finger_length=20.0, finger_width=6.0, palm=6.0,
                Br=6.8e-3, Ba_max=0.06, Br_angle_deg=45.0, radius=10.0, gap=0.65),
    units=dict(E="MPa", nu="1", h="mm", finger_length="mm", finger_width="mm", palm="mm", Br="T", Ba_max="T",
               Br_angle_deg="deg", radius="mm", gap="mm (sphere surface above the palm's top face)"),
    mesh=(10, 3), steps=20,
    loads=(CaseLoad("magnetic", None, (0.0, 0.0, 1.0), lambda p: p["Br"]),),
    load_name="Ba", load_unit="T", load_value=lambda p, lam: lam * p["Ba_max"],
    notes="No reference: the measures are the total contact force on the sphere and the global balance.",
    extra=dict(family="contact"),
))
