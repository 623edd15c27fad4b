"""Coulomb friction catalogue cases (data only; the builders, runner and measures are in
``catalogue.family_friction``; the derivations in docs/CONTACT.md "Friction").

* ``friction-pushed-cantilever``: a cantilever strip pressed end-on against a rough wall by an
  axial force P (its root free to slide along the axis), the wall then sliding across the
  strip (along its thickness) by s: the end sticks and is carried with the wall while the
  lateral force H = P k s / (tan kL - kL) (k = sqrt(P/EI): the cantilever beam-column with an
  end load, Timoshenko & Gere, Theory of Elastic Stability, 2nd ed., 1961, sec. 1.11) is below
  mu P, then slips at H = mu P with the end held at s* = mu (tan kL - kL) / k.
* ``friction-gripper-hold``: the four-finger magnetic gripper (``magnetic-gripper-grasp``) closes
  in its field on a rough sphere, then the sphere is pulled out of the grasp (the gripper upside
  down holding it against its weight): the largest force held against the bound
  sum_i N_i (n_z,i + mu sqrt(1 - n_z,i^2)) of the contact normal forces N_i (mu sum N_i where
  the fingers touch vertical faces).
* ``friction-walker``, ``friction-walker-symmetric``: a magnetic soft inchworm (a strip of the
  scale of Hu et al., Nature 554 (2018) 81: two halves magnetised along the axis in opposite
  senses, arching in a vertical field) on a rough floor under gravity, driven by a cyclic
  field: per cycle the vertical field rises from Bmin to B0 (the strip arches, its feet slide
  together), the horizontal field turns from +Bx to -Bx, the vertical field falls back (the feet
  slide apart), the horizontal field returns.  A magnetisation component mz Br through the
  thickness makes the horizontal field shift the weight between the feet: the rear foot slips
  while the strip arches, the front one while it flattens, and the strip walks.  The
  symmetric walker (mz = 0, Bx = 0) is mirror symmetric: its feet slip alike, and it does not
  move.

Units: consistent (the pushed strip: length 1, E 1e5); N, mm, MPa, T, t/mm^3 (the gripper and
the walkers).  EI = E w h^3 / 12 (nu = 0).
"""
from __future__ import annotations

from math import pi, sqrt, tan

import numpy as np

from ..errors import LoadError
from .case import Case, CaseLoad, add_case

__all__ = ["PUSH_PARAMS", "HOLD_PARAMS", "WALKER_PARAMS", "push_formula", "walker_field", "RAMP"]

RAMP = 0.2           # friction-pushed-cantilever: the load factor at which P is reached and the wall starts


def push_formula(p):
    """The pushed cantilever's P [force], k [1/length], compliance f = (tan kL - kL)/(P k) of its
    end [length/force], slip onset s* = mu P f [length] and the wall's travel slide s*.

    Example
    -------
    >>> r = push_formula(PUSH_PARAMS)
    >>> round(r["kL"], 6), round(r["s_star"] / PUSH_PARAMS["L"], 6)
    (0.496729, 0.027379)
    """
    if not 0.0 < p["P_ratio"] < 1.0:       # tan kL changes sign at the buckling load (kL = pi/2)
        raise LoadError(f"friction-pushed-cantilever: P_ratio = {p['P_ratio']:g} must lie in (0, 1): the end "
                        "load P = P_ratio pi^2 EI/(4 L^2) must stay below the cantilever's buckling load, where "
                        "the strip would buckle before the wall moves (e.g. --set P_ratio=0.5)")
    EI = p["E"] * p["width"] * p["h"] ** 3 / 12.0
    P = p["P_ratio"] * pi ** 2 * EI / (4.0 * p["L"] ** 2)
    k = sqrt(P / EI)
    f = (tan(k * p["L"]) - k * p["L"]) / (P * k)
    s_star = p["mu"] * P * f
    return dict(EI=EI, P=P, k=k, kL=k * p["L"], f=f, s_star=s_star, travel=p["slide"] * s_star)


def push_wall(p, lam):
    """The wall's travel s(lam) [length]: 0 while P ramps up, then linear to slide s* at 1."""
    return push_formula(p)["travel"] * max(0.0, (lam - RAMP) / (1.0 - RAMP))


def walker_field(p):
    """The walkers' applied field B(lam) [T] (lab (3,)): load factor 0 -> 0.5 ramps Bx along
    +x, 0.5 -> 1 ramps Bz to Bmin; each unit after 1 is a cycle of phase f = lam - 1 - floor(.):
    Bz rises Bmin -> B0 with +Bx (f < 0.4), Bx turns to -Bx (f < 0.5), Bz falls back with -Bx
    (f < 0.9), Bx returns to +Bx.

    Example
    -------
    >>> B = walker_field(WALKER_PARAMS)
    >>> [np.round(B(lam) * 1e3, 6).tolist() for lam in (1.0, 1.4, 1.5, 1.9)]
    [[0.5, 0.0, 1.0], [0.5, 0.0, 3.0], [-0.5, 0.0, 3.0], [-0.5, 0.0, 1.0]]
    """
    B0, Bmin, b = p["B0"], p["Bmin"], p["Bx"]

    def B(lam):
        if lam <= 0.5:
            return np.array([b * lam / 0.5, 0.0, 0.0])
        if lam <= 1.0:
            return np.array([b, 0.0, Bmin * (lam - 0.5) / 0.5])
        f = (lam - 1.0) - np.floor(lam - 1.0 + 1e-12)
        f = 0.0 if f < 1e-12 or f > 1 - 1e-12 else f
        if f < 0.4:
            return np.array([b, 0.0, Bmin + (B0 - Bmin) * f / 0.4])
        if f < 0.5:
            return np.array([b * (1.0 - 2.0 * (f - 0.4) / 0.1), 0.0, B0])
        if f < 0.9:
            return np.array([-b, 0.0, B0 - (B0 - Bmin) * (f - 0.5) / 0.4])
        return np.array([-b + 2.0 * b * (f - 0.9) / 0.1, 0.0, Bmin])
    return B

# P = 0.1 of the cantilever's Euler load pi^2 EI / (4 L^2): k L = 0.497, s* = 0.0274 L
PUSH_PARAMS = dict(E=1.0e5, nu=0.0, h=0.01, L=1.0, width=0.1, P_ratio=0.1, mu=0.3, slide=2.0)
HOLD_PARAMS = dict(E=1.45 * 0.324054, nu=0.45, h=0.7, finger_length=20.0, finger_width=6.0, palm=6.0,
                   Br=6.8e-3, Ba_max=0.06, Br_angle_deg=45.0, radius=10.0, gap=0.65, mu=0.5, lift=0.2)
WALKER_PARAMS = dict(L=4.0, width=1.5, h=0.2, E=0.07, nu=0.0, rho=1.86e-9, g=9810.0, Br=0.078, mz=0.2,
                     mu=0.5, B0=3.0e-3, Bmin=1.0e-3, Bx=0.5e-3, cycles=3.0, period=1.0)
_WALKER_UNITS = dict(L="mm", width="mm", h="mm", E="MPa", nu="1", rho="t/mm^3", g="mm/s^2", Br="T",
                     mz="1 (of Br, through the thickness)", mu="1", B0="T", Bmin="T", Bx="T", cycles="1",
                     period="s (of a cycle: the quasi-static check)")

add_case(Case(
    name="friction-pushed-cantilever",
    description="A cantilever pressed end-on against a rough wall by P, the wall then sliding across it: the "
                "end sticks while H = P k s / (tan kL - kL) < mu P, then slips at mu P.",
    geometry="strip", params=PUSH_PARAMS,
    units=dict(E="force/length^2", nu="1", h="length", L="length", width="length", P_ratio="1 (of pi^2 EI/(4L^2))",
               mu="1", slide="1 (of the slip onset s*)"),
    mesh=(40, 1), steps=9,
    loads=(CaseLoad("edge_force", "x0", (1.0, 0.0, 0.0), lambda p: p["P_ratio"]),),
    load_name="s", load_unit="length", load_value=lambda p, lam: push_wall(p, lam),
    supports=(("slide", "x0"),), probe="tip",
    notes="Load factor 0 -> 0.2: P ramps up (2 steps); 0.2 -> 1: the wall slides by slide * s* in `steps` "
          "steps. The contact is at the end's mid-surface (side 0: an edge pressed end-on).",
    extra=dict(family="friction"),
))

add_case(Case(
    name="friction-gripper-hold",
    description="The magnetic gripper closes on a rough sphere, which is then pulled out of the grasp: the "
                "largest force held against the bound from the contact normal forces.",
    geometry="strip", params=HOLD_PARAMS,
    units=dict(E="MPa", nu="1", h="mm", finger_length="mm", finger_width="mm", palm="mm", Br="T", Ba_max="T",
               Br_angle_deg="deg", radius="mm", gap="mm", mu="1", lift="mm (the pull at load factor 1)"),
    mesh=(10, 3), steps=20,
    loads=(CaseLoad("magnetic", None, (0.0, 0.0, 1.0), lambda p: p["Br"]),),
    load_name="lift", load_unit="mm", load_value=lambda p, lam: p["lift"] * max(0.0, 2.0 * lam - 1.0),
    notes="Load factor 0 -> 0.5: the field ramps to Ba_max (10 steps); 0.5 -> 1: the sphere rises by `lift` "
          "in `steps` steps.",
    extra=dict(family="friction"),
))

for _name, _over, _what in (("friction-walker", {}, "walks: the rear foot slips while it arches, the front one "
                             "while it flattens"),
                            ("friction-walker-symmetric", dict(mz=0.0, Bx=0.0), "is mirror symmetric: its feet "
                             "slip alike and it stays where it is")):
    add_case(Case(
        name=_name,
        description=f"A magnetic inchworm on a rough floor under a cyclic field {_what}: net displacement per cycle.",
        geometry="strip", params=dict(WALKER_PARAMS, **_over), units=_WALKER_UNITS,
        mesh=(20, 1), steps=40,
        loads=(CaseLoad("magnetic", None, (0.0, 0.0, 1.0), lambda p: p["Br"]),),
        load_name="Bz", load_unit="T", load_value=lambda p, lam: float(walker_field(p)(lam)[2]),
        supports=(), probe="centre",
        notes="`steps` is the number of steps per cycle; load factor 0 -> 1 ramps the field to (Bx, 0, Bmin) in "
              "10 steps, then each unit of load factor is a cycle.",
        extra=dict(family="friction"),
    ))
