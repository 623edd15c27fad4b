"""The Problem of a validated scenario spec: material law, supports, loads and magnets through
the same registries and Problem methods as the Python API; failures of the core's own checks
become ScenarioErrors keyed to the section that caused them."""
from __future__ import annotations

import warnings

import numpy as np

from .. import lie
from .. import mesh as M
from ..errors import CoreSE3Error, LoadWarning, OptionError, ScenarioError, SingularSystemError
from ..fem import RegionMaterial
from ..fem.material_kinds import MATERIALS
from ..model import FIELDS, LOADS, MU0, SUPPORTS, Problem
from ..model.solving import check_linear_solver
from .geometry import selection
from .obstacles import add_obstacles
from .magnetisation import pattern_br
from .physics import material_index, solve_defaults
from .validate import join, make_scale, user_key

__all__ = ["build_problem", "mu0_of"]

def mu0_of(units):
    """Vacuum permeability in a scenario's units: MU0 (SI, Pa) or MU0 * 1e6 (N-mm-MPa)."""
    return MU0 * (1e6 if units == "N-mm-MPa" else 1.0)


def _law(v, spec, mesh, regions):
    """The material law of the validated [material]: one law, or a RegionMaterial of the
    distinct laws of its regions (per-region stiffness needs the default element)."""
    mat, s = spec["material"], spec["solver"]
    kind = MATERIALS[mat.get("law", "isotropic")]
    mats, index = material_index(mat, regions, mesh.n_elements)
    used = np.unique(index)
    stiff = [k for k in kind.keys() if k not in kind.inert]
    try:
        if len({tuple(mats[i].values()) for i in used}) == 1:
            return kind.build(mats[used[0]])
        if len({tuple(mats[i][k] for k in stiff) for i in used}) > 1 and s["element"] != "default":
            v.fail("solver.element", "per-region elastic properties need the default element")
        return RegionMaterial([kind.build(m) for m in mats], index)
    except ScenarioError:
        raise
    except CoreSE3Error as exc:
        v.fail("material", str(exc))
    except ValueError as exc:                   # a user's law refusing its values
        v.fail(user_key("material", kind, exc), f"{kind.name}: {exc}")


def build_problem(v, spec, mesh, regions):
    """The Problem of a validated spec (its ``solve_defaults`` are the spec's [solver])."""
    s = spec["solver"]
    law = _law(v, spec, mesh, regions)
    try:
        check_linear_solver(s["linear_solver"])        # ('mumps' without petsc4py: [solver]'s, not [material]'s)
    except OptionError as exc:
        v.fail("solver.linear_solver", str(exc).removeprefix("Problem: "))
    try:
        prob = Problem(mesh, law, element=s["element"], linear_solver=s["linear_solver"])
    except CoreSE3Error as exc:
        v.fail("material", str(exc))
    prob.solve_defaults = solve_defaults(s)
    prob.scenario_parts = dict(fields={}, loads=[])     # what [design] variables refer to by name
    for i, sp in enumerate(spec["supports"]):
        _add_support(v, prob, mesh, sp, f"supports[{i}]")
    for i, ld in enumerate(spec["loads"]):
        key = f"loads[{i}]"
        values = {k: x for k, x in ld.items() if k not in ("type", "scale", "edge", "nodes", "region")}
        if isinstance(ld.get("edge"), list):
            where = list(ld["edge"])              # a union of named lines, each along its own edges
        elif "edge" in ld or "nodes" in ld:
            where = selection(mesh, ld)
            lineage = getattr(mesh, "_lineage", None)
            if lineage is not None and LOADS[ld["type"]].target == "nodes":
                # a force per node acts on the unrefined mesh's nodes of its selection: [mesh]
                # refine must not multiply it by the new nodes of a line
                where = where[where < lineage[0].n_nodes]
                if len(where) == 0:
                    v.fail(key, f"a {ld['type']} load (a force per node) acts on the unrefined mesh's nodes of its "
                                "selection, so that [mesh] refine does not multiply it, and this selection has "
                                "none (its nodes are new nodes of the refinement): select nodes of the unrefined "
                                "mesh, or give the finer mesh itself instead of refine")
            elif lineage is not None and LOADS[ld["type"]].target == "line":
                # a total along a line: the new node on every element edge between two selected
                # nodes joins it, whatever the set's order or pieces (as the supports')
                held = M.carry_held(lineage, where[where < lineage[0].n_nodes])
                where = np.concatenate([where, held[~np.isin(held, where)]])
        else:
            where = regions[ld["region"]] if ld.get("region") else None
        try:
            with warnings.catch_warnings(record=True) as said:
                warnings.simplefilter("always", LoadWarning)
                added = prob.add_load(ld["type"], where, make_scale(ld["scale"]), check=False, **values)
            for w in said:                        # a load that adds nothing, located in the file
                if issubclass(w.category, LoadWarning):
                    v.warn(join(key, "rho") if ld.get("rho") is not None else "material.rho", str(w.message))
                else:
                    warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
            prob.scenario_parts["loads"].append(added)
        except CoreSE3Error as exc:
            param = getattr(exc, "param", None)
            v.fail(join(key, param) if param else key, str(exc))
        except ValueError as exc:               # a user's kind refusing its values
            v.fail(user_key(key, LOADS[ld["type"]], exc), f"{ld['type']}: {exc}")
    _loads_act(v, prob, spec["solver"]["lam_end"], prob.scenario_parts["loads"], "loads")
    if spec["magnets"]:
        _add_magnets(v, prob, spec, mesh, regions)
        _loads_act(v, prob, spec["solver"]["lam_end"], prob.scenario_parts["magnets"], "magnets")
    add_obstacles(v, prob, spec, regions)
    for pr in spec["probes"]:
        prob.add_probe(pr["name"], selection(mesh, pr))
    try:
        prob.check_supports(mesh.g0)
    except SingularSystemError as exc:
        v.fail("supports", str(exc))
    return prob


def _loads_act(v, prob, lam, entries, section):
    """A ScenarioError for a load (or magnet) that acts only on dofs the supports hold: their
    reaction absorbs it and it does nothing (an edge force on the clamped edge).  Each entry's
    loads are evaluated at the reference frames and the final load factor ``lam`` (one that is
    switched off there, or vanishes at the reference, is not checked)."""
    held = prob.constraint_mask()
    g0 = prob.mesh.g0
    for i, built in enumerate(entries):
        f = sum(ld.evaluate(g0, lam, tangent=False).f for ld in built)
        total = float(np.abs(f).max()) if np.size(f) else 0.0
        if total > 0 and float(np.abs(np.where(held, 0.0, f)).max()) <= 1e-14 * total:
            nodes = np.nonzero(np.abs(f).max(1) > 0)[0]
            by = [f"supports[{j}]" for j, s in enumerate(prob.supports) if np.isin(nodes, s.nodes).any()]
            v.fail(f"{section}[{i}]", f"it acts only on dofs that {', '.join(by) or 'the supports'} hold (nodes "
                                  f"{nodes[:6].tolist()}{'...' if len(nodes) > 6 else ''}): their reaction would absorb "
                                  "it and it would do nothing; load other nodes, or free those dofs")


def _add_support(v, prob, mesh, sp, key):
    """One [[supports]] entry, by its kind's build; a conflict with an earlier one (a node moved
    by one and held by the other) names both entries."""
    kind = SUPPORTS[sp["type"]]
    nodes = selection(mesh, sp)
    lineage = getattr(mesh, "_lineage", None)
    values = {k: sp[k] for k in kind.keys()}
    if lineage is not None:
        coarse = nodes[nodes < lineage[0].n_nodes]
        if "region" not in sp:
            # [mesh] refine: the new node between two held nodes of an element edge is held too (a
            # line listed out of order, several lines in one set, a closed loop: not one line in
            # order); a region's nodes are its refined elements' already
            held = M.carry_held(lineage, coarse)
            extra = held[~np.isin(held, nodes)]
            if len(extra) and "nodes" in sp:
                # ids may be points that happen to be neighbours: say what the refinement reads
                v.warn(join(key, "nodes"), f"[mesh] refine: the support also holds {len(extra)} new node(s) between "
                                           "neighbouring ids it holds, read as a line; if these ids are separate "
                                           "points, give the finer mesh itself instead of refine")
            nodes = np.concatenate([nodes, extra])
        # a rotation's default point, the nodes' centroid, is that of the unrefined mesh's nodes:
        # the refined nodes of a curved or graded line would move it at every level
        centroid = mesh.X[coarse].mean(0).tolist() if len(coarse) else None
        if sp["type"] == "rotate" and values.get("point") is None:
            values["point"] = centroid
        if sp["type"] == "prescribed" and isinstance(values.get("rotate"), dict) and values["rotate"].get("point") is None:
            values["rotate"] = dict(values["rotate"], point=centroid)
    counts = len(prob.supports), len(prob.loads)
    try:
        kind.build(prob, nodes, make_scale(sp["scale"]) if kind.moves else None, **values)
        _name_supports(prob, counts, key)
    except CoreSE3Error as exc:
        other = getattr(exc, "other", None)
        msg = str(exc)
        if other is not None:
            msg = msg.replace(f"support {len(prob.supports)} (", f"{key} (").replace(
                f"support {other} (", f"supports[{other}] (")
        v.fail(key, msg)
    except ValueError as exc:                   # a user's kind: its own refusal, named by key
        v.fail(user_key(key, kind, exc), f"{sp['type']}: {exc}")


def _name_supports(prob, counts, key):
    """Name what the entry ``key`` (``supports[i]``) added -- the supports and penalty-spring
    loads past ``counts`` -- by it: its reaction's key in the results (``support_reactions``)."""
    for s in prob.supports[counts[0]:]:
        s.name = key
    for ld in prob.loads[counts[1]:]:
        if getattr(ld, "support_force", False):
            ld.support_name = key


def _frame_br(v, key, m, mesh, elems):
    """The lab B^r (k, 3) of a magnet's ``Br_frame``: its components along the reference directors
    of each element of the selection ``elems`` (None: all), the mean of its nodes' frames.  In-plane
    components are refused where the selection's frames turn by quarter turns across a cut (an
    element edge whose nodes' d1 differ by more than 45 deg about the normal,
    ``mesh.gauge.edge_matching``: a mesh file's default frames on a doubly curved part follow a
    cross field): there the mean of the nodes' frames is no director of any of them (up to 40 deg
    off every node's d1 and d2 on the closed cubed sphere 4 x 4 per face) and d1 jumps by a quarter
    turn from one element to the next -- before, such a magnet was built without a word."""
    from ..mesh.gauge import edge_matching
    sel = np.arange(mesh.n_elements) if elems is None else np.asarray(elems)
    comp = np.asarray(m["Br_frame"], float)
    k = edge_matching(mesh.g0, mesh.edge_nodes) if np.any(comp[:2]) else None
    if k is not None:
        cut = np.isin(mesh.elem_edges[sel], np.flatnonzero(k)).any(1)
        if cut.any():
            e = int(sel[np.argmax(cut)])
            where = f"region {m['region']!r}" if m.get("region") else "the whole shell"
            v.fail(join(key, "Br_frame"),
                   f"Br_frame = {comp.tolist()} has components along d1, d2, but the nodal frames of {where} turn by "
                   f"quarter turns across cuts ({int(cut.sum())} of its elements, e.g. element {e} (nodes "
                   f"{mesh.quads[e].tolist()}), have nodes whose d1 differ by more than 45 deg: a mesh file's default "
                   "frames on a doubly curved shell follow a cross field, docs/ELEMENTS.md 'A mesh file's default "
                   "frames'), so 'along d1' is no single direction there; give Br as a lab vector, a direction = "
                   "\"radial\" or \"tangential\" pattern or a Br_file, or frames whose d1 turns little ([mesh] d1_hint); "
                   "a Br_frame along d3 alone ([0, 0, Br]) is kept")
    R0 = lie.mean_rotation(mesh.g0[mesh.quads[sel], :3, :3])      # (k, 3, 3)
    return np.einsum("kij,j->ki", R0, comp)


def _add_magnets(v, prob, spec, mesh, regions):
    built = {}
    mu0_units = mu0_of(spec["units"])
    for name, f in spec["fields"].items():
        values = {k: x for k, x in f.items() if k not in ("type", "scale")}
        try:
            built[name] = FIELDS[f["type"]].build(values, make_scale(f["scale"]), mu0_units)
        except CoreSE3Error as exc:
            v.fail(join("fields", name), str(exc))
        except ValueError as exc:               # a user's kind refusing its values
            v.fail(user_key(join("fields", name), FIELDS[f["type"]], exc), f"{f['type']}: {exc}")
    prob.scenario_parts["fields"] = built
    for i, m in enumerate(spec["magnets"]):
        key = f"magnets[{i}]"
        elems = regions[m["region"]] if m.get("region") else None
        per = "element"                         # the table a pattern, a Br_file or Br_frame makes
        if "direction" in m or "Br_table" in m:
            Br = pattern_br(m, mesh, elems)
            per = m["Br_table"]["kind"] if "Br_table" in m else per
        elif "Br" in m:
            Br, per = np.asarray(m["Br"], float), None
        else:
            Br = _frame_br(v, key, m, mesh, elems)
        mu0 = m["mu0"] if m["mu0"] is not None else mu0_units
        try:
            with warnings.catch_warnings(record=True) as said:
                warnings.simplefilter("always", LoadWarning)
                added = prob.add_magnetic(Br, built[m["field"]], elements=elems, mu0=mu0, Br_per=per)
        except CoreSE3Error as exc:
            v.fail(key, str(exc))
        for w in said:                            # a magnet that adds nothing (Br = 0), located in the file
            if issubclass(w.category, LoadWarning) and getattr(w.message, "cause", None) == "field":
                _zero_field(v, spec, key, m)
            elif issubclass(w.category, LoadWarning) and getattr(w.message, "cause", None) == "units":
                if spec["units"] not in ("SI", "N-mm-MPa"):       # (those: the plausibility check says it)
                    v.warn(key, str(w.message).split(": ", 1)[1])
            elif issubclass(w.category, LoadWarning) and getattr(w.message, "cause", None) == "field_defect":
                v.warn(join("fields", m["field"]), str(w.message).replace("add_magnetic: ", "", 1))
            elif issubclass(w.category, LoadWarning):
                given = next((k for k in ("Br_frame", "Br_table") if k in m), "Br")
                where = f"region {m['region']!r}" if m.get("region") else "the whole shell"
                v.warn(join(key, "Br_file" if given == "Br_table" else given),
                       f"Br is zero on {where}: the magnet adds no load (a sweep may start at zero); give its "
                       "residual flux density [T], or drop the magnet")
            else:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        prob.scenario_parts.setdefault("magnets", []).append(added if isinstance(added, list) else [added])


def _zero_field(v, spec, key, m):
    """The warning of a magnet whose applied field is zero on it (value and gradient: a B of
    zeros): it adds no load at any load factor, as a zero Br; named at the field's B (its
    ``m``, or the field, for other kinds).  Not where [design] varies the field or its poses set
    it (an optimisation may start at zero)."""
    name = m["field"]
    design = spec.get("design") or {}
    if any(x.get("type") == "field" and x.get("field") == name for x in design.get("variables", [])) or \
            any(name in (p.get("fields") or {}) for p in design.get("poses", [])):
        return
    f = spec["fields"][name]
    given = next((k for k in ("B", "m") if k in f), None)
    where = f"region {m['region']!r}" if m.get("region") else "the whole shell"
    v.warn(join(join("fields", name), given) if given else join("fields", name),
           f"the applied field {name!r} is zero on {where} at every load factor (its value and gradient): "
           f"{key} in it adds no load (a sweep may start at zero); give the field's flux density [T], or drop "
           "the magnet")
