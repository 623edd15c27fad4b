"""``core-se3 design FILE.toml --out DIR``: optimise a scenario's [design] and write

* ``optimised.toml`` (one pose) or ``optimised_<pose>.toml``: the scenario with the design's
  values (fields, magnets per design region, material regions, load magnitudes) and without its
  [design] section -- ``core-se3 run`` reproduces the design's state;
* ``design.json``: the result (variables, objective, gradient, misfits, history, every pose's
  targets and achieved values: angles in degrees, as the targets give them; the components'
  ``units``, an angle of a polar form in rad, also in degrees in ``angles_deg``);
* ``convergence.png``: objective and gradient norm per iteration;
* ``target_<pose>.png``: the achieved shape with the targets and the achieved points;
* ``vtu/<pose>/``: the VTU series of the final design's load path from the flat state, written as a
  run writes its steps (each step's contact fields, stress resultants, FieldData, obstacles).
"""
from __future__ import annotations

import copy
import os
from types import SimpleNamespace

import numpy as np

from ..design import FieldVariable
from ..errors import ScenarioError
from ..io import atomic_path, write_json_atomic
from ..io.plots import new_figure, save_figure
from .build import mu0_of
from .design_section import AngleInDegrees
from .outputs import physical_record
from .toml_writer import dumps

__all__ = ["run_design", "optimised_document", "DESIGN_FILES"]

# the names a design writes (a foreign file of such a name is never overwritten)
DESIGN_FILES = ("optimised*.toml", "design.json", "convergence.png", "target_*.png", "vtu/*/step_*.vtu", "vtu/*/series.pvd",
                "vtu/*/obstacles.pvd")

_LOAD_KEYS = {"edge_force": ("force",), "edge_moment": ("moment",), "nodal": ("force", "moment"), "pressure": ("p",),
              "body_force": ("q",), "gravity": ("g",)}


def _write_field(scn, doc, v):
    names = {id(f): n for n, f in scn.fields.items()}
    doc["fields"][names[id(v.field)]]["B"] = [float(b) for b in v.vector()]


def _write_magnetisation(scn, doc, v):
    names = {id(f): n for n, f in scn.fields.items()}
    union = np.unique(np.concatenate(v.regions))
    kept = []
    for m in doc.get("magnets", []):
        el = scn.regions[m["region"]] if "region" in m else np.arange(scn.mesh.n_elements)
        if not np.all(np.isin(el, union)):
            kept.append(m)
    for name, Br in zip(v.region_names, v.Br()):
        for field in v.fields:                     # the material in each field of its magnets
            m = dict(region=name, Br=[float(b) for b in Br], field=names[id(field)])
            if abs(v.mu0 - mu0_of(scn.spec["units"])) > 1e-15 * v.mu0:
                m["mu0"] = v.mu0
            kept.append(m)
    doc["magnets"] = kept


def _write_material(scn, doc, v):
    mr = doc["material"].setdefault("regions", {})
    for name, val in zip(v.region_names, v.value()):
        mr.setdefault(name, {})[v.prop] = float(val)


def _load_index(scn, v):
    """The index of the [[loads]] entry that built the load of a load variable."""
    return next(j for j, lds in enumerate(scn.load_objects) if any(ld is v.load for ld in lds))


def _write_load(scn, doc, v):
    # the magnitude keys of the load's type, given or at their defaults in the scenario's units
    # (a gravity with the default g: before, an absent key was left out, and the optimised
    # scenario had P = 1)
    j = _load_index(scn, v)
    ld = doc["loads"][j]
    for key in _LOAD_KEYS[ld["type"]]:
        val = ld.get(key, scn.spec["loads"][j].get(key))
        if val is not None:
            ld[key] = (np.asarray(val, float) * v.P).tolist() if isinstance(val, (list, tuple)) else val * v.P


def _check_writable(scn, design):
    """ScenarioError (before optimising) for a variable whose value the optimised scenario
    could not hold: a kind without a writer, a load variable on a load type whose magnitude
    keys are not known here (a plugin's)."""
    for i, v in enumerate(design.variables):
        if writer_of(v) is None:
            raise ScenarioError(f"design variable kind {v.scenario_kind.name!r} gives no write(scn, doc, variable): the "
                                "optimised scenario could not hold its value; give the kind one", scn.file,
                                f"design.variables[{i}].type")
        if writer_of(v) is _write_load:
            j = _load_index(scn, v)
            if scn.raw["loads"][j]["type"] not in _LOAD_KEYS:
                raise ScenarioError(f"a load variable on [[loads]][{j}] of type {scn.raw['loads'][j]['type']!r}: the "
                                    f"optimised scenario can scale only the magnitudes of {', '.join(sorted(_LOAD_KEYS))}",
                                    scn.file, f"design.variables[{i}].load")


# how the built-in kinds write their values into the scenario (a user kind gives its own write)
WRITERS = {"field": _write_field, "magnetisation": _write_magnetisation, "material": _write_material,
           "load": _write_load}


def writer_of(v):
    """write(scn, doc, variable) of a design variable: its kind's own ``write``, the built-in
    kind's, or None (a field a pose holds is written as a field)."""
    kind = getattr(v, "scenario_kind", None)
    if kind is None:
        return _write_field if isinstance(v, FieldVariable) else None
    return kind.write or WRITERS.get(kind.name)


def relocated(doc, base_dir, out_dir):
    """``doc`` with its relative file references (``mesh.file``, ``magnets[i].Br_file``, the
    plugin files) rewritten relative to ``out_dir``, where the optimised scenario is written
    (they are relative to the scenario file's ``base_dir``).

    Example
    -------
    >>> relocated({"mesh": {"file": "grip.msh"}, "plugins": ["k.py", "pkg.mod"]}, "/a/b", "/a/b/out")
    {'mesh': {'file': '../grip.msh'}, 'plugins': ['../k.py', 'pkg.mod']}
    """
    from .plugins import is_file_name

    def moved(f):
        return f if os.path.isabs(f) else os.path.relpath(os.path.join(os.path.abspath(base_dir), f), out_dir)
    if isinstance(doc.get("mesh"), dict) and isinstance(doc["mesh"].get("file"), str):
        doc["mesh"]["file"] = moved(doc["mesh"]["file"])
    for m in doc.get("magnets", []):
        if isinstance(m.get("Br_file"), str):
            m["Br_file"] = moved(m["Br_file"])
    if doc.get("plugins"):
        doc["plugins"] = [moved(f) if isinstance(f, str) and is_file_name(f) else f for f in doc["plugins"]]
    return doc


def optimised_document(scn, design, result, k):
    """The scenario document (dicts) of pose k at the design's values, without [design].

    Example
    -------
    See tests/test_design_scenario.py.

    >>> sorted(_LOAD_KEYS)[:2]
    ['body_force', 'edge_force']
    """
    doc = copy.deepcopy(scn.raw)
    doc.pop("design", None)
    design.assign_pose(k, result.x)
    for v in design.pose_variables(k):
        writer_of(v)(scn, doc, v)
    doc["name"] = f"{scn.name}-optimised" + (f"-{design.poses[k].name}" if len(design.poses) > 1 else "")
    return doc


def designed_spec(scn, design, result, k):
    """The validated spec of pose k with the design's field and load values (their writers,
    :func:`optimised_document`'s, applied to ``scn.spec``): its physical record is the design's."""
    spec = copy.deepcopy(scn.spec)
    design.assign_pose(k, result.x)
    for v in design.pose_variables(k):
        write = writer_of(v)
        if write in (_write_field, _write_load):          # the quantities of the physical record
            write(scn, spec, v)
    return spec


def _convergence_plot(path, history, title):
    it = [h["iteration"] for h in history]
    fig = new_figure((6, 4))
    ax = fig.add_subplot(1, 1, 1)
    ax.semilogy(it, [max(h["objective"], 1e-300) for h in history], "o-", label="objective")
    ax.semilogy(it, [max(h["gradient_norm"], 1e-300) for h in history], "s--", label="|gradient|")
    ax.set_xlabel("design iteration")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    save_figure(fig, path, dpi=110, bbox_inches="tight")
    return path


def _target_plot(path, mesh, g, targets, achieved, title):
    import mpl_toolkits.mplot3d  # noqa: F401  (registers the 3d projection)
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    x = g[:, :3, 3]
    fig = new_figure((6, 5))
    ax = fig.add_subplot(111, projection="3d")
    ax.add_collection3d(Poly3DCollection(x[mesh.quads], facecolor=(0.6, 0.75, 0.9, 0.6), edgecolor="k", linewidth=0.2))
    ax.plot(*mesh.X[mesh.edge_nodes].transpose(2, 0, 1).reshape(3, -1), ",", color="0.7")
    if len(targets):
        t, a = np.array(targets), np.array(achieved)
        ax.scatter(*t.T, color="red", marker="x", s=60, label="target")
        ax.scatter(*a.T, facecolor="none", edgecolor="blue", s=60, label="achieved")
        ax.legend()
    pts = np.vstack([x, mesh.X] + ([np.array(targets)] if len(targets) else []))
    c, r = pts.mean(0), 0.55 * np.ptp(pts, 0).max()
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.set_title(title)
    save_figure(fig, path, dpi=110, bbox_inches="tight")
    return path


def run_design(scn, out=None, method=None, max_iter=None, progress=False, vtu=True, plots=True, force=False):
    """Optimise the [design] of a Scenario and write its outputs in ``out`` (module docstring).

    Parameters: scn (a Scenario with [design]); out (default [output] dir or out/NAME-design,
    the name made safe); method, max_iter (override the section's); progress (one line per
    iteration); vtu, plots; force (write into the directory of an earlier design, deleting only
    its files).  The directory is handled as a run's (``io.rundir``).  Returns: (DesignResult,
    files: kind -> path).

    Example
    -------
    See tests/test_design_scenario.py (the CLI: ``core-se3 design FILE.toml --out DIR``).

    >>> callable(run_design)
    True
    """
    from ..backend import launched_rank
    from .runner import point_fields
    from ..io.rundir import RunDirectory
    from .context import on_root
    from .runner import output_directory
    rd = RunDirectory(output_directory(scn, out, "-design"), "design", DESIGN_FILES)
    on_root(lambda: rd.claim(force=force))
    files = {}
    try:
        return _design(scn, rd, method, max_iter, progress, vtu, plots, files)
    except OSError as exc:           # the files written before it (the CLI says which were, which not)
        exc.written = dict(files)
        raise
    finally:
        rd.release()


def _component_units(scn, design):
    """label -> unit of every component of the design's variables in the scenario's units: an
    angle of a polar form in rad (the optimiser's), a field or B^r in the field unit, a gradient
    in field/length, E in the stress unit, h in the length unit, a load magnitude "1" (the
    multiplier of the load as the scenario gives it)."""
    from .units import UNIT_SYSTEMS
    u = UNIT_SYSTEMS.get(scn.spec.get("units") or "consistent", UNIT_SYSTEMS["consistent"])
    by_kind = {"FieldVariable": u["field"], "RegionMagnetisation": u["field"],
               "FieldGradientVariable": f"{u['field']}/{u['length']}", "LoadMagnitude": "1"}
    out = {}
    for v in design.variables:
        kind = type(v).__name__
        unit = u["stress"] if getattr(v, "prop", None) == "E" else u["length"] if kind == "MaterialVariable" \
            else by_kind.get(kind, "")
        out.update({lab: "rad" if lab.endswith(".angle") else unit for lab in v.labels})
    return out


def _units_document(scn, design, r):
    """The ``units`` of design.json's components and their angles in degrees (``angles_deg``):
    the components are the optimiser's, angles in rad, while the targets' angles are in degrees."""
    units = _component_units(scn, design)
    comps = dict(zip(r.labels, np.asarray(r.x, float).tolist()))
    return dict(units=units, angles_deg={k: float(np.degrees(comps[k])) for k, un in units.items() if un == "rad"})


def _pose_rows(scn, pose, st):
    """The achieved values and misfits of a pose's targets (angles in degrees, as given)."""
    tg, ach, rows = [], [], []
    for t in pose.targets:
        m = t.misfit(scn.problem, st.g, st.lam)
        q = t.quantity.value(scn.problem, st.g, st.lam)
        angle = dict(unit="deg", target=t.quantity.target, achieved=[float(t.quantity.target + q[0])]) \
            if isinstance(t.quantity, AngleInDegrees) else {}
        rows.append(dict(name=t.name, type=type(t.quantity).__name__, misfit=m.tolist(),
                         max_misfit=float(np.abs(m).max()), value=q.tolist(), **angle))
        target = getattr(t.quantity, "target", None)
        if type(t.quantity).__name__ in ("ProbePosition", "NodePosition") and target is not None:
            tg.extend(np.atleast_2d(target).tolist())
            ach.extend((np.atleast_2d(target) + q.reshape(-1, 3)).tolist())
    return tg, ach, rows


def _design(scn, rd, method, max_iter, progress, vtu, plots, files):
    """The design's optimisation and its outputs: each written file is put in ``files`` (kind ->
    path) once written, so a failed write leaves there only the written ones."""
    from ..backend import launched_rank
    from ..io.rundir import safe_name
    from .sinks import write_path_vtu
    ds, out = scn.spec["design"], rd.path
    root = launched_rank() == 0          # under mpirun every rank optimises the same design, rank 0 writes
    design = scn.design()
    _check_writable(scn, design)
    r = design.optimise(method or ds["method"], max_iter=ds["max_iter"] if max_iter is None else max_iter, tol=ds["tol"],
                        tolerance=ds["tolerance"], progress=progress, stop_at_tolerance=ds["stop_at_tolerance"])
    poses_doc = []
    for k, pose in enumerate(design.poses):
        st = r.states[k]
        design.assign_pose(k, r.x)
        tg, ach, rows = _pose_rows(scn, pose, st)
        poses_doc.append(dict(name=pose.name, lam=pose.lam, targets=rows))
        suffix = "" if len(design.poses) == 1 else f"_{safe_name(pose.name)}"
        path = rd.file(f"optimised{suffix}.toml")
        if root:
            with atomic_path(path) as tmp, open(tmp, "w") as fh:
                fh.write(f"# written by core-se3 design from {scn.file}: pose {pose.name!r}\n")
                fh.write(dumps(relocated(optimised_document(scn, design, r, k), scn.base_dir, out)))
        files[f"scenario{suffix}"] = path
        if plots and root:
            files[f"target{suffix}"] = _target_plot(rd.file(f"target{suffix or '_' + safe_name(pose.name)}.png"),
                                                    scn.mesh, st.g, tg, ach,
                                                    f"{scn.name}: pose {pose.name} (x target, o achieved)")
        if vtu:
            design.assign_pose(k, r.x)
            with design.element_check.quiet():                  # a coarse mesh: said once, by the design
                res = scn.problem.solve(lam_end=pose.lam)      # (collective under mpirun)
            if root:                         # each step's own contact state, as a run writes it
                spec = designed_spec(scn, design, r, k)
                files[f"vtu_{pose.name}"] = write_path_vtu(rd, f"vtu/{safe_name(pose.name)}", scn.problem, res.steps,
                                                           lambda lam: physical_record(SimpleNamespace(spec=spec), lam))
    if plots and r.history and root:
        files["convergence"] = _convergence_plot(rd.file("convergence.png"), r.history,
                                                 f"{scn.name}: {r.method}")
    from .provenance import problem_provenance
    doc = dict(schema="core-se3-design v1", scenario=scn.file, name=scn.name,
               result={**r.document(), **_units_document(scn, design, r)}, poses=poses_doc,
               files={k: os.path.relpath(v, out) for k, v in files.items()}, provenance=problem_provenance(scn.problem))
    if root:
        write_json_atomic(rd.file("design.json"), doc)
    files["design"] = rd.file("design.json")
    return r, files
