"""Run a catalogue case: build its Problem (the generic builder or its family's), solve it, and
write its result document with the error against its reference."""
from __future__ import annotations

import numbers
import time

from ..errors import MeshError
from ..solvers.options import load_steps
from .case import case_params, family_of, get_case
from .generic import build_problem as generic_build, case_document, torsion_constant
from .references import elastica_entry

__all__ = ["run_case", "build_problem"]


def build_problem(case, p, mesh=None, element="default", linear_solver="auto"):
    """The Problem of a case at parameters p (its family's builder, or the generic one).

    Parameters
    ----------
    case : Case
        The case; ``p``: its parameters (:func:`case_params`).
    mesh : (int, int), optional
        (nx, ny) elements (default the case's).
    element, linear_solver : str, optional
        As for :class:`~core_se3.Problem`.

    Returns
    -------
    core_se3.Problem
        With the case's supports, loads (at lam = 1) and probe.

    Example
    -------
    >>> case = get_case("cantilever-shear")
    >>> prob = build_problem(case, case_params(case), mesh=(4, 1))
    >>> prob.mesh.n_elements, sorted(prob.probes), len(prob.loads)
    (4, ['tip'], 1)
    """
    fam = family_of(case)
    if fam is not None:
        return fam.build(case, p, mesh, element, linear_solver)
    return generic_build(case, p, mesh, element, linear_solver)


def run_case(name, mesh=None, overrides=None, steps=None, element="default", linear_solver="auto",
             **solve_kw):
    """Run a catalogue case; returns (document in the result schema, Result, Problem).

    mesh: (nx, ny) elements (default the case's); overrides: case parameters to change
    (``--set``); steps: load steps (default the case's); solve_kw: solver options.

    Parameters
    ----------
    name : str
        The case.
    mesh, overrides, steps, element, linear_solver, **solve_kw
        As above.

    Returns
    -------
    (dict, core_se3.Result, core_se3.Problem)
        The document carries ``reference`` = dict(entry, block, error, ...) for cases with a
        reference.

    Example
    -------
    >>> doc, res, prob = run_case("cantilever-shear", mesh=(8, 1), steps=4)
    >>> doc["reference"]["entry"], doc["reference"]["error"] < 5e-3
    ('1_cantilever_tip_force_kirchhoff', True)
    """
    case = get_case(name)
    steps = case.steps if steps is None else load_steps(steps)
    if mesh is not None and (len(mesh) != 2 or any(isinstance(k, bool) or not isinstance(k, numbers.Integral)
                                                   or k < 1 for k in mesh)):
        # checked here: a case whose mesh is chosen from its parameters (nx None) read 0 as "auto"
        raise MeshError(f"mesh must be two whole numbers >= 1 (elements along x and y), got {mesh!r}")
    p = case_params(case, overrides)
    t0 = time.perf_counter()
    prob = build_problem(case, p, mesh, element, linear_solver)
    t_setup = time.perf_counter() - t0
    fam = family_of(case)
    if fam is not None:
        doc, res = fam.run(case, p, prob, steps, **solve_kw)
        res.timings["setup"] = res.timings.get("setup", 0.0) + t_setup
        doc["timings"]["setup"] = doc["timings"].get("setup", 0.0) + t_setup
        doc["timings"]["total"] = doc["timings"].get("total", 0.0) + t_setup
        return doc, res, prob
    res = prob.solve(steps=steps, **solve_kw)
    res.timings["setup"] += t_setup
    doc = case_document(case, p, prob, res)
    if case.name == "torsion":
        doc["torsion"] = _torsion_block(p, mesh or case.mesh, element)
    return doc, res, prob


def _torsion_block(p, mesh, element):
    """The torsion case's small-twist J beside the entry's plate values: those of the seed strip
    (w = 0.25, h = 0.1; --set width=0.5 printed them beside J of the wider strip), so at other
    w, h the thin-plate w h^3/3 is evaluated at the run's and the Mindlin value is not given."""
    from .cases_shells import same_params
    e = elastica_entry("5_strip_torsion_seed_strip")["params"]
    why = same_params(p, {k: e[k] for k in ("w", "h")})
    out = dict(J=torsion_constant(p, mesh, element), mesh=list(mesh), reference_entry="5_strip_torsion_seed_strip",
               J_mindlin_ks1=None if why else e["J_mindlin_ks=1"],
               J_kirchhoff_plate=p["width"] * p["h"] ** 3 / 3 if why else e["J_kirchhoff_plate=wh^3/3"],
               note="The Cosserat law penalises the skew part of the curvature (H on unsymmetrised K), "
                    "which a Reissner-Mindlin plate leaves free; in the edge layers of this thick strip "
                    "(w/h = 2.5) that stiffens the twist above the Mindlin value toward w h^3/3.")
    if why:
        out["note"] = f"Mindlin value not given: {why} (w h^3/3 evaluated at the run's w, h)"
    return out
