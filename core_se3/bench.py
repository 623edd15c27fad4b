"""Catalogue runner: build a Problem from a case definition, solve, measure against its reference.

Error measure (used by every module of the project): at each reference load, the distance
between the computed and the reference probe displacement, divided by the largest reference
probe displacement on the path; the case's error is the maximum over the path.  The reference
curves are dense and smooth, so they are interpolated (cubic spline in the load) at the
computed load levels.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from math import pi
from typing import Callable

import numpy as np

from . import cases as C
from . import mesh as M
from .material import Material
from .problem import Problem
from .references import elastica_entry
from .results import SCHEMA, VERSION

__all__ = ["build_problem", "run_case", "case_params", "reference_for", "error_against_reference",
           "result_document", "Family", "FAMILIES", "register_family"]


@dataclass
class Family:
    """How to run the cases of one family (``case.extra["family"]``) that the generic strip/arch
    runner below does not cover: each hook takes the generic one's arguments.

    build(case, p, mesh, element, linear_solver) -> Problem
    run(case, p, prob, steps, verbose, **solve_kw) -> (doc, Result)     (doc: result schema)
    plot(case, p, doc, res, path) -> None                               (optional)
    report(doc) -> list of extra lines for the CLI                      (optional)
    """
    build: Callable
    run: Callable
    plot: Callable | None = None
    report: Callable | None = None


FAMILIES: dict[str, Family] = {}


def register_family(name, family):
    FAMILIES[name] = family


def family_of(case):
    name = case.extra.get("family")
    if name is None:
        return None
    if name not in FAMILIES:
        raise KeyError(f"case {case.name!r} belongs to the unregistered family {name!r}")
    return FAMILIES[name]


def case_params(case, overrides=None):
    p = dict(case.params)
    for k, v in (overrides or {}).items():
        if k not in p:
            raise KeyError(f"case {case.name!r} has no parameter {k!r}; its keys: {', '.join(p)}")
        p[k] = float(v)
    return p


def _mesh_for(case, p, nx, ny):
    if case.geometry == "strip":
        return M.rectangle(p["L"], p["width"], nx, ny)
    if case.geometry == "arch":
        return M.cylinder_arch(p["R"], pi, p["width"], nx, ny)
    if case.geometry == "semicylinder":
        return M.cylinder_panel(p["R"], p["L"], -pi / 2, pi / 2, nx, ny)
    raise ValueError(f"unknown geometry {case.geometry!r}")


def build_problem(case, p, mesh=None, element="default", linear_solver="auto"):
    fam = family_of(case)
    if fam is not None:
        return fam.build(case, p, mesh, element, linear_solver)
    nx, ny = mesh or case.mesh
    m = _mesh_for(case, p, nx, ny)
    prob = Problem(m, Material(p["E"], p["nu"], p["h"], drilling=p.get("drilling", 1.0)),
                   element=element, linear_solver=linear_solver)
    for kind, where in case.supports:
        if kind == "clamp":
            prob.clamp(where)
    for load in case.loads:
        mag = load.magnitude(p)
        d = np.asarray(load.direction, float)
        if case.name == "arch-follower" and p.get("direction", 0.0) == 1.0:
            d = np.array([0.0, 0.0, 1.0])
        if load.kind == "edge_force":
            prob.add_edge_force(load.edge, mag * d, follower=load.follower)
        elif load.kind == "edge_moment":
            prob.add_edge_moment(load.edge, mag * d, follower=load.follower)
        elif load.kind == "pressure":
            prob.add_pressure(mag, direction=d, follower=bool(p.get("follower", 0.0)))
        elif load.kind == "edge_rotation":
            nodes = m.node_set(load.edge)
            point = [m.X[nodes, i].mean() if c is None else c for i, c in enumerate(load.point)]
            prob.rotate_edge(load.edge, load.axis, mag, point=point, free=load.free)
        else:
            raise ValueError(f"unknown load kind {load.kind!r}")
    prob.add_probe("tip", "x1")
    return prob


def reference_for(case, p):
    """(entry name, block, ref) with ref = dict(load, u, v, theta) in case units, or None."""
    ref = case.reference
    if ref is None:
        return None
    entry = ref.entry
    if case.name == "arch-follower" and p.get("direction", 0.0) == 1.0:
        entry = "4_arch_halfcircle_follower_normal_inward_shell_ks1"
    if case.name == "pressure-strip" and p.get("follower", 0.0) == 1.0:
        entry = "5_plate_cylindrical_bending_pressure_follower"
    e = elastica_entry(entry)
    tip = e[ref.block]
    Lr = ref.length(p)
    return entry, ref.block, dict(load=np.asarray(e["load"], float), u=Lr * np.asarray(tip["u"], float),
                                  v=Lr * np.asarray(tip["v"], float), theta=np.asarray(tip["theta"], float))


def _planar(case, u):
    """Map a computed probe displacement (ux, uy, uz) onto the reference plane (u, v)."""
    if case.extra.get("plane") == "xy":
        return np.array([u[0], u[1]])
    return np.array([u[0], u[2]])


def error_against_reference(case, p, loads_ref_axis, disps, ref):
    """Max over the path of |d - d_ref(load)| / max |d_ref| (see module docstring)."""
    from scipy.interpolate import CubicSpline
    L = ref["load"]
    order = np.argsort(L)
    L, u, v = L[order], ref["u"][order], ref["v"][order]
    keep = np.concatenate([[True], np.diff(L) > 0])
    L, u, v = L[keep], u[keep], v[keep]
    su, sv = CubicSpline(L, u), CubicSpline(L, v)
    lo, hi = min(loads_ref_axis), max(loads_ref_axis)
    on_path = (L >= min(lo, 0.0) - 1e-12) & (L <= hi + 1e-12) & (L * np.sign(hi if hi != 0 else lo) >= -1e-12)
    scale = np.max(np.hypot(u[on_path], v[on_path]))
    errs = np.full(len(loads_ref_axis), np.nan)        # NaN where the load is outside the table
    for i, (lam_ref, d) in enumerate(zip(loads_ref_axis, disps)):
        if lam_ref < L[0] - 1e-12 or lam_ref > L[-1] + 1e-12:
            continue
        dr = np.array([su(lam_ref), sv(lam_ref)])
        errs[i] = np.linalg.norm(d - dr) / scale
    k = int(np.nanargmax(errs))
    return float(errs[k]), float(loads_ref_axis[k]), errs


def edge_wrench(prob, g, edge, point):
    """Lab force and moment about ``point`` that the shell exerts on the supports of ``edge``
    (internal forces at the edge nodes, i.e. minus the reactions)."""
    ev = prob.element.evaluate(g, tangent=False)
    nodes = prob.mesh.node_set(edge)
    R = g[nodes, :3, :3]
    n = np.einsum("nij,nj->ni", R, ev["r"][nodes, :3])
    m = np.einsum("nij,nj->ni", R, ev["r"][nodes, 3:]) + np.cross(g[nodes, :3, 3] - point, n)
    return n.sum(0), m.sum(0)


def torsion_constant(p, mesh, element="default", angle=1e-4):
    """Small-twist torsion constant J = T L / (G angle) of the ``torsion`` case's strip."""
    case = C.get_case("torsion")
    q = dict(p, angle=angle)
    prob = build_problem(case, q, mesh, element)
    res = prob.solve(steps=1, rtol=1e-12, dtol=1e-12)
    _, M = edge_wrench(prob, res.final.g, "x1", np.array([q["L"], 0.0, 0.0]))
    G = q["E"] / (2 * (1 + q["nu"]))
    return float(M[0] * q["L"] / (G * angle))


def run_case(name, mesh=None, overrides=None, steps=None, element="default", linear_solver="auto",
             verbose=False, **solve_kw):
    """Run a catalogue case; returns (document in the result schema, Result, Problem)."""
    case = C.get_case(name)
    p = case_params(case, overrides)
    t0 = time.perf_counter()
    prob = build_problem(case, p, mesh, element, linear_solver)
    t_setup = time.perf_counter() - t0
    fam = family_of(case)
    if fam is not None:
        doc, res = fam.run(case, p, prob, steps or case.steps, verbose, **solve_kw)
        res.timings["setup"] = res.timings.get("setup", 0.0) + t_setup
        return doc, res, prob
    res = prob.solve(steps=steps or case.steps, verbose=verbose, **solve_kw)
    res.timings["setup"] += t_setup
    doc = result_document(case, p, prob, res)
    if case.name == "torsion":
        e = elastica_entry("5_strip_torsion_seed_strip")["params"]
        J = torsion_constant(p, mesh or case.mesh, element)
        doc["torsion"] = dict(
            J=J, mesh=list(mesh or case.mesh), reference_entry="5_strip_torsion_seed_strip",
            J_mindlin_ks1=e["J_mindlin_ks=1"], J_kirchhoff_plate=e["J_kirchhoff_plate=wh^3/3"],
            note="The Cosserat law penalises the skew part of the curvature (H on unsymmetrised K), "
                 "which a Reissner-Mindlin plate leaves free; in the edge layers of this thick strip "
                 "(w/h = 2.5) that stiffens the twist above the Mindlin value toward w h^3/3.")
    return doc, res, prob


def result_document(case, p, prob, res):
    ref = reference_for(case, p)
    steps = []
    loads_ref, disps = [], []
    axis = np.array([0.0, 0.0, 1.0]) if case.extra.get("plane") == "xy" else np.array([0.0, -1.0, 0.0])
    for st in res.steps:
        pr = st.probes["tip"]
        value = case.load_value(p, st.load_factor)
        load = dict(name=case.load_name, value=float(value), unit=case.load_unit)
        if ref is not None:
            load.update(reference_entry=ref[0], reference_value=float(case.reference.load_to_ref(p, value)))
        steps.append(dict(
            load_factor=float(st.load_factor),
            load=load,
            probes={"tip": dict(u=pr["u"].tolist(), rotation_angle=float(np.linalg.norm(pr["w"])),
                                rotation_about_axis=float(pr["w"] @ axis),
                                rotation_vector=pr["w"].tolist(), rotation=pr["R"].tolist())},
            iterations=int(st.iterations),
            residual=float(st.residual_history[-1]) if st.residual_history else 0.0,
            residual_history=[float(x) for x in st.residual_history],
            balance_error=float(st.balance_error),
        ))
        if ref is not None:
            loads_ref.append(case.reference.load_to_ref(p, value))
            disps.append(_planar(case, pr["u"]))
    reference = None
    if ref is not None:
        entry, block, r = ref
        err, at, errs = error_against_reference(case, p, loads_ref, disps, r)
        for s, e in zip(steps, errs):
            s["error"] = None if np.isnan(e) else float(e)
        reference = dict(entry=entry, block=block, error=err, error_at_load=at, file="elastica.json")
    m = prob.mesh
    t = dict(res.timings)
    t["total"] = sum(t.values())
    return dict(
        schema=SCHEMA, version=VERSION, case=case.name, model="core_se3", variant=prob.element_name,
        params={k: dict(value=v, unit=case.units.get(k, "")) for k, v in p.items()},
        mesh=dict(nx=(m.shape or (m.n_elements, 1))[0], ny=(m.shape or (m.n_elements, 1))[1], n_nodes=m.n_nodes, n_elements=m.n_elements,
                  n_dofs=6 * m.n_nodes),
        steps=steps, timings=t, reference=reference,
    )


# Case families with their own runners register here (each module imports this one).
from . import bench_magnetic  # noqa: E402,F401
from . import bench_sze  # noqa: E402,F401
