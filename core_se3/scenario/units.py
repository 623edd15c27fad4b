"""Unit systems of scenario files, the physical value of every load and field at a load
factor, the dimensionless load numbers, and the plausibility checks that warn before a run.

``units`` is one of :data:`UNIT_SYSTEMS`: ``"SI"`` (N, m, Pa, kg/m^3, T), ``"N-mm-MPa"`` (N, mm,
MPa, t/mm^3, T) or ``"consistent"`` (any consistent system of your own: no range checks, and
every magnet needs its ``mu0``).  A magnetic or gravity problem must name one.

Load numbers (dimensionless, ``load_numbers``): for each magnet 12 |B^r| |B^a| L^2 / (mu0 E h^2)
(the magneto-elastic number A B^r B^a L^2 / (mu0 E I) of a strip); for each load, with the
plate modulus D = E h^3 / 12: a force F along a line of width w, F L^2 / (D w) (a point force
F L / D); a moment, M L / (D w) (M / D); a pressure or body force q, q L^3 / D; gravity,
rho h |g| L^3 / D.  L, the span, is the largest distance from the loaded (or magnetised) nodes
to the nearest supported node; E and h are the means over the loaded elements.
"""
from __future__ import annotations

import warnings

import numpy as np

from ..errors import TURNS_MAX, AngleWarning, did_you_mean
from ..fem.material import E_RANGE_PA
from ..model import FIELDS, MU0
from ..model.fields import B_MAX
from .geometry import selection
from .validate import make_scale

__all__ = ["UNIT_SYSTEMS", "UNIT_DEFAULTS", "unit_defaults", "units_section", "unit_of", "physical_loads", "load_numbers",
           "plausibility", "describe_units"]

UNIT_SYSTEMS = {
    "SI": dict(length="m", force="N", stress="Pa", moment="N m", density="kg/m^3", acceleration="m/s^2",
               field="T", to_pa=1.0, to_kg_m3=1.0, g=9.81, mu0=MU0, dipole_mu0=MU0),
    "N-mm-MPa": dict(length="mm", force="N", stress="MPa", moment="N mm", density="t/mm^3",
                     acceleration="mm/s^2", field="T", to_pa=1e6, to_kg_m3=1e12, g=9810.0, mu0=MU0 * 1e6,
                     dipole_mu0=MU0 * 1e3),
    "consistent": dict(length="length", force="force", stress="force/length^2", moment="force length",
                       density="mass/length^3", acceleration="length/time^2", field="field", to_pa=None,
                       to_kg_m3=None, g=None, mu0=None, dipole_mu0=None),
}
_CHOICES = ('units = "SI" (N, m, Pa, kg/m^3, T), units = "N-mm-MPa" (N, mm, MPa, t/mm^3, T) or '
            'units = "consistent" (your own consistent units; then every magnet needs its mu0)')
RHO_RANGE = (10.0, 2.5e4)          # kg/m^3: the lightest foams .. osmium (1.2 kg/m^3 is air, or 1.2 g/cm^3)
H_OVER_L_MAX = 0.3
# thinner than h/L 1e-4 (L/h 1e4) is beyond this package's own thin benchmarks (Scordelis-Lo R/h
# 1e4, in span h/L 1e-4) and real soft-robotic and engineering shells (L/h 10 .. 1e3), and is
# where a thickness in m with lengths in mm (1000 times too thin) puts any shell of L/h >= 10
H_OVER_L_MIN = 1e-4
LINEAR_MAX = 0.1              # a linear analysis: rotations of the order of the load number
FIRST_STEP_MAX = 1e3
# TURNS_MAX (errors): a bare angle [rad] over three turns is likely degrees (360 -> 57 turns, 45 -> 7.2,
# 30 -> 4.8: silent at the ten turns before); real paths turn 1 or 2
# parameters of the built-in load kinds -> dimension
_DIMENSION = {"force": "force", "moment": "moment", "p": "stress", "q": "stress", "g": "acceleration"}


def describe_units(units):
    """One line naming the unit system (for the first line of a run).

    Example
    -------
    >>> describe_units("N-mm-MPa")
    'units N-mm-MPa: length mm, force N, stress MPa, density t/mm^3, field T, mu0 = 1.25664 (magnets)'
    """
    if units not in UNIT_SYSTEMS:
        return "units: none given (lengths, forces and moduli in any consistent units)"
    u = UNIT_SYSTEMS[units]
    mu = f", mu0 = {u['mu0']:.6g} (magnets)" if u["mu0"] else ", mu0 given per magnet"
    return (f"units {units}: length {u['length']}, force {u['force']}, stress {u['stress']}, density "
            f"{u['density']}, field {u['field']}{mu}")


def unit_of(units, dimension):
    """The unit string of a dimension ('force', 'stress', ...) in a unit system ('' if none)."""
    return UNIT_SYSTEMS.get(units, {}).get(dimension, "")


def units_section(v, doc, spec):
    """Check ``units``: a known system (did you mean), required by magnets and gravity."""
    units = spec["units"]
    if units and units not in UNIT_SYSTEMS:
        v.choice_fail("units", units, tuple(UNIT_SYSTEMS))
    needs = [w for w, on in (("magnets", bool(spec["magnets"])),
                             ("gravity", any(ld["type"] == "gravity" for ld in spec["loads"]))) if on]
    if needs and not units:
        v.fail("units", f"a problem with {' and '.join(needs)} needs its unit system (mu0, g and the "
                        f"plausibility checks depend on it): add {_CHOICES}")
    if units == "consistent":
        for i, m in enumerate(spec["magnets"]):
            if m["mu0"] is None:
                v.fail(f"magnets[{i}].mu0", 'with units = "consistent" every magnet needs mu0, the vacuum '
                                            "permeability in your units (4 pi 1e-7 in SI)")
    return units


# defaults that depend on the unit system: (section, kind, key) -> the unit system's value
UNIT_DEFAULTS = {("loads", "gravity", "g"): lambda u: [0.0, 0.0, -u["g"]],
                 ("fields", "dipole", "mu0"): lambda u: u["dipole_mu0"]}


def unit_defaults(v, doc, spec):
    """Fill the defaults that depend on the unit system (:data:`UNIT_DEFAULTS`: gravity's g, a
    dipole's mu0) where the file leaves them out: -9.81 m/s^2 in SI is -9810 mm/s^2 in
    N-mm-MPa; with ``units = "consistent"`` such a key is required.

    Example
    -------
    >>> from core_se3.scenario.validate import Validator
    >>> spec = {"units": "N-mm-MPa", "loads": [{"type": "gravity", "g": [0.0, 0.0, -9.81]}], "fields": {}}
    >>> unit_defaults(Validator("s.toml"), {"loads": [{"type": "gravity"}]}, spec)["loads"][0]["g"]
    [0.0, 0.0, -9810.0]
    """
    u = UNIT_SYSTEMS.get(spec["units"])
    if u is None:
        return spec                      # none given or unknown: units_section says so
    entries = [("loads", f"loads[{i}]", ld, raw) for i, (ld, raw) in
               enumerate(zip(spec["loads"], doc.get("loads") or []))]
    entries += [("fields", f"fields.{n}", f, (doc.get("fields") or {}).get(n, {})) for n, f in spec["fields"].items()]
    for section, key, entry, raw in entries:
        for (sec, kind, name), value in UNIT_DEFAULTS.items():
            if sec == section and entry.get("type") == kind and name not in raw:
                if spec["units"] == "consistent":
                    v.fail(f"{key}.{name}", f'with units = "consistent" {kind} needs {name!r} in your units '
                                            "(there is no default)")
                entry[name] = value(u)
    return spec


def _scale_values(spec_scale, lams):
    f = make_scale(spec_scale)
    return np.array([f(x) for x in lams], float)


def physical_loads(spec, lam):
    """name -> (value, unit) of every load, field and prescribed rotation at load factor lam:
    the magnitude of its main vector (or its number) times its scale s(lam).

    Example
    -------
    >>> spec = {"units": "N-mm-MPa", "loads": [{"type": "edge_force", "force": [0.0, 0.0, 2.0], "scale": "linear"}],
    ...         "fields": {"coil": {"type": "uniform", "B": [0.0, 0.0, 0.06], "scale": "linear"}}, "supports": []}
    >>> physical_loads(spec, 0.5)
    {'loads[0].force': (1.0, 'N'), 'fields.coil.B': (0.03, 'T')}
    """
    units = spec.get("units", "")
    out = {}
    for i, ld in enumerate(spec.get("loads", [])):
        s = float(make_scale(ld["scale"])(lam))
        for key, dim in _DIMENSION.items():
            if key in ld and ld[key] is not None and not isinstance(ld[key], bool):
                val = ld[key]
                mag = float(np.linalg.norm(val)) if isinstance(val, (list, tuple)) else float(val)
                if key == "g" and ld["type"] == "gravity" or mag:
                    out[f"loads[{i}].{key}"] = (s * mag, unit_of(units, dim))
    for name, f in spec.get("fields", {}).items():
        s = float(make_scale(f["scale"])(lam))
        key = "B" if "B" in f else ("m" if "m" in f else None)
        if key is not None:
            unit = unit_of(units, "field") if key == "B" else f"A {unit_of(units, 'length')}^2".strip()
            out[f"fields.{name}.{key}"] = (s * float(np.linalg.norm(f[key])), unit)
    for i, sp in enumerate(spec.get("supports", [])):
        s = float(make_scale(sp["scale"])(lam)) if "scale" in sp else 0.0
        if sp["type"] == "rotate":
            out[f"supports[{i}].angle"] = (s * sp["angle"], "rad")
        elif sp["type"] == "prescribed":
            if any(sp["translate"]):
                out[f"supports[{i}].translate"] = (s * float(np.linalg.norm(sp["translate"])),
                                                   unit_of(units, "length"))
            if sp["rotate"] is not None:
                out[f"supports[{i}].rotate.angle"] = (s * sp["rotate"]["angle"], "rad")
    return {k: (round(v, 15), u) for k, (v, u) in out.items()}


def _spans(mesh, problem, nodes):
    """Largest distance from ``nodes`` to the nearest supported node."""
    from scipy.spatial import cKDTree
    held = np.nonzero(problem.constraint_mask().any(1))[0]
    if len(held) == 0 or len(nodes) == 0:
        return mesh.length_scale
    d, _ = cKDTree(mesh.X[held]).query(mesh.X[np.asarray(nodes)])
    return float(d.max()) or mesh.length_scale


def _elem_props(spec, mats_index, elems):
    mats, index = mats_index
    sel = index[elems] if elems is not None else index
    E = float(np.mean([mats[i]["E"] for i in sel]))
    h = float(np.mean([mats[i]["h"] for i in sel]))
    return E, h


def _line_width(X, nodes):
    P = X[np.asarray(nodes)]
    return float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum()) if len(P) > 1 else 0.0


def load_numbers(scn, lam=None):
    """The dimensionless load number of every magnet and load (module docstring).

    Parameters
    ----------
    scn : Scenario
        A validated scenario.
    lam : float, optional
        Load factor (default: the largest |scale| over the requested load factors, i.e. full load).

    Returns
    -------
    list of dict
        name (``magnets[0]``, ``loads[1]``), kind, value, span L [length], E, h, formula.

    Example
    -------
    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
    ...     "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
    ...     "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}]})
    >>> [(n["name"], round(n["value"], 9), n["span"]) for n in load_numbers(scn)]     # F L^2 / (D w) = 12 * 100 / 1200
    [('loads[0]', 1.0, 10.0)]
    """
    from .physics import material_index
    spec, mesh, prob = scn.spec, scn.mesh, scn.problem
    if "E" not in spec["material"] or "h" not in spec["material"]:
        return []                     # a material law without E and h: no plate modulus to scale by
    mi = material_index(spec["material"], scn.regions, mesh.n_elements)
    lams = scn.load_factors() if lam is None else [lam]
    out = []
    for i, m in enumerate(spec["magnets"]):
        elems = scn.regions[m["region"]] if m.get("region") else None
        nodes = np.unique(mesh.quads[elems if elems is not None else slice(None)])
        E, h = _elem_props(spec, mi, elems)
        L = _spans(mesh, prob, nodes)
        f = spec["fields"][m["field"]]
        field = _field_of(f)
        Ba = max(float(np.linalg.norm(field.value(mesh.X[nodes], x), axis=1).max()) for x in lams)
        Br = _br_magnitude(m, mesh)
        mu0 = m["mu0"] if m["mu0"] is not None else (UNIT_SYSTEMS.get(spec["units"], {}).get("mu0") or MU0)
        out.append(dict(name=f"magnets[{i}]", kind="magnetic", value=12 * Br * Ba * L ** 2 / (mu0 * E * h ** 2),
                        span=L, E=E, h=h, formula="12 |Br| |Ba| L^2 / (mu0 E h^2)"))
    for i, ld in enumerate(spec["loads"]):
        s = float(np.abs(_scale_values(ld["scale"], lams)).max())
        if "edge" in ld or "nodes" in ld:
            nodes = selection(mesh, ld)
            elems = np.nonzero(np.isin(mesh.quads, nodes).any(1))[0]
        else:
            elems = scn.regions[ld["region"]] if ld.get("region") else None
            nodes = np.unique(mesh.quads[elems if elems is not None else slice(None)])
        E, h = _elem_props(spec, mi, elems)
        D = E * h ** 3 / 12
        L = _spans(mesh, prob, nodes)
        w = _line_width(mesh.X, nodes) if ("edge" in ld or "nodes" in ld) else 0.0
        if ld["type"] == "nodal":
            w = 0.0 if len(nodes) == 1 else w
        value, formula = None, ""
        F = float(np.linalg.norm(ld.get("force") or [0.0])) * (len(nodes) if ld["type"] == "nodal" else 1)
        M = float(np.linalg.norm(ld.get("moment") or [0.0])) * (len(nodes) if ld["type"] == "nodal" else 1)
        if F or M:
            value = (F * L ** 2 / (D * w) + M * L / (D * w)) if w > 0 else (F * L / D + M / D)
            formula = "F L^2/(D w) + M L/(D w)" if w > 0 else "F L/D + M/D"
        elif ld["type"] in ("pressure", "body_force"):
            q = abs(ld["p"]) if "p" in ld else float(np.linalg.norm(ld["q"]))
            value, formula = q * L ** 3 / D, "q L^3 / D"
        elif ld["type"] == "gravity":
            rho = ld.get("rho") if ld.get("rho") is not None else spec["material"].get("rho")
            value, formula = (rho or 0.0) * h * float(np.linalg.norm(ld["g"])) * L ** 3 / D, "rho h |g| L^3 / D"
        if value is not None:
            out.append(dict(name=f"loads[{i}]", kind=ld["type"], value=s * value, span=L, E=E, h=h,
                            formula=formula + " (D = E h^3/12)"))   # not "..., D = E h^3/12 = value"
    return out


def _br_magnitude(m, mesh):
    if "Br_max" in m:
        return float(m["Br_max"])
    if "Br" in m:
        return float(np.linalg.norm(m["Br"]))
    if "Br_frame" in m:
        return float(np.linalg.norm(m["Br_frame"]))
    return float(m.get("Br_max", 0.0))


def keyed_angles(build, *args):
    """``build(*args)`` without the AngleWarnings of the layers below (a generator's angle0, a
    support's or an obstacle's angle, a field's rotate.angle): the validation says each as a
    ScenarioWarning at its key (:func:`_angles`), once."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AngleWarning)
        return build(*args)


def _field_of(f):
    """The field of a [fields.NAME] table ``f`` at scale 1 x its scale, to evaluate B [T] (its
    rotate.angle said at its key by :func:`_angles`, not again as an AngleWarning)."""
    return keyed_angles(FIELDS[f["type"]].build, {k: x for k, x in f.items() if k not in ("type", "scale")},
                        make_scale(f["scale"]), MU0)


def _density_message(rho, rho_si, u, units):
    """The warning for a density rho [the system's unit] of rho_si kg/m^3 outside real solids'."""
    si = '' if u['to_kg_m3'] == 1 else f' = {rho_si:.3g} kg/m^3'
    gcm3 = (f"; a density in g/cm^3 is 1000 times too small: {rho_si:g} g/cm^3 is "
            f"{rho_si * 1000 / u['to_kg_m3']:g} {u['density']}" if 0.1 <= rho_si < RHO_RANGE[0] else "")
    return (f"rho = {rho:g} {u['density']}{si} is outside the densities of real solids (10 to 25 000 kg/m^3): "
            f"in {units} the density is in {u['density']} (water {1000 / u['to_kg_m3']:g}){gcm3}")


def _thin_message(h, span, u):
    """The warning for a shell of thickness h [length] thinner than H_OVER_L_MIN of its span."""
    unit = u["length"] if u is not None and u["to_pa"] is not None else "the mesh's length unit"
    return (f"h / L = {h:g} / {span:g} = {h / span:.3g} (L/h = {span / h:.3g}) < {H_OVER_L_MIN:g}: thinner than "
            f"real shells other than foils and films (L = the largest distance to a support); h is in {unit}, "
            f"as the mesh: a thickness given in m with lengths in mm is 1000 times too thin.  If it is meant: its "
            f"bending stiffness is (h/L)^2 = {(h / span) ** 2:.2g} of its membrane stiffness, and beyond L/h 1e5 "
            "double precision limits the solution's accuracy (errors.AccuracyWarning)")


def _angles(v, spec):
    """Warn about angles [rad] of more than TURNS_MAX turns (a rotating field, a rotated edge, a
    prescribed motion's or an obstacle's turn, a box's orientation): such a turn is split into
    sub-steps of at most pi/4 (``solvers.splitting``), and an angle in degrees by mistake turns 57
    times per 360; and about a generator's orientation (``angle0``, ``theta0``) of more than a
    turn (a star's angle0 = 45 meant as degrees put arm 0 at 58.3 degrees, silently)."""
    found = [(f"fields.{name}.rotate.angle", f["rotate"]["angle"]) for name, f in spec["fields"].items()
             if f.get("rotate") and f["rotate"].get("angle") is not None]
    found += [(f"supports[{i}].angle", sp["angle"]) for i, sp in enumerate(spec["supports"])
              if sp.get("angle") is not None]
    found += [(f"supports[{i}].rotate.angle", sp["rotate"]["angle"]) for i, sp in enumerate(spec["supports"])
              if isinstance(sp.get("rotate"), dict) and sp["rotate"].get("angle") is not None]
    for i, ob in enumerate(spec.get("obstacles") or ()):
        if (ob.get("motion") or {}).get("angle") is not None:
            found.append((f"obstacles[{i}].motion.angle", ob["motion"]["angle"]))
        turn = float(np.linalg.norm(ob.get("params", {}).get("rotation") or 0.0))
        if turn > 2 * np.pi:           # an orientation needs no more than half a turn: degrees?
            v.warn(f"obstacles[{i}].rotation", f"the rotation vector's angle is {turn:g} rad, more than a turn: "
                                              f"it is in radians (90 degrees is {np.pi / 2:.6g} rad)")
    for name in ("angle0", "theta0"):          # a generator's orientation (star, polygon, sectors, panels)
        a = spec["mesh"].get(name)
        if a is not None and abs(float(a)) > 2 * np.pi:
            v.warn(f"mesh.{name}", f"{name} = {a:g} rad is more than a turn: it is in radians ({a:g} degrees is "
                                   f"{np.radians(a):.6g} rad; {a:g} rad places the mesh at {np.degrees(a) % 360:.4g} "
                                   "degrees)")
    hole = spec["mesh"].get("hole_deg") if spec["mesh"].get("generator") == "hemisphere_quarter" else None
    if hole is not None and hole < 1.0:         # the one angle in degrees: radians by mistake?
        v.warn("mesh.hole_deg", f"hole_deg = {hole:g} degrees: hole_deg is in degrees ({hole:g} rad is "
                                f"{np.degrees(hole):.4g} degrees); a hole under a degree makes the elements at it "
                                "slivers (at 0.3 degrees and nt = nf: 190 times longer than wide)")
    _many_turns(v, spec.get("many_turns") or [], found)


def _many_turns(v, meant, found):
    """Warn at each angle [rad] of ``found`` ((key, angle)) beyond TURNS_MAX turns unless its key is
    listed in the top-level ``many_turns`` (``meant``), which lists only such angle keys."""
    for i, key in enumerate(meant):
        if key not in dict(found):
            v.fail(f"many_turns[{i}]", f"{key!r} is not an angle of this file that may turn (its path angles: "
                                       f"{', '.join(k for k, _ in found) or 'none'}){did_you_mean(key, dict(found))}")
    for key, angle in found:
        turns = abs(float(angle)) / (2 * np.pi)
        if turns > TURNS_MAX and key not in meant:
            cost = "" if key.startswith("obstacles") else " (the run then takes at least 8 sub-steps per turn)"
            v.warn(key, f"angle = {angle:g} rad is {turns:.3g} turns (more than {TURNS_MAX}): angles are in "
                        f"radians (360 degrees is {2 * np.pi:.6g} rad); if so many turns are meant{cost}, say so "
                        f'at the top level: many_turns = ["{key}"]')


def plausibility(v, scn):
    """Warn (``v.warn``, errors with strict) about implausible values: see docs/SCENARIOS.md."""
    spec, units = scn.spec, scn.spec["units"]
    u = UNIT_SYSTEMS.get(units)
    mats = [("material", spec["material"])] + [(f"material.regions.{k}", r)
                                               for k, r in spec["material"]["regions"].items()]
    if u is not None and u["to_pa"] is not None:
        for key, mat in mats:
            E_pa = mat["E"] * u["to_pa"] if "E" in mat else None       # a law without E: no check
            if E_pa is not None and not E_RANGE_PA[0] <= E_pa <= E_RANGE_PA[1]:
                v.warn(f"{key}.E", f"E = {mat['E']:g} {u['stress']}{'' if u['to_pa'] == 1 else f' = {E_pa:.3g} Pa'} is outside the range of real "
                                   f"solids (10 Pa for soft gels to 700 GPa for tungsten carbide): with units = "
                                   f"{units!r} E is in {u['stress']} (a silicone elastomer ~{1e6 / u['to_pa']:g}, "
                                   f"steel {2.1e11 / u['to_pa']:g}); check its unit")
            if mat.get("rho") is not None:
                r = mat["rho"] * u["to_kg_m3"]
                if mat["rho"] > 0 and not RHO_RANGE[0] <= r <= RHO_RANGE[1]:
                    v.warn(f"{key}.rho", _density_message(mat["rho"], r, u, units))
        for i, ld in enumerate(spec["loads"]):
            if ld["type"] == "gravity" and ld.get("rho") is not None:
                r = ld["rho"] * u["to_kg_m3"]
                if ld["rho"] > 0 and not RHO_RANGE[0] <= r <= RHO_RANGE[1]:      # 0: build's zero-mass warning
                    v.warn(f"loads[{i}].rho", _density_message(ld["rho"], r, u, units))
            if ld["type"] == "gravity":
                gmag = float(np.linalg.norm(ld["g"]))
                if gmag and not 0.01 <= gmag / u["g"] <= 100:
                    v.warn(f"loads[{i}].g", f"|g| = {gmag:g} {u['acceleration']} is {gmag / u['g']:.3g} times "
                                            f"Earth's gravity ({u['g']:g} {u['acceleration']} in {units}); check its unit")
        for i, m in enumerate(spec["magnets"]):
            if m["mu0"] is not None and abs(m["mu0"] / u["mu0"] - 1) > 1e-6:
                v.warn(f"magnets[{i}].mu0", f"mu0 = {m['mu0']:g} differs from mu0 in {units} ({u['mu0']:.6g}, "
                                            f"4 pi 1e-7 T m/A for stresses in {u['stress']}): leave it out")
        for name, f in spec["fields"].items():
            if f["type"] == "dipole" and abs(f["mu0"] / u["dipole_mu0"] - 1) > 1e-6:
                v.warn(f"fields.{name}.mu0", f"mu0 = {f['mu0']:g} differs from mu0 of a dipole in {units} "
                                             f"({u['dipole_mu0']:.6g}: m in A {u['length']}^2, lengths in "
                                             f"{u['length']}): leave it out")
    if u is not None and u["mu0"] is not None:
        for i, m in enumerate(spec["magnets"]):
            br = _br_magnitude(m, scn.mesh)
            if br > B_MAX:
                v.warn(f"magnets[{i}]", f"|Br| = {br:g} T exceeds {B_MAX:g} T (the strongest permanent magnets, "
                                        "NdFeB, reach about 1.4 T): Br is in tesla; did you give mT?")
        for name, f in spec["fields"].items():
            field = _field_of(f)
            b = max(float(np.linalg.norm(field.value(scn.mesh.X, x), axis=1).max()) for x in scn.load_factors())
            if b > B_MAX and f["type"] != "dipole" or b > 1e3 * B_MAX:
                v.warn(f"fields.{name}", f"the applied field reaches |B| = {b:g} T on the shell, above "
                                         f"{B_MAX:g} T (lab electromagnets): B is in tesla; did you give mT?")
    _angles(v, spec)
    _idle(v, scn)
    span = _spans(scn.mesh, scn.problem, np.arange(scn.mesh.n_nodes))
    for key, mat in mats:
        if mat.get("h", 0.0) / span > H_OVER_L_MAX:
            v.warn(f"{key}.h", f"h / L = {mat['h']:g} / {span:g} = {mat['h'] / span:.3g} > {H_OVER_L_MAX:g}: the "
                               "shell is thick for its span (L = the largest distance to a support); a shell "
                               "model needs h << L: check h and the mesh's length unit")
        elif 0.0 < mat.get("h", 0.0) / span < H_OVER_L_MIN:
            v.warn(f"{key}.h", _thin_message(mat["h"], span, u))
    lam1 = scn.load_factors()[0] if scn.solver["control"] != "arclength" else scn.solver["dlam0"]
    for n in load_numbers(scn, lam=lam1):
        if scn.solver["control"] == "linear" and n["value"] > LINEAR_MAX:
            v.warn(n["name"], f"the load number {n['formula']} = {n['value']:.3g} at lam_end = {lam1:g} (span L = "
                              f"{n['span']:.4g}) is above {LINEAR_MAX:g}: rotations of that order, beyond the "
                              'small rotations of a linear analysis; solve with control = "load"')
        elif n["value"] > FIRST_STEP_MAX:
            v.warn(n["name"], f"the load number {n['formula']} = {n['value']:.3g} in the first step (load factor "
                              f"{lam1:g}; span L = {n['span']:.4g}) is above {FIRST_STEP_MAX:g}: the first step "
                              "bends the shell through many turns; check the units of the load (and mu0)"
                              + _file_length(spec, u) + ", or take more or smaller steps")
    if scn.solver["control"] == "linear":
        _linear_motions(v, spec, scn.solver["lam_end"], scn.mesh.length_scale)
    return None


def _idle(v, scn):
    """Warn about a load, field or prescribed motion whose ``scale`` is 0 at every load factor of
    the run (a table ramping beyond lam_end: it acts nowhere; under load control its table's
    points inside the run count, where a try lands: a peak between two steps acts), and a field's ``rotate`` that has
    not begun at any step (its start at or past lam_end: it never turns).  Load control and
    linear analysis (an arc-length path's load factors are not known beforehand)."""
    if scn.solver["control"] == "arclength":
        return
    spec, lams = scn.spec, np.array(scn.load_factors(), float)
    scaled = [(f"loads[{i}].scale", ld.get("scale")) for i, ld in enumerate(spec["loads"])]
    scaled += [(f"supports[{i}].scale", sp.get("scale")) for i, sp in enumerate(spec["supports"])]
    scaled += [(f"fields.{name}.scale", f.get("scale")) for name, f in spec["fields"].items()]
    where = f"at every load factor of the run ({lams.min():g} .. {lams.max():g})"
    for key, sc in scaled:
        if sc is None:
            continue
        f = make_scale(sc)
        # load control also applies a table's points inside the run (a peak between two steps)
        seen = lams if scn.solver["control"] == "linear" else \
            np.r_[lams, [t for t in getattr(f, "knots", ()) if min(0.0, lams.min()) < t < lams.max()]]
        if all(f(lam) == 0 for lam in seen):
            v.warn(key, f"the scale is 0 {where}: it acts nowhere; move its table's ramp into the run "
                        "or raise lam_end")
    for name, f in spec["fields"].items():
        r = f.get("rotate")
        if r and r.get("angle"):
            turn = np.clip((lams - r.get("start", 0.0)) / (r.get("end", 1.0) - r.get("start", 0.0)), 0.0, 1.0)
            if turn.max() == 0:
                v.warn(f"fields.{name}.rotate", f"the field's rotation has not begun {where} (start = "
                                                f"{r.get('start', 0.0):g}): it never turns; move start into the run")


def _file_length(spec, u):
    """For a mesh read from a file: a reminder that its coordinates are lengths in the scenario's
    unit (a Gmsh file in mm read with units = "SI" is 1000 times too large: a load number
    L^2 h^-2 goes up 10^6 times, and this warning was the only sign, blaming the load)."""
    if "file" not in spec["mesh"]:
        return ""
    unit = u["length"] if u is not None else "the scenario's length unit"
    return (f" and the mesh file's length unit (its coordinates are read as {unit}: a file in mm read with "
            f"units = \"SI\" is 1000 times too large)")


def _linear_motions(v, spec, lam, span):
    """Warn of a prescribed motion (rotate, prescribed) beyond a linear analysis at ``lam``: a
    rotation above LINEAR_MAX rad, or a translation above LINEAR_MAX of the mesh's extent (the
    linear answer holds the support's targets exactly and the shell between them to first order:
    a supported end turned by 3 rad is not a linear problem)."""
    for i, sp in enumerate(spec["supports"]):
        if sp["type"] not in ("rotate", "prescribed"):
            continue
        s = abs(float(make_scale(sp["scale"])(lam)))
        rot = sp if sp["type"] == "rotate" else (sp.get("rotate") or {})
        angle = abs(float(rot.get("angle", 0.0))) * s
        move = float(np.linalg.norm(sp.get("translate") or [0.0, 0.0, 0.0])) * s
        if angle > LINEAR_MAX or move > LINEAR_MAX * span:
            what = (f"a rotation of {angle:.3g} rad" if angle > LINEAR_MAX else
                    f"a translation of {move:.3g} ({move / span:.3g} of the mesh's extent {span:.4g})")
            v.warn(f"supports[{i}]", f"prescribes {what} at lam_end = {lam:g}, above {LINEAR_MAX:g}: beyond the "
                                     'small rotations of a linear analysis; solve with control = "load"')

