"""The generic catalogue runner: strips, arches and the semi-cylinder built from their case data,
solved by load stepping, measured against their reference (``catalogue.measures``)."""
from __future__ import annotations

from math import pi

import numpy as np

from .. import mesh as M
from ..fem import Material
from ..model import Problem
from ..results import result_document, step_record
from .case import get_case, resolve
from .measures import error_against_reference
from .references import elastica_entry

__all__ = ["build_problem", "reference_for", "case_document", "planar", "edge_wrench",
           "torsion_constant", "case_mesh"]

# how a case load kind becomes a registered load of the model (core_se3.model.LOADS)
_AS_LOAD = {
    "edge_force": lambda ld: dict(force=ld.magnitude * np.asarray(ld.direction, float), follower=ld.follower),
    "edge_moment": lambda ld: dict(moment=ld.magnitude * np.asarray(ld.direction, float), follower=ld.follower),
    "pressure": lambda ld: dict(p=ld.magnitude, follower=True) if ld.follower else
    dict(p=ld.magnitude, direction=ld.direction),
}


def case_mesh(case, p, nx, ny):
    """The mesh of a strip, arch or semi-cylinder case."""
    if case.geometry == "strip":
        return M.rectangle(p["L"], p["width"], nx, ny)
    if case.geometry == "arch":
        return M.cylinder_arch(p["R"], pi, p["width"], nx, ny)
    if case.geometry == "semicylinder":
        return M.cylinder_panel(p["R"], p["L"], -pi / 2, pi / 2, nx, ny)
    raise ValueError(f"unknown geometry {case.geometry!r}")


def build_problem(case, p, mesh=None, element="default", linear_solver="auto"):
    """The Problem of a generic case at parameters p on an (nx, ny) mesh (default the case's).

    Parameters: case (a strip, arch or semi-cylinder Case), p (parameters), mesh ((nx, ny)),
    element, linear_solver.  Returns: Problem (supports, loads, probe ``tip`` on ``x1``).

    Example
    -------
    >>> case = get_case("arch-follower")
    >>> build_problem(case, case.params, (8, 1)).mesh.n_elements
    8
    """
    nx, ny = mesh or case.mesh
    m = case_mesh(case, p, nx, ny)
    prob = Problem(m, Material(p["E"], p["nu"], p["h"], drilling=p.get("drilling", 1.0)),
                   element=element, linear_solver=linear_solver)
    for kind, where in case.supports:
        if kind == "clamp":
            prob.clamp(where)
    loads, _ = resolve(case, p)
    for ld in loads:
        if ld.kind == "edge_rotation":
            nodes = m.node_set(ld.edge)
            point = [m.X[nodes, i].mean() if c is None else c for i, c in enumerate(ld.point)]
            prob.rotate_edge(ld.edge, ld.axis, ld.magnitude, point=point, free=ld.free)
        elif ld.kind in _AS_LOAD:
            prob.add_load(ld.kind, ld.edge, **_AS_LOAD[ld.kind](ld))
        else:
            raise ValueError(f"unknown load kind {ld.kind!r} of a generic case")
    prob.add_probe("tip", "x1")
    prob.solve_defaults.update(case.extra.get("solve", {}))      # e.g. torsion: limit_check off
    return prob


def reference_for(case, p, check=True):
    """(entry name, block, ref) with ref = dict(load, u, v, theta) in case units, or None.

    Parameters: case, p (its parameters; variants apply), check (False: also when
    ``Reference.applies`` says the entry was computed for other parameters, for studies that
    pick their own entry).  Returns: as above (u, v scaled by ``Reference.length``), None when
    the entry does not apply to p.

    Example
    -------
    >>> case = get_case("cantilever-shear")
    >>> entry, block, ref = reference_for(case, case.params)
    >>> entry, block, sorted(ref), ref["load"][:3].tolist()
    ('1_cantilever_tip_force_kirchhoff', 'tip', ['load', 'theta', 'u', 'v'], [0.0, 0.25, 0.5])
    """
    _, ref = resolve(case, p)
    if ref is None:
        return None
    e = elastica_entry(ref.entry)
    if check and ref.applies is not None and ref.applies(p, e.get("params", {})):
        return None                         # a table for other parameters: no error, not a wrong one
    tip = e[ref.block]
    Lr = ref.length(p)
    return ref.entry, ref.block, dict(load=np.asarray(e["load"], float), u=Lr * np.asarray(tip["u"], float),
                                      v=Lr * np.asarray(tip["v"], float), theta=np.asarray(tip["theta"], float))


def planar(case, u):
    """Map computed probe displacements (..., 3) = (ux, uy, uz) onto the reference plane (u, v).

    Parameters: case (``extra["plane"]`` 'xy', else the x-z plane), u (..., 3).  Returns: (..., 2).

    Example
    -------
    >>> planar(get_case("cantilever-shear"), [1.0, 2.0, 3.0]).tolist()       # x-z plane: (ux, uz)
    [1.0, 3.0]
    """
    u = np.asarray(u, float)
    return u[..., [0, 1]] if case.extra.get("plane") == "xy" else u[..., [0, 2]]


def case_document(case, p, prob, res, reference_case=None):
    """The result document of a catalogue run: steps with the reported load, the error against
    the case's reference (``reference_case`` overrides the case's Reference, e.g. a family's).

    Parameters
    ----------
    case : Case
        The case; ``p`` its parameters; ``prob`` the Problem; ``res`` the Result of its solve.
    reference_case : Case, optional
        The case whose Reference to measure against.

    Returns
    -------
    dict
        Schema core-se3-result v1; each step has ``error``, the document ``reference``.

    Example
    -------
    >>> case = get_case("cantilever-shear")
    >>> prob = build_problem(case, case.params, (4, 1))
    >>> doc = case_document(case, case.params, prob, prob.solve(steps=2))
    >>> [s["load"]["value"] for s in doc["steps"]], doc["reference"]["error"] < 0.02
    ([0.0, 2.0, 4.0], True)
    """
    rc = reference_case or case
    ref = reference_for(rc, p)
    axis = np.array([0.0, 0.0, 1.0]) if case.extra.get("plane") == "xy" else np.array([0.0, -1.0, 0.0])
    steps, loads_ref, disps = [], [], []
    for st in res.steps:
        value = case.load_value(p, st.load_factor)
        load = dict(name=case.load_name, value=float(value), unit=case.load_unit)
        if ref is not None:
            load.update(reference_entry=ref[0], reference_value=float(rc.reference.load_to_ref(p, value)))
            loads_ref.append(rc.reference.load_to_ref(p, value))
            disps.append(planar(case, st.probes["tip"]["u"]))
        steps.append(step_record(st, load, axis=axis))
    reference = None
    _, unresolved = resolve(rc, p)
    if ref is None and unresolved is not None and unresolved.applies is not None:
        why = unresolved.applies(p, elastica_entry(unresolved.entry).get("params", {}))
        reference = dict(entry=unresolved.entry, block=unresolved.block, error=None, file="elastica.json",
                         note=f"not compared: {why}")
    if ref is not None:
        entry, block, r = ref
        err, at, errs = error_against_reference(loads_ref, disps, r)
        for s, e in zip(steps, errs):
            s["error"] = None if np.isnan(e) else float(e)
        reference = dict(entry=entry, block=block, error=None if np.isnan(err) else err,
                         error_at_load=None if np.isnan(at) else at, file="elastica.json",
                         **_coverage(errs, r["load"], loads_ref))
    from ..scenario.provenance import problem_provenance
    extra = {}
    if res.critical_points:             # passed by load control with limit_check off (torsion)
        extra["critical_points"] = [dict(kind=c.kind, load_factor=float(c.lam), bracket=list(c.lam_bracket),
                                         step=int(c.step), description=c.describe()) for c in res.critical_points]
    return result_document(case.name, "core_se3", prob.element_name,
                           {k: dict(value=v, unit=case.units.get(k, "")) for k, v in p.items()},
                           prob.mesh, steps, res.timings, reference, provenance=problem_provenance(prob, res),
                           **extra)


def _coverage(errs, table_loads, loads_ref):
    """n_points (the steps compared) and n_beyond_table, with a ``note`` when some steps lie
    outside the table's load range (a run past the table's end, e.g. ``--set load_max`` above
    it): the error then covers the compared part of the path only."""
    n_out = int(np.isnan(errs).sum())
    out = dict(n_points=len(errs) - n_out, n_beyond_table=n_out)
    if n_out:
        x = np.asarray(loads_ref, float)[~np.isnan(errs)]
        out["note"] = (f"partial: the table's loads run from {np.min(table_loads):g} to {np.max(table_loads):g} "
                       f"(reference axis), the path to {np.asarray(loads_ref, float)[-1]:g}; {n_out} of "
                       f"{len(errs)} steps lie beyond it and are not compared (compared up to "
                       f"{x[np.argmax(np.abs(x))]:g})")
    return out


def edge_wrench(prob, g, edge, point):
    """Lab force and moment about ``point`` that the supports of ``edge`` exert on the shell (the
    reactions: the internal forces r_int at the edge nodes, where no load acts).

    Parameters
    ----------
    prob : core_se3.Problem
        The problem; ``g`` (n, 4, 4) a converged state.
    edge : str
        The supported node set.
    point : (3,) array
        The moment's reference point [length].

    Returns
    -------
    (3,) ndarray, (3,) ndarray
        Force [force] and moment [force x length].

    Example
    -------
    A tip force 0.01 along z: the clamp holds the strip with -0.01 and the moment 0.1 about y.

    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 0.01))
    >>> n, m = edge_wrench(p, p.solve(steps=1).final.g, "x0", np.zeros(3))
    >>> (n.round(9) + 0.0).tolist(), (m.round(5) + 0.0).tolist()
    ([0.0, 0.0, -0.01], [0.0, 0.1, 0.0])
    """
    ev = prob.element.evaluate(g, tangent=False)
    nodes = prob.mesh.node_set(edge)
    R = g[nodes, :3, :3]
    n = np.einsum("nij,nj->ni", R, ev.r[nodes, :3])
    m = np.einsum("nij,nj->ni", R, ev.r[nodes, 3:]) + np.cross(g[nodes, :3, 3] - point, n)
    return n.sum(0), m.sum(0)


def torsion_constant(p, mesh, element="default", angle=1e-4):
    """Small-twist torsion constant J = T L / (G angle) of the ``torsion`` case's strip.

    Parameters
    ----------
    p : dict
        The torsion case's parameters (E, nu, h, L, width, ...).
    mesh : (int, int)
        (nx, ny) elements.
    element : str, optional
        The element; ``angle``: the end twist [rad] of the linear solve.

    Returns
    -------
    float
        J [length^4] (T: the torque at the twisted end).

    Example
    -------
    Between the Mindlin (6.41e-5) and thin-plate (w h^3 / 3 = 8.33e-5) values, as in the README:

    >>> J = torsion_constant(get_case("torsion").params, (4, 2))
    >>> bool(6.41e-5 < J < 8.33e-5)
    True
    """
    case = get_case("torsion")
    q = dict(p, angle=angle)
    prob = build_problem(case, q, mesh, element)
    res = prob.solve(steps=1, rtol=1e-12, dtol=1e-12)
    _, Mw = edge_wrench(prob, res.final.g, "x1", np.array([q["L"], 0.0, 0.0]))
    G = q["E"] / (2 * (1 + q["nu"]))
    return float(Mw[0] * q["L"] / (G * angle))
