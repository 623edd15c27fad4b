"""Case parameters, load variants and the project's error measures for fenicsx_ref (NumPy only,
no DOLFINx).

The case data, the variant switches (``core_se3.catalogue.resolve``) and the error measures
(``core_se3.catalogue.measures``) are the catalogue's own, so that the two models are measured
the same way; this module only maps them onto fenicsx_ref's parameter domain and step dicts.
Planar references (u, v, theta) map onto the shell as (ux, uz, rotation about -y), uy = 0.
"""
from __future__ import annotations

from dataclasses import asdict
from math import pi

import numpy as np

from core_se3.catalogue import case_params, resolve
from core_se3.catalogue.measures import curve_deviation, curve_columns, errors_at_table_loads
from core_se3.catalogue.references import elastica_entry

__all__ = ["case_params", "apply_variant", "case_length", "case_domain", "reference_entry",
           "reference_load_factors", "reference_error", "literature_error", "check_inputs",
           "reference_mismatch", "check_springs"]

reference_entry = elastica_entry


def case_length(case, p):
    """Extent of the parameter domain along its first coordinate (arc length for curved cases)."""
    if case.geometry == "strip":
        return p["L"]
    if case.geometry in ("arch", "semicylinder"):
        return pi * p["R"]  # half circle
    raise NotImplementedError(f"fenicsx_ref: geometry {case.geometry!r}")


def case_domain(case, p):
    """(length, width, box) of the parameter domain; box = ((s0, y0), (s1, y1)).

    strip / arch: s in [0, L] (arc length), y in [-w/2, w/2].  semicylinder: s = R t with
    t in [-pi/2, pi/2] (arc length, so the reference metric is the identity), y in [0, L]."""
    if case.geometry in ("strip", "arch"):
        L, w = case_length(case, p), p["width"]
        return L, w, ((0.0, -w / 2), (L, w / 2))
    if case.geometry == "semicylinder":
        S = pi * p["R"]
        return S, p["L"], ((-S / 2, 0.0), (S / 2, p["L"]))
    raise NotImplementedError(f"fenicsx_ref: geometry {case.geometry!r}")


_GEOMETRY_KEYS = ("L", "width", "R")


def check_inputs(case, p, mesh, steps=None, shear_factor=1.0, load_factors=None, cell="quadrilateral"):
    """Reject what the shell cannot solve before any DOLFINx work, naming the input.

    Parameters
    ----------
    case : Case
        The catalogue case; ``p`` its parameters (:func:`case_params`).
    mesh : (int, int)
        Elements along the two parameter directions, each >= 1.
    steps : int, optional
        Uniform load steps, >= 1.
    shear_factor : float
        k_s > 0.
    load_factors : list of float, optional
        Explicit load factors, finite.
    cell : str
        'quadrilateral' or 'triangle'.

    Raises
    ------
    core_se3.errors.MaterialError
        E <= 0, h <= 0, nu outside (-1, 0.5) (the project's material range), k_s <= 0, non-finite.
    core_se3.errors.MeshError
        A length (L, width, R) <= 0 or non-finite, or a mesh count < 1.
    core_se3.errors.LoadError
        Any other parameter (loads, switches) not finite.
    core_se3.errors.OptionError
        steps < 1, non-finite load factors, an unknown cell.
    """
    from core_se3.errors import LoadError, MaterialError, MeshError, OptionError
    where = f"case {case.name!r}"
    for k, v in p.items():
        if not np.isfinite(v):
            cls = MaterialError if k in ("E", "nu", "h") else MeshError if k in _GEOMETRY_KEYS else LoadError
            raise cls(f"{where}: parameter {k} = {v} is not finite; set a finite value (--set {k}=...)")
    bad = [(k, "> 0") for k in ("E", "h") if k in p and not p[k] > 0]
    if "nu" in p and not -1.0 < p["nu"] < 0.5:
        bad.append(("nu", "in (-1, 0.5)"))
    if bad:
        k, rng = bad[0]
        raise MaterialError(f"{where}: {k} = {p[k]:g} must be {rng}; set it with --set {k}=...")
    if not (np.isfinite(shear_factor) and shear_factor > 0):
        raise MaterialError(f"{where}: shear_factor = {shear_factor} must be finite and > 0")
    for k in _GEOMETRY_KEYS:
        if k in p and not p[k] > 0:
            raise MeshError(f"{where}: the length {k} = {p[k]:g} must be > 0")
    try:
        ok = len(mesh) == 2 and all(int(n) == n and n >= 1 for n in mesh)
    except TypeError:
        ok = False
    if not ok:
        raise MeshError(f"{where}: mesh must be (nx, ny) with integers >= 1, got {mesh!r} (e.g. --mesh 16x1)")
    if steps is not None and not (int(steps) == steps and steps >= 1):
        raise OptionError(f"{where}: steps must be an integer >= 1, got {steps!r}")
    if cell not in ("quadrilateral", "triangle"):
        raise OptionError(f"{where}: cell must be 'quadrilateral' (Q2) or 'triangle' (P2), got {cell!r}")
    if load_factors is not None and not np.all(np.isfinite(np.asarray(load_factors, float))):
        raise OptionError(f"{where}: load_factors must be finite, got {list(load_factors)!r}")


#: penalty springs of core_se3's builders that fenicsx_ref replaces by exact (Dirichlet) supports:
#: the semicylinder's pinned edges, u_z (k_pin E h) and the rotation about y (k_rot E h^3)
_SPRINGS = ("k_pin", "k_rot")


def check_springs(case, p):
    """NotImplementedError when a support spring is softer than the case's own value.

    fenicsx_ref holds those supports exactly (the rigid limit).  The catalogue's values are
    that limit (sze-semicylinder 16x16 in core_se3: crown -u_z(P_max) 1.6809849 with k_pin = 1e3,
    k_rot = 1e5; 1.6809841 with 1e6, 1e8: 4e-7), as is any stiffer value; a softer one is a
    different problem (k_pin = 1: 1.6814934; k_rot = 1e-2: a limit point at P = 646) that this
    model would replace silently by the rigid one."""
    soft = [(k, p[k], case.params[k]) for k in _SPRINGS if k in p and k in case.params and p[k] < case.params[k]]
    if soft:
        k, v, v0 = soft[0]
        raise NotImplementedError(
            f"fenicsx_ref: case {case.name!r} has {k} = {v:g} below the catalogue's {v0:g}: fenicsx_ref "
            f"holds that support exactly (the rigid limit {k} -> infinity, which {v0:g} and stiffer "
            f"values reproduce), not as a spring; run a softer {k} with core_se3 or drop --set {k}")


def reference_mismatch(ref, p):
    """"" when the reference entry holds for the parameters p, else why not (the catalogue's
    ``Reference.applies``, e.g. a table in physical units computed for another E or h: an
    error against it would measure the change of parameters, not the model)."""
    if ref is None or ref.applies is None:
        return ""
    return ref.applies(p, reference_entry(ref.entry).get("params", {}))


def apply_variant(case, p):
    """Loads (list of dicts, magnitudes at lam = 1) and the Reference, after the case's variant
    switches (``core_se3.catalogue.resolve``: pressure-strip follower=1, arch-follower
    direction=1, ...)."""
    loads, ref = resolve(case, p)
    return [asdict(ld) for ld in loads], ref


def _ref_axis(case, p, ref):
    """Slope a of the reference-load axis: ref_load = a * lam."""
    return ref.load_to_ref(p, case.load_value(p, 1.0)) - ref.load_to_ref(p, case.load_value(p, 0.0))


def reference_load_factors(case, p, ref, theta_limit=pi):
    """Load factors of the reference loads inside the case's range, and the cap on the range:
    the path stops at the last reference load with |theta| below ``theta_limit``."""
    e = reference_entry(ref.entry)
    blk = e[ref.block]
    a = _ref_axis(case, p, ref)
    lo, hi = case.lam_range
    lams, cap, info = [], hi, None
    for r, th in sorted(zip(e["load"], blk["theta"]), key=lambda t: abs(t[0])):
        if r == 0 or a == 0:
            continue
        lam = r / a
        if not (lo < lam <= hi * (1 + 1e-12)):
            continue
        if abs(th) >= theta_limit * (1 - 1e-9):
            if lams:
                cap = max(lams)
            else:
                cap = lo
            info = {"reason": f"reference |theta| >= {theta_limit:.6g} beyond this load factor",
                    "load_factor": cap}
            break
        lams.append(lam)
    return lams, cap, info


def reference_error(case, p, ref, steps, lam_tol=1e-9):
    """The catalogue's error measure at the reference's own load points (the steps include
    them), with the tip rotation-angle error (``measures.errors_at_table_loads``)."""
    e = reference_entry(ref.entry)
    blk = e[ref.block]
    a = _ref_axis(case, p, ref)
    Ls = ref.length(p)
    table = dict(load=np.asarray(e["load"], float), u=Ls * np.asarray(blk["u"], float),
                 v=Ls * np.asarray(blk["v"], float), theta=np.asarray(blk["theta"], float))
    u = np.array([s["probes"]["tip"]["u"] for s in steps]).reshape(-1, 3)
    out = errors_at_table_loads([a * s["load_factor"] for s in steps], u[:, [0, 2]],
                                [s["probes"]["tip"]["rotation_angle"] for s in steps], table,
                                tol=lam_tol * max(1.0, abs(a)))
    return dict(entry=ref.entry, block=ref.block, **out)


def literature_error(case, p, steps, probe):
    """The catalogue's curve deviation (``measures.curve_deviation``) of the computed path
    against the literature table of the case; error None with a note when the case's parameters
    are not the table's (a run in other units is compared in the table's units, ``u_max`` too).
    The table's scale P_max and its parameter names (``L_total``, ``half_angle_rad``,
    ``R_inner``, ...) are read by core_se3's ``family_sze.table_scale``, the one mapping onto the
    case keys."""
    from core_se3.catalogue.family_sze import table_scale, table_units
    P_max, why = table_scale(case, p)
    if why:  # the table is for the published parameters: a distance to it would measure the change
        return {"entry": case.extra["literature"], "file": "literature.json", "error": None,
                "note": f"not compared: {why}"}
    lams = [s["load"]["value"] / P_max for s in steps]
    col = curve_columns(case)[0]
    a = table_units(case, p)[0]          # a run in other units: P_max is in its units, u / a in the table's
    dev, per, info = curve_deviation(case, lams, [{col["probe"]: np.asarray(s["probes"][probe]["u"], float) / a}
                                                  for s in steps])
    out = {"entry": case.extra["literature"], "file": "literature.json", "column": col["column"],
           "measure": "max distance to the tabulated curve in (P/P_max, u/u_max)",
           "error": dev if len(steps) else None, "n_points": len(steps), "P_max": P_max,
           "u_max": info[0]["u_max"]}
    if len(steps):
        j = int(np.argmax(per))
        out["error_at_load"] = float(lams[j] * P_max)
        out["per_load"] = [[float(x * P_max), float(d)] for x, d in zip(lams, per)]
    return out
