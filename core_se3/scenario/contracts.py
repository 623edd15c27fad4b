"""The contract every registered kind passes, read from its declaration alone (so that a new kind
is tested by registering it: tests/test_kind_contracts.py walks every registry, a user runs
:func:`check_kind` on a kind of a plugin):

* **TOML round trip**: a scenario with the kind, written by ``scenario.dumps`` and read back,
  validates to the same spec; the kind's own writer (``Kind.entry``) gives back its values;
* **a clear error for each required key missing**: a ScenarioError naming that key;
* **the tangent against central differences at a large rotation** (loads, fields, obstacles,
  elements, material laws, supports): ``model.verify.tangent_fd_check`` < 1e-6 at a state of
  nodal rotations of about 0.5 rad;
* **frame invariance**: the same scenario turned by a rigid rotation Q (its mesh, and every
  value by its Param's ``frame``) has the same residual and tangent in the body frames, to
  1e-10 relative.

The kind's values are its ``extra["example"]`` when it gives one (a placement that suits the
contract's strip, 1 x 0.5, clamped at x0), else the built-in examples below, else made from its
Params (every default given, a required number 1 or inside its bounds, a vector [0.3, -0.2,
0.9], ...).

Example
-------
>>> from core_se3.model import LOADS
>>> check_kind("loads", LOADS["edge_force"])              # doctest: +ELLIPSIS
{'round_trip': 0.0, 'missing_keys': ['force'], 'fd_tangent': ..., 'frame_invariance': ...}
"""
from __future__ import annotations

import copy
import os
import tempfile

import numpy as np

from .. import lie
from ..errors import ScenarioError
from .spec import from_dict as _from_dict, tomllib     # tomllib, or the tomli backport on Python 3.10
from .toml_writer import dumps

__all__ = ["BASE", "SECTIONS", "example_values", "scenario_with", "round_trip", "missing_keys", "fd_tangent",
           "frame_invariance", "check_kind", "rotated"]

BASE = {"units": "consistent", "mesh": {"generator": "rectangle", "L": 1.0, "width": 0.5, "nx": 4, "ny": 2},
        "material": {"E": 1.0e6, "nu": 0.3, "h": 0.02}, "supports": [{"type": "clamp", "edge": "x0"}],
        "probes": [{"name": "tip", "edge": "x1"}], "regions": {"all": {"box": {"x": [-1.0, 2.0]}}}}
# the sections whose kinds carry a residual (the tangent and frame-invariance contracts)
PHYSICAL = ("generator", "material", "supports", "loads", "fields", "obstacles", "elements")
SECTIONS = PHYSICAL + ("variables", "targets")
EXAMPLES = {
    ("obstacles", "half_space"): dict(point=[0.0, 0.0, -0.1], normal=[0.0, 0.0, 1.0]),
    ("obstacles", "sphere"): dict(centre=[0.5, 0.0, 0.5], radius=0.4),
    ("obstacles", "cylinder"): dict(point=[0.5, 0.0, 0.3], axis=[0.0, 1.0, 0.0], radius=0.2),
    ("obstacles", "box"): dict(centre=[0.5, 0.0, 0.4], half_sizes=[0.2, 0.2, 0.2], rotation=[0.1, 0.2, 0.3]),
    ("fields", "dipole"): dict(m=[0.3, -0.2, 0.9], x0=[0.5, 0.0, 1.0], mu0=1.0),
    ("material", "isotropic"): dict(E=1.0e6, nu=0.3, h=0.02),
    ("fields", "gradient"): dict(B=[0.01, 0.0, 0.02], G=[[0.01, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -0.01]]),
    ("loads", "pressure"): dict(p=0.5, direction=[0.3, -0.2, 0.9]),
    ("loads", "gravity"): dict(g=[0.3, -0.2, -9.0], rho=1000.0),
    ("supports", "fix"): dict(dofs=[2, 3]),
    ("generator", "annulus"): dict(r_in=0.5, r_out=1.0, angle=1.0, nr=2, nt=3),
    ("generator", "annulus_sector"): dict(r_in=0.5, r_out=1.0, angle=1.0, size=0.25),
    ("generator", "cylinder_panel"): dict(R=1.0, length=1.0, theta0=0.0, theta1=1.0, nt=3, nl=2),
    ("supports", "rotate"): dict(axis=[1.0, 0.0, 0.0], angle=0.4),
    ("supports", "prescribed"): dict(translate=[0.05, 0.0, 0.1], rotate=dict(axis=[1.0, 0.0, 0.0], angle=0.3)),
    ("variables", "field"): dict(field="f"), ("variables", "magnetisation"): dict(regions=["all"]),
    ("variables", "material"): dict(prop="E", regions=["all"]), ("variables", "load"): dict(load=0),
    ("targets", "position"): dict(value=[1.0, 0.0, 0.2]), ("targets", "angle"): dict(value=20.0),
    ("targets", "orientation"): dict(value=[0.0, -0.3, 0.0]),
}


def from_dict(doc):
    """The scenario of a contract's document (its plausibility warnings kept in the Scenario)."""
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return _from_dict(doc)


def _listed(v):
    """A default as TOML reads it: tuples as lists."""
    if isinstance(v, (list, tuple)):
        return [_listed(x) for x in v]
    return copy.deepcopy(v)


def _auto(p):
    """A value of Param p: its default, else one inside its bounds."""
    if not p.required:
        return _listed(p.default)
    if p.kind == "integer":
        return 1 if p.lo is None else int(p.lo)
    if p.kind == "number":
        lo = 0.0 if p.lo is None else p.lo
        return lo + 1.0 if p.hi is None else 0.5 * (lo + p.hi)
    if p.kind == "vector":
        return [0.3, -0.2, 0.9][:p.n] + [0.5] * max(0, p.n - 3)
    if p.kind == "matrix3":
        return [[0.1, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -0.1]]
    if p.kind == "bool":
        return False
    if p.kind == "string":
        return next(iter(p.choices)) if p.choices else "x"
    if p.kind == "table":
        return {q.name: _auto(q) for q in p.fields if q.default is not None}
    return [] if p.kind == "list" else None


def example_values(section, kind):
    """The kind's values for the contracts (module docstring): every key with a value."""
    given = (getattr(kind, "extra", None) or {}).get("example") or EXAMPLES.get((section, kind.name), {})
    out = {p.name: _auto(p) for p in kind.params}
    out.update(copy.deepcopy(given))
    if "backend" in out and "backend" not in given:
        out["backend"] = "structured"          # (the same mesh with or without Gmsh)
    return {k: v for k, v in out.items() if v is not None}


def scenario_with(section, kind, values):
    """The contract's scenario document (BASE) with the kind's entry of ``values``, and the
    dotted key of that entry."""
    doc = copy.deepcopy(BASE)
    name = kind.name
    if section == "generator":
        doc["mesh"] = dict(generator=name, **values)
        doc["supports"], doc["probes"], doc["regions"] = [{"type": "clamp", "nodes": [0]}], [], {}
        return doc, "mesh"
    if section == "material":
        doc["material"] = dict(law=name, **values)
        return doc, "material"
    if section == "elements":
        doc["solver"] = {"element": name}
        doc["loads"] = [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}]
        return doc, "solver"
    if section == "supports":
        doc["supports"].append(dict(type=name, edge="x1", **values))
        return doc, "supports[1]"
    if section == "loads":
        sel = {"edge": "x1"} if getattr(kind, "target", "elements") != "elements" else {}
        doc["loads"] = [dict(type=name, **sel, **values)]
        return doc, "loads[0]"
    if section == "fields":
        doc["fields"] = {"f": dict(type=name, **values)}
        doc["magnets"] = [{"Br": [0.0, 0.0, 0.5], "mu0": 1.0}]
        return doc, "fields.f"
    if section == "obstacles":
        doc["obstacles"] = [dict(type=name, **values)]
        return doc, "obstacles[0]"
    return _design_doc(doc, section, kind, values)


def _design_doc(doc, section, kind, values):
    """A [design] around a variable or a target kind (a field, a magnet, a load to refer to)."""
    doc["fields"] = {"f": {"type": "uniform", "B": [0.0, 0.0, 0.01]}}
    doc["magnets"] = [{"Br": [0.1, 0.0, 0.0], "mu0": 1.0}]
    doc["loads"] = [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 0.01]}]
    var = dict(type=kind.name, **values) if section == "variables" else {"type": "field", "field": "f"}
    tgt = dict(type=kind.name, probe="tip", **values) if section == "targets" else \
        {"type": "position", "probe": "tip", "value": [1.0, 0.0, 0.1]}
    doc["design"] = {"variables": [var], "targets": [tgt]}
    return doc, f"design.{section}[0]"


def _entry(doc, key):
    """The table of the dotted key (``loads[0]``, ``fields.f``, ``design.targets[0]``) in doc."""
    from .keys import split_dotted
    node = doc
    for p in split_dotted(key):
        node = node[p]
    return node


def round_trip(section, kind):
    """0.0 when the scenario with the kind survives dumps -> TOML -> validation unchanged and
    the kind's writer (``Kind.entry``) gives back its validated values; an AssertionError
    naming the difference otherwise."""
    doc, key = scenario_with(section, kind, example_values(section, kind))
    spec = from_dict(doc).spec
    again = from_dict(tomllib.loads(dumps(doc))).spec
    assert json_equal(spec, again), f"{kind.name}: the spec changes through TOML"
    if section in ("elements",):
        return 0.0
    table, entry = _entry(doc, key), _entry(spec, key)
    entry = entry["params"] if section == "obstacles" else entry
    values = {p.name: entry.get(p.name) for p in kind.params}
    for k in kind.keys():
        table.pop(k, None)
    table.update(kind.entry(values))
    written = from_dict(tomllib.loads(dumps(doc))).spec
    assert json_equal(written, spec), f"{kind.name}: Kind.entry does not give back the values"
    return 0.0


def json_equal(a, b):
    import json
    return json.dumps(a, sort_keys=True, default=str) == json.dumps(b, sort_keys=True, default=str)


def missing_keys(section, kind):
    """The required keys of the kind, each checked: without it the scenario is a ScenarioError
    naming exactly that key and saying it is missing (an AssertionError otherwise)."""
    values = example_values(section, kind)
    out = []
    for p in kind.params:
        if not p.required:
            continue
        doc, key = scenario_with(section, kind, {k: v for k, v in values.items() if k != p.name})
        try:
            from_dict(doc)
        except ScenarioError as exc:
            assert exc.key == f"{key}.{p.name}" and "missing required key" in exc.detail, (kind.name, p.name, str(exc))
            out.append(p.name)
            continue
        raise AssertionError(f"{kind.name}: a scenario without {p.name!r} was accepted")
    return out


def _state(problem, amplitude=0.5, seed=0):
    """Frames of nodal rotations and displacements of about ``amplitude`` (prescribed nodes set)."""
    xi = amplitude * np.random.default_rng(seed).standard_normal((problem.mesh.n_nodes, 6))
    return problem.apply_prescribed(problem.mesh.g0 @ lie.exp(xi), 0.7)


def _into_contact(problem, g, lam):
    """g moved rigidly so that the node nearest to each obstacle lies a thickness inside it
    (a state with nodes in contact, in the band and free: the contact tangent is tested)."""
    for ld in problem.loads:
        ob = getattr(ld, "obstacle", None)
        if ob is None:
            continue
        d, n, _ = ob.evaluate(g[:, :3, 3], lam)
        k = int(np.argmin(d))
        T = np.eye(4)
        T[:3, 3] = -(d[k] + ld.h) * n[k]
        g = T @ g
    return g


def fd_tangent(section, kind):
    """max |K - K_fd| / max |K_fd| of the scenario with the kind at a large rotation (< 1e-6
    asserted); with an obstacle, at a state pushed into it (:func:`_into_contact`)."""
    from ..model.verify import tangent_fd_check
    doc, _ = scenario_with(section, kind, example_values(section, kind))
    problem = from_dict(doc).problem
    err = tangent_fd_check(problem, _into_contact(problem, _state(problem), 0.7), 0.7)[0]
    assert err < 1e-6, f"{kind.name}: tangent against central differences {err:.2e}"
    return err


def rotated(values, params, Q):
    """``values`` turned by the rotation Q, each by its Param's ``frame`` (tables recursively)."""
    out = dict(values)
    for p in params:
        v = values.get(p.name)
        if v is None:
            continue
        if p.kind == "table" and isinstance(v, dict):
            out[p.name] = rotated(v, p.fields, Q)
        elif p.frame == "vector":
            out[p.name] = (Q @ np.asarray(v, float)).tolist()
        elif p.frame == "tensor":
            out[p.name] = (Q @ np.asarray(v, float) @ Q.T).tolist()
        elif p.frame == "rotation":
            out[p.name] = lie.log_so3(Q @ lie.exp_so3(np.asarray(v, float))).tolist()
    return out


def _turned_doc(doc, section, kind, values, Q, path):
    """The contract's scenario turned by Q: its mesh written to ``path`` (a VTU file) turned,
    the node sets by id, every vector of the entry and of the magnets turned."""
    import meshio
    scn = from_dict(doc)
    mesh = scn.mesh
    meshio.write_points_cells(path, mesh.X @ Q.T, [("quad", mesh.quads)])
    turned, _ = scenario_with(section, kind, rotated(values, kind.params, Q))
    turned["mesh"] = {"file": path, "d1_hint": (Q @ mesh.g0[0, :3, 0]).tolist()}
    turned["edges"] = {k: {"nodes": np.asarray(v).tolist()} for k, v in mesh.edges.items()}
    turned["regions"] = {k: {"elements": np.asarray(v).tolist()} for k, v in scn.regions.items()}
    for m in turned.get("magnets", []):
        m["Br"] = (Q @ np.asarray(m["Br"], float)).tolist()
    for ld in turned.get("loads", []) if section != "loads" else []:
        ld["force"] = (Q @ np.asarray(ld["force"], float)).tolist()
    return scn, from_dict(turned)


def frame_invariance(section, kind, seed=1):
    """max relative difference of the residual and the tangent (body frames) between the
    scenario and the same turned by a rigid rotation (< 1e-10 asserted)."""
    values = example_values(section, kind)
    doc, _ = scenario_with(section, kind, values)
    Q = lie.exp_so3(np.array([0.7, -1.1, 0.4]))
    T = np.eye(4)
    T[:3, :3] = Q
    with tempfile.TemporaryDirectory() as d:
        a, b = _turned_doc(doc, section, kind, values, Q, os.path.join(d, "turned.vtu"))
    g = _state(a.problem, seed=seed)
    ea, eb = a.problem.evaluate(g, 0.7), b.problem.evaluate(T @ g, 0.7)
    err = max(np.abs(ea.r - eb.r).max() / max(np.abs(ea.r).max(), 1e-300),
              abs(ea.K - eb.K).max() / max(abs(ea.K).max(), 1e-300))
    assert err < 1e-10, f"{kind.name}: residual and tangent change under a rigid rotation by {err:.2e}"
    return err


def check_kind(section, kind):
    """Every contract of one kind of ``section`` (one of :data:`SECTIONS`): {contract: result}
    (an AssertionError or ScenarioError naming the kind when one fails)."""
    out = dict(round_trip=round_trip(section, kind), missing_keys=missing_keys(section, kind))
    if section in PHYSICAL and section != "generator":
        out["fd_tangent"] = fd_tangent(section, kind)
        out["frame_invariance"] = frame_invariance(section, kind)
    return out

