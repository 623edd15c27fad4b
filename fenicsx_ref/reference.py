"""Case parameters, load variants and the project's error measure (NumPy only, no DOLFINx).

Error measure (shared by every model of the project): at each reference load on the computed
path, the distance between the computed and reference probe displacements, divided by the
largest reference probe displacement on the path; the case error is the max over the path.
Planar references (u, v, theta) map onto the shell as (ux, uz, rotation about -y), uy = 0.
"""
from __future__ import annotations

from dataclasses import replace
from math import pi

import numpy as np

__all__ = ["case_params", "apply_variant", "case_length", "case_domain", "reference_entry",
           "reference_load_factors", "reference_error", "point_curve_distances", "curve_distance",
           "literature_curve", "literature_error"]


def reference_entry(name):
    """Parsed entry of elastica.json (via core_se3.references when available)."""
    try:
        from core_se3.references import elastica_entry
    except ImportError:  # pragma: no cover - fallback while core_se3.references is absent
        import json
        import os
        path = os.path.join(os.path.dirname(__file__), "..", "core_se3", "data", "elastica.json")
        with open(path, encoding="utf-8") as f:
            return json.load(f)[name]
    return elastica_entry(name)


def case_params(case, overrides):
    p = dict(case.params)
    for k, v in overrides.items():
        if k not in p:
            raise KeyError(f"case {case.name!r} has no parameter {k!r}; parameters: {', '.join(p)}")
        p[k] = float(v)
    return p


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


def apply_variant(case, p):
    """Loads (list of dicts, magnitudes at lam = 1) and the Reference, after the parameter switches
    documented in the case notes (pressure-strip: follower=1; arch-follower: direction=1)."""
    ref = case.reference
    loads = []
    for ld in case.loads:
        d = dict(kind=ld.kind, edge=ld.edge, direction=tuple(ld.direction),
                 magnitude=float(ld.magnitude(p)), follower=bool(ld.follower))
        if ld.kind == "edge_rotation":
            d.update(axis=ld.axis, point=ld.point, free=ld.free)
        loads.append(d)
    if case.name == "pressure-strip" and p.get("follower", 0.0) >= 0.5:
        loads[0]["follower"] = True
        ref = replace(ref, entry="5_plate_cylindrical_bending_pressure_follower")
    if case.name == "arch-follower" and p.get("direction", 0.0) >= 0.5:
        loads[0]["direction"] = (0.0, 0.0, 1.0)
        ref = replace(ref, entry="4_arch_halfcircle_follower_normal_inward_shell_ks1")
    return loads, ref


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
    e = reference_entry(ref.entry)
    blk = e[ref.block]
    a = _ref_axis(case, p, ref)
    Ls = ref.length(p)
    done = {round(s["load_factor"], 12): s for s in steps}
    rows, denom = [], 0.0
    for r, u, v, th in zip(e["load"], blk["u"], blk["v"], blk["theta"]):
        if a == 0:
            continue
        lam = r / a
        hit = None
        for k, s in done.items():
            if abs(k - lam) <= lam_tol * max(1.0, abs(lam)):
                hit = s
                break
        if hit is None:
            continue
        ref_u = np.array([u * Ls, 0.0, v * Ls])
        comp = np.asarray(hit["probes"]["tip"]["u"])
        denom = max(denom, float(np.linalg.norm(ref_u)))
        rows.append((r, float(np.linalg.norm(comp - ref_u)),
                     abs(hit["probes"]["tip"]["rotation_angle"] - th)))
    if not rows or denom == 0.0:
        return {"entry": ref.entry, "block": ref.block, "error": None, "n_points": len(rows)}
    errs = [d / denom for _, d, _ in rows]
    return {"entry": ref.entry, "block": ref.block, "error": float(max(errs)),
            "n_points": len(rows), "max_reference_displacement": denom,
            "theta_error_max": float(max(t for _, _, t in rows)),
            "per_load": [[float(r), float(er)] for (r, _, _), er in zip(rows, errs)]}


# ---- distance to a tabulated curve (literature load-displacement tables) --------------------------

def point_curve_distances(points, curve):
    """Euclidean distance from each point to a piecewise-linear curve (NumPy only).

    points: (k, 2) array; curve: (m, 2) array of vertices in order (m >= 1).  Returns (k,)."""
    P = np.asarray(points, dtype=float).reshape(-1, 2)
    C = np.asarray(curve, dtype=float).reshape(-1, 2)
    if len(C) == 0:
        raise ValueError("empty curve")
    if len(C) == 1:
        return np.linalg.norm(P - C[0], axis=1)
    A, AB = C[:-1], np.diff(C, axis=0)                       # segments A + t AB, t in [0, 1]
    L2 = np.einsum("ij,ij->i", AB, AB)
    AP = P[:, None, :] - A[None, :, :]                        # (k, m-1, 2)
    t = np.einsum("kij,ij->ki", AP, AB) / np.where(L2 > 0, L2, 1.0)
    t = np.clip(np.where(L2 > 0, t, 0.0), 0.0, 1.0)
    d = np.linalg.norm(AP - t[..., None] * AB[None], axis=2)  # (k, m-1)
    return d.min(axis=1)


def curve_distance(points, curve):
    """Largest distance from the points (k, 2) to the piecewise-linear curve (m, 2)."""
    d = point_curve_distances(points, curve)
    return float(d.max()) if len(d) else 0.0


def literature_curve(case):
    """(load/P_max, u/u_max, P_max, u_max) of a case whose reference is a literature table
    (``case.extra['literature']``, column ``case.extra['column']`` scaled by
    ``displacement_scale``); u_max is the table's largest |displacement|."""
    from core_se3.references import literature_entry
    ex = case.extra
    e = literature_entry(ex["literature"])
    x = np.asarray(e["P_over_Pmax"], dtype=float)
    u = np.asarray(e[ex["column"]], dtype=float) * float(ex.get("displacement_scale", 1.0))
    P_max = float(e["parameters"]["P_max"])
    u_max = float(np.max(np.abs(u)))
    return x, u / u_max, P_max, u_max


def literature_error(case, p, steps, probe):
    """Curve distance of the computed path (P_k/P_max, u_k/u_max) to the literature table; u_k is
    probe component ``probe_component`` times ``probe_sign`` (case.extra)."""
    x, y, P_max, u_max = literature_curve(case)
    ex = case.extra
    k, sgn = int(ex.get("probe_component", 2)), float(ex.get("probe_sign", 1.0))
    pts = np.array([[s["load"]["value"] / P_max, sgn * s["probes"][probe]["u"][k] / u_max]
                    for s in steps]).reshape(-1, 2)
    d = point_curve_distances(pts, np.column_stack([x, y]))
    out = {"entry": ex["literature"], "file": "literature.json", "column": ex["column"],
           "measure": "max distance to the tabulated curve in (P/P_max, u/u_max)",
           "error": float(d.max()) if len(d) else None, "n_points": int(len(d)),
           "P_max": P_max, "u_max": u_max}
    if len(d):
        j = int(np.argmax(d))
        out["error_at_load"] = float(pts[j, 0] * P_max)
        out["per_load"] = [[float(a * P_max), float(b)] for a, b in zip(pts[:, 0], d)]
    return out
