"""The catalogue's strip, arch and semi-cylinder cases (data only; the generic builder and runner
are in ``catalogue.generic``).  Coordinates and units as in ``catalogue.case``."""
from __future__ import annotations

from math import pi

from .case import Case, CaseLoad, Reference, Variant, add_case, beam_EI
from .references import elastica_entry

__all__ = []


_DIM = dict(E="force/length^2", nu="1", h="length", L="length", width="length",
            load_max="force", R="length", k="1")


def rod_nu0(p, data):
    """"" at nu = 0, else why a rod elastica does not hold: it is the strip's exact reduction
    only for nu = 0 (EI = E w h^3 / 12); at nu != 0 the strip's bending stiffness lies between
    that and the plate's E w h^3 / (12 (1 - nu^2)), and an error against the curve would measure
    that (cantilever-shear: 0.52 % at nu = 0.3 against 0.064 % at nu = 0, 16x1).

    Example
    -------
    >>> rod_nu0({"nu": 0.3}, {})
    'the reference is the rod elastica with EI = E w h^3/12, exact for the strip at nu = 0; the run has nu = 0.3'
    """
    nu = p.get("nu", 0.0)
    if nu == 0.0:
        return ""
    return (f"the reference is the rod elastica with EI = E w h^3/12, exact for the strip at nu = 0; "
            f"the run has nu = {nu:g}")


def _master(entry, load_name_fn, block="tip"):
    """Reference on a dimensionless master curve (L = 1, EI = 1), for nu = 0."""
    return Reference(entry=entry, load_to_ref=load_name_fn, length=lambda p: p["L"], block=block,
                     applies=rod_nu0)


_UNITS = ("MPa", "Pa", "mm", "m", "m2", "m4", "N", "Nmm2")      # unit suffixes of the entries' names
_NAMES = {"w": "width", "width": "width"}


def _param_name(key):
    """The case parameter an entry's key names (its unit suffix dropped: 'E_MPa' -> 'E', 'w_mm' -> 'width')."""
    base, _, unit = key.rpartition("_")
    name = base if unit in _UNITS and base else key
    return _NAMES.get(name, name)


def same_params(p, data):
    """"" when every parameter the reference entry states (``data``: E, nu, L, h, w, R, and the
    section's A, I, EI, with or without a unit suffix such as ``E_MPa``) has the case's value
    (to 1e-4 relative: the arch's section is given to five digits), else the first that differs:
    a table computed in physical units holds only there.

    Example
    -------
    >>> same_params({"E": 2.0, "h": 0.1}, {"E_MPa": 2.0, "h_mm": 0.2})
    'the reference entry is for h = 0.2, the run has h = 0.1'
    """
    q = dict(p)
    if "h" in p and "width" in p:
        q.setdefault("A", p["h"] * p["width"])
        q.setdefault("I", p["width"] * p["h"] ** 3 / 12)
        if "E" in p:
            q.setdefault("EI", p["E"] * q["I"])
    for key, v in data.items():
        name = _param_name(key)
        if name in q and isinstance(v, (int, float)) and not isinstance(v, bool):
            if abs(q[name] - v) > 1e-4 * max(abs(q[name]), abs(v)):
                return f"the reference entry is for {name} = {v:g}, the run has {name} = {q[name]:g}"
    return ""


def _same_rod(p, data):
    """same_params, and nu = 0 (rod_nu0) for a rod entry that states no nu: the arch entries'
    EA = E A, kGA = G A hold for the shell with nu = 0 only (arch-follower direction=1 at
    nu = 0.3: 0.46 % against 0.11 % at nu = 0, 40x1)."""
    return same_params(p, data) or ("" if "nu" in data else rod_nu0(p, data))


_LENGTHS = ("L", "R", "h", "width", "r_in", "r_out")     # the case parameters of dimension length


def similarity(p, data):
    """(a, s): the length and stress scales of the run ``p`` against a reference entry's
    ``data`` (its L, else R, else the annulus' r_out; its E), 1 where the entry states none.  A run in other units (or
    a scaled copy: L, h, width, R times a, E times s) is the same problem; the table holds for
    it with lengths times a and forces times s a^2 (:func:`_physical`).

    Example
    -------
    >>> similarity({"L": 1.0, "E": 2.0e11, "h": 0.01}, {"L_mm": 1000.0, "E_MPa": 2.0e5, "h_mm": 10.0})
    (0.001, 1000000.0)
    """
    named = {_param_name(k): v for k, v in data.items()}
    key = next((k for k in ("L", "R", "r_out") if k in p and isinstance(named.get(k), (int, float)) and named[k]), None)
    a = p[key] / named[key] if key else 1.0
    s = p["E"] / named["E"] if "E" in p and isinstance(named.get("E"), (int, float)) and named["E"] else 1.0
    return a, s


def _in_reference_units(p, data):
    """The run's parameters carried to the entry's units by :func:`similarity`."""
    a, s = similarity(p, data)
    return {k: (v / a if k in _LENGTHS else v / s if k == "E" else v) for k, v in p.items()}


def similar_params(p, data):
    """:func:`same_params` of the run carried to the entry's units (:func:`similarity`): "" for
    the entry's problem in any units, else why not -- the first parameter that differs as the
    run states it, and, for a run in other units, the one that differs in the entry's units.

    Example
    -------
    >>> similar_params({"R": 10000.0, "h": 40.0, "E": 68.25}, {"R": 10.0, "h": 0.04, "E": 6.825e7})
    ''
    >>> similar_params({"R": 12.0, "h": 0.04}, {"R": 10.0, "h": 0.04})    # doctest: +NORMALIZE_WHITESPACE
    'the reference entry is for R = 10, the run has R = 12; nor is it that problem in other units
     (lengths x 1.2, E x 1: in its units the reference entry is for h = 0.04, the run has h = 0.0333333)'
    """
    why = same_params(_in_reference_units(p, data), data)
    if not why:
        return ""
    a, s = similarity(p, data)
    raw = same_params(p, data)
    if (a, s) == (1.0, 1.0) or not raw:
        return raw or why
    return f"{raw}; nor is it that problem in other units (lengths x {a:g}, E x {s:g}: in its units {why})"


def _similar_rod(p, data):
    """:func:`_same_rod` of the run carried to the entry's units: a run in other units (mm for
    m, MPa for Pa, ...) or scaled as a whole is compared, not refused (before: 'not compared:
    the reference entry is for E = 200000, the run has E = 2e+11' for the steel strip in SI)."""
    return similar_params(p, data) or ("" if "nu" in data else rod_nu0(p, data))


def _physical(entry, block="tip"):
    """A table in physical units (the entry's), carried to a similar run (:func:`similarity`):
    loads / (s a^2), displacements times a; exactly the table at the entry's own parameters."""
    def scales(p):
        return similarity(p, elastica_entry(entry)["params"])

    def load_to_ref(p, P):
        a, s = scales(p)
        return P / (s * a * a)
    return Reference(entry=entry, load_to_ref=load_to_ref, length=lambda p: scales(p)[0], block=block,
                     applies=_similar_rod)


def _rollup_M(p):
    return p["k"] * 2.0 * pi * beam_EI(p) / p["L"]


def _circle(entry, EI, key="L"):
    """The exact circle of a table in physical units under an end moment, carried to any
    parameters by similarity: the state depends on M a / EI only and lengths scale with a, the
    length ``key`` (the straight strip's L; the arch's radius R: curvature 1/R + M/EI)."""
    def data():
        return elastica_entry(entry)["params"]
    return Reference(entry=entry, block="tip",
                     load_to_ref=lambda p, M: M * (p[key] / EI(p)) * (data()["EI"] / data()[key]),
                     length=lambda p: p[key] / data()[key],
                     applies=rod_nu0)


add_case(Case(
    name="cantilever-shear",
    description="Sze et al. 2004 s3.1 cantilever strip under a dead transverse end shear P (to 4).",
    geometry="strip",
    params=dict(E=1.2e6, nu=0.0, h=0.1, L=10.0, width=1.0, load_max=4.0),
    units=_DIM, mesh=(16, 1), steps=10,
    loads=(CaseLoad("edge_force", "x1", (0.0, 0.0, 1.0), lambda p: p["load_max"]),),
    load_name="P", load_unit="force", load_value=lambda p, lam: lam * p["load_max"],
    reference=_master("1_cantilever_tip_force_kirchhoff", lambda p, P: P * p["L"] ** 2 / beam_EI(p)),
    notes="Kirchhoff elastica master curve; Sze's Abaqus S4R table in literature.json agrees.",
))

add_case(Case(
    name="cantilever-shear-steel",
    description="The seed's steel plate strip (mm, N, MPa) under a dead end shear to PL^2/EI = 10.",
    geometry="strip",
    params=dict(E=2.0e5, nu=0.0, h=10.0, L=1000.0, width=200.0, load_max=10.0 * 2.0e5 * 200.0 * 1e3 / 12 / 1e6),
    units=dict(_DIM, E="MPa", h="mm", L="mm", width="mm", load_max="N"), mesh=(20, 1), steps=10,
    loads=(CaseLoad("edge_force", "x1", (0.0, 0.0, 1.0), lambda p: p["load_max"]),),
    load_name="P", load_unit="N", load_value=lambda p, lam: lam * p["load_max"],
    reference=_physical("1_cantilever_tip_force_seed_plate_nu0"),
))

add_case(Case(
    name="rollup",
    description="Strip rolled up by an end moment about the width axis, M = k 2 pi EI / L (k to 3).",
    geometry="strip",
    params=dict(E=1.2e7, nu=0.0, h=0.1, L=10.0, width=1.0, k=3.0),
    units=_DIM, mesh=(10, 1), steps=12,
    loads=(CaseLoad("edge_moment", "x1", (0.0, -1.0, 0.0), _rollup_M),),
    load_name="M", load_unit="force*length", load_value=lambda p, lam: lam * _rollup_M(p),
    reference=_circle("2_pure_bending_rollup_out_of_plane", beam_EI),
    notes="Exact: circle of radius EI/M.",
))

add_case(Case(
    name="inplane-rollup",
    description="In-plane (drilling) bending of a strip by an end moment about the normal (k to 2).",
    geometry="strip",
    params=dict(E=1200.0, nu=0.0, h=1.0, L=10.0, width=1.0, k=2.0, drilling=1.0),
    units=dict(_DIM, drilling="1 (factor on the seed's drilling modulus)"), mesh=(40, 4), steps=40,
    loads=(CaseLoad("edge_moment", "x1", (0.0, 0.0, 1.0),
                lambda p: p["k"] * 2 * pi * p["E"] * p["h"] * p["width"] ** 3 / 12 / p["L"]),),
    load_name="M", load_unit="force*length",
    load_value=lambda p, lam: lam * p["k"] * 2 * pi * p["E"] * p["h"] * p["width"] ** 3 / 12 / p["L"],
    reference=Reference("2_pure_bending_rollup_inplane_drilling", lambda p, M: M, lambda p: 1.0,
                        note="in-plane: v -> uy, theta about +z; exact only for small k", applies=same_params),
    notes="The reference circle has the membrane stiffness E h w^3/12 only. The seed's "
          "drilling-curvature modulus D(1-nu) adds D(1-nu) w, which equals it for this h = w "
          "strip: with drilling=1 (the seed) the strip is twice as stiff in-plane. "
          "--set drilling=0.01 matches the circle to 0.48 % at k = 0.25 (40x4); drilling=0 leaves "
          "a drilling zero-energy mode. With drilling=1 the path converges to k = 2 (4 pi). "
          "Beyond small k the strip's in-plane response is finite bending (catalogue."
          "finite_bending): it softens, and its couple peaks at 0.0859 E h w^2 (kappa w = 1.84), "
          "below this case's 0.1047 E h w^2 at k = 2: with drilling <= 0.0125 (the circle within "
          "1 %) load control meets that limit point (about lam = 0.82-0.83), or earlier where "
          "the end couple, brought in on the drilling rotations, crushes the last element.",
    extra=dict(plane="xy"),
))

add_case(Case(
    name="torsion",
    description="Strip twisted by a rigid rotation of its end edge about the strip axis (to 3 pi), "
                "axial displacement of the end free.",
    geometry="strip",
    params=dict(E=1.2e7, nu=0.3, h=0.1, L=1.0, width=0.25, angle=3 * pi),
    units=dict(_DIM, angle="rad"), mesh=(20, 6), steps=24,
    loads=(CaseLoad("edge_rotation", "x1", (1.0, 0.0, 0.0), lambda p: p["angle"],
                axis=(1.0, 0.0, 0.0), point=(None, 0.0, 0.0), free=(0,)),),
    load_name="angle", load_unit="rad", load_value=lambda p, lam: lam * p["angle"],
    reference=None,
    notes="Small-twist torque -> J = T L/(G angle) against 5_strip_torsion_seed_strip. The straight "
          "twisted strip bifurcates at 0.722-0.723 of the twist (1.08 turns: the smallest eigenvalue of the "
          "tangent passes through zero, the strip would buckle sideways into a helix); the case follows the "
          "straight, beyond it unstable, path to 3 pi with limit_check off, and its document records the "
          "bifurcation (critical_points).",
    extra=dict(solve=dict(limit_check=False)),
))

add_case(Case(
    name="torsion-rollup",
    description="Strip under follower end moments about the strip axis and the width axis together, "
                "each ramped to the value that alone gives one full turn.",
    geometry="strip",
    params=dict(E=1.2e7, nu=0.3, h=0.1, L=10.0, width=1.0),
    units=_DIM, mesh=(50, 20), steps=40,
    loads=(
        CaseLoad("edge_moment", "x1", (0.0, -1.0, 0.0), lambda p: 2 * pi * beam_EI(p) / p["L"] / (1 - p["nu"] ** 2), follower=True),
        CaseLoad("edge_moment", "x1", (1.0, 0.0, 0.0),
             lambda p: 2 * pi * p["E"] / (2 * (1 + p["nu"])) * p["width"] * p["h"] ** 3 / 3 / p["L"], follower=True),
    ),
    load_name="lambda", load_unit="1", load_value=lambda p, lam: lam,
))

add_case(Case(
    name="arch-follower",
    description="Half-circle arch (R = 0.5 m) under a tip follower force along the current tip "
                "tangent (direction=tangential) or toward the centre (direction=inward), P to 3000 N.",
    geometry="arch",
    params=dict(E=7.2e10, nu=0.0, h=2.4495e-2, R=0.5, width=4.0825e-3, load_max=3000.0, direction=0.0),
    units=dict(_DIM, E="Pa", h="m", R="m", width="m", load_max="N", direction="0=tangential,1=inward"),
    mesh=(40, 1), steps=30,
    loads=(CaseLoad("edge_force", "x1", (1.0, 0.0, 0.0), lambda p: p["load_max"], follower=True),),
    load_name="P", load_unit="N", load_value=lambda p, lam: lam * p["load_max"],
    reference=_physical("4_arch_halfcircle_follower_tangential_plus_shell_ks1"),
    notes="direction=1 switches the force to +d3 (toward the centre) and the reference to "
          "4_arch_halfcircle_follower_normal_inward_shell_ks1.",
    variants=(Variant("direction", 0, dict(direction=(0.0, 0.0, 1.0)),
                      "4_arch_halfcircle_follower_normal_inward_shell_ks1"),),
))

add_case(Case(
    name="curved-rollup",
    description="Half-cylinder of radius 10/(2 pi) (arc length 5) under an end moment, "
                "M = k EI / R (= k 2 pi EI / 10 at that radius), k from -1 to 2.",
    geometry="arch",
    params=dict(E=1.2e7, nu=0.0, h=0.1, R=10.0 / (2 * pi), width=1.0, k=2.0),
    units=_DIM, mesh=(10, 1), steps=8,
    # k EI / R, not k 2 pi EI / 10: the 10 was a length in the default units (the same arch in
    # metres, every length x 1e-3, got 1e-3 of its moment in units of EI / R)
    loads=(CaseLoad("edge_moment", "x1", (0.0, -1.0, 0.0), lambda p: p["k"] * beam_EI(p) / p["R"]),),
    load_name="M", load_unit="force*length", load_value=lambda p, lam: lam * p["k"] * beam_EI(p) / p["R"],
    reference=_circle("4_arch_halfcircle_end_moment_R10over2pi", beam_EI, "R"),
    notes="Run with --set k=-1 for the opening branch.",
))

add_case(Case(
    name="pressure-strip",
    description="The rollup strip clamped on x0 under a uniform pressure to qL^3/EI = 20 (q = p w); "
                "dead (along +z) or follower (normal to the deformed surface, per current area).",
    geometry="strip",
    params=dict(E=1.2e7, nu=0.0, h=0.1, L=10.0, width=1.0, load_max=20.0, follower=0.0),
    units=dict(_DIM, load_max="1 (q L^3/EI)", follower="0=dead,1=follower"), mesh=(16, 1), steps=20,
    loads=(CaseLoad("pressure", None, (0.0, 0.0, 1.0),
                lambda p: p["load_max"] * beam_EI(p) / p["L"] ** 3 / p["width"]),),
    load_name="q L^3/EI", load_unit="1", load_value=lambda p, lam: lam * p["load_max"],
    reference=_master("5_plate_cylindrical_bending_pressure_dead", lambda p, q: q),
    notes="follower=1 switches to the follower pressure and 5_plate_cylindrical_bending_pressure_follower.",
    variants=(Variant("follower", 0, dict(follower=True), "5_plate_cylindrical_bending_pressure_follower"),),
))


add_case(Case(
    name="sze-semicylinder",
    description="Sze et al. 2004 s3.7: clamped semi-cylinder (isotropic) pinched by a point load at "
                "the crown of its free curved edge, P to 2000.",
    geometry="semicylinder",
    params=dict(E=2.0685e7, nu=0.3, h=0.03, R=1.016, L=3.048, load_max=2000.0, k_pin=1e3, k_rot=1e5),
    units=dict(_DIM, k_pin="1 (u_z penalty stiffness / (E h))", k_rot="1 (rotation-vector penalty stiffness / (E h^3))"), mesh=(40, 40), steps=40,
    loads=(CaseLoad("point_force", "y1", (0.0, 0.0, -1.0), lambda p: p["load_max"]),),
    load_name="P", load_unit="force", load_value=lambda p, lam: lam * p["load_max"],
    supports=(("clamp", "y0"),
              # longitudinal edges (theta = -+pi/2): lab u_z = 0 and the rotation about the axis
              # (lab y) fixed, as fenicsx_ref reads them; core_se3's builder (family_sze.
              # _semicylinder) holds the lab components exactly, by penalties (path independent)
              ("fix", "x0", ("uz", "rot_y")), ("fix", "x1", ("uz", "rot_y"))),
    reference=None,
    probe="crown",
    notes="Reference: literature.json sze3.7_clamped_semicylinder_point_load, column "
          "minus_W_A_x100_isotropic (table = 100 x displacement; -W_A = -u_z at the crown of y1). "
          "Geometry: phi0 = (R sin t, s, R cos t), t in [-pi/2, pi/2] along x, s in [0, L] along y; "
          "the load acts at the midpoint of edge y1. Measure: largest distance from each computed "
          "point to the tabulated curve in the plane (P/P_max, u/u_max).",
    extra=dict(family="sze", shape="semicylinder",
               literature="sze3.7_clamped_semicylinder_point_load", column="minus_W_A_x100_isotropic",
               displacement_scale=0.01, probe_edge="y1", probe_component=2, probe_sign=-1.0),
))
