"""Scenario sections on geometry: [mesh] (a generator or a file), [edges.NAME] (node sets),
[regions.NAME] (element sets), node selections of supports, loads and probes, [[probes]]."""
from __future__ import annotations

import hashlib
import os
import warnings

import numpy as np

from .. import mesh as M
from ..errors import CoreSE3Error, MeshWarning, did_you_mean
from ..io.files import check_input_file, without_contents
from ..mesh.generator_kinds import GENERATORS
from ..model.probes import along_line
from ..registry import Param, Section
from .schema import EDGE, PROBE, REGION
from .validate import Bounds, join, show, tname, user_key

__all__ = ["GENERATORS", "MESH_FILE", "MAX_ELEMENTS", "MAX_REFINE", "mesh_section", "refine_guard", "edges_section", "regions_section",
           "region_ref", "nodes_ref", "selection", "is_line", "probes_section", "renumbered_warning"]

MAX_ELEMENTS = 1_000_000
MAX_MESH_BYTES = 2 ** 30          # 1 GiB: an ASCII Gmsh file of 10^6 quads has about 100 MB
MESH_FILE = Section("mesh file", (
    Param("file", "string", doc="a quad mesh meshio reads (Gmsh .msh 4.1 or 2.2, .vtu, ...), relative to the scenario"),
    Param("d1_hint", "vector", None, nonzero=True,
          doc="d1 is its projection on each node's tangent plane; none: +x on flat and developable parts, along "
              "the mesh's edges on doubly curved ones (domes)"),
    Param("triangles", "string", "error", choices=("error", "split"),
          doc="a quad-dominant mesh: an error, or every cell split into quads")),
    doc="[mesh] from a file")

MAX_REFINE = 6


def mesh_section(v, d, base_dir):
    """(Mesh, spec, file digest) of the [mesh] table: a generator or a file meshio reads, refined
    ``refine`` times (``mesh.refine``: every quad into four, new frames on the SE(3) geodesics)."""
    key = "mesh"
    if not isinstance(d, dict):
        v.fail(key, f"expected a table, got {tname(d)}")
    levels = v.integer(d, "refine", key, default=0, lo=0, hi=MAX_REFINE)
    d = {k: x for k, x in d.items() if k != "refine"}
    mesh, spec, digest = _unrefined_mesh(v, d, base_dir)
    if levels:
        if mesh.n_elements * 4 ** levels > MAX_ELEMENTS:
            v.fail(join(key, "refine"), f"{mesh.n_elements} elements refined {levels} times make "
                                        f"{mesh.n_elements * 4 ** levels}, over the limit of {MAX_ELEMENTS}")
        lineage = M.refine_levels(mesh, levels)
        mesh = lineage[-1]
        # node ids and points of the file are those of the unrefined mesh (node_ids): a line of
        # them gets its new nodes, as the named lines do
        mesh._lineage = lineage
        spec["refine"] = levels
    return mesh, spec, digest


def node_ids(v, t, key, mesh):
    """The node ids of ``t['nodes']`` (ids, or ``{near = ...}`` points), given on the unrefined
    mesh: with [mesh] refine a line of them (consecutive nodes joined by element edges) gets the
    new nodes between them (``mesh.carry_nodes``); points stay points."""
    lineage = getattr(mesh, "_lineage", None)
    base = mesh if lineage is None else lineage[0]
    if isinstance(t["nodes"], dict):
        ids = _near_nodes(v, t["nodes"], key, base)
    else:
        ids = _int_list(v, t, "nodes", key, base.n_nodes)
        renumbered_warning(v, join(key, "nodes"), base, ids)
    return ids if lineage is None else M.carry_nodes(lineage, ids).tolist()


def renumbered_warning(v, path, mesh, ids):
    """Warn at ``path`` when node ``ids`` of a mesh read from a file are not the file's point ids:
    the reader dropped points that no quad uses (``mesh.dropped_points``, e.g. a Gmsh circle's
    centre saved without physical groups) and renumbered the points after them."""
    dropped = getattr(mesh, "dropped_points", None)
    if dropped is None:
        return
    ids = np.asarray(ids, np.int64)
    moved = ids[ids >= dropped[0]]
    if not len(moved):
        return
    k = int(moved[0])
    point = k + int(np.searchsorted(dropped - np.arange(len(dropped)), k, side="right"))
    shown = ", ".join(map(str, dropped[:4].tolist())) + (", ..." if len(dropped) > 4 else "")
    v.warn(path, f"node ids count the mesh's nodes, not the mesh file's points: the file has {len(dropped)} point(s) "
                 f"that no quad uses (point {shown}), dropped on reading, so the points after them are renumbered "
                 f"(node {k} is the file's point {point}, at ({', '.join(f'{c:.6g}' for c in mesh.X[k])})); if the ids come from the file, "
                 "select by position ({near = [x, y, z]}) or by a named group instead")


def refine_guard(v, doc, levels):
    """Refuse what [mesh] refine cannot carry: a magnet's Br_file (values per element or node
    id of the unrefined mesh; the new ids would have none)."""
    if not levels:
        return
    for i, t in enumerate(doc.get("magnets") or []):
        if isinstance(t, dict) and "Br_file" in t:
            v.fail(f"magnets[{i}].Br_file", "a table of Br per element or node id of the unrefined mesh cannot "
                                            "follow [mesh] refine (the new ids have no value): refine the mesh "
                                            "file and its table together, or give Br without a table")


def _unrefined_mesh(v, d, base_dir):
    """(Mesh, spec, file digest) of the [mesh] table without its ``refine``."""
    key = "mesh"
    if ("generator" in d) == ("file" in d):
        v.fail(key, "give exactly one of 'generator' (" + ", ".join(GENERATORS) + ") or 'file' "
                    "(a mesh meshio reads: Gmsh .msh, .vtu, ...)")
    if "file" in d:
        vals = v.section(d, key, MESH_FILE)
        fname, hint, tri = vals["file"], vals["d1_hint"], vals["triangles"]
        path = fname if os.path.isabs(fname) else os.path.join(base_dir, fname)
        if not os.path.exists(path):
            v.fail(join(key, "file"), f"mesh file {fname!r} does not exist (looked for {path})")
        why = check_input_file(path, MAX_MESH_BYTES, "a mesh file")
        if why is not None:
            v.fail(join(key, "file"), why)
        # the reader's warnings (nodes at one point: a cut) become the scenario's, at its key
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", MeshWarning)
            try:
                raw = M.read_meshio(path)
            except CoreSE3Error as exc:
                detail = without_contents(str(exc).split(f"{path!r}: ", 1)[-1], path)
                v.fail(join(key, "file"), f"cannot read mesh file {fname!r}: {detail}")
        try:
            with warnings.catch_warnings(record=True) as later:
                warnings.simplefilter("always", MeshWarning)
                mesh = M.from_meshio(raw, d1_hint=hint, triangles=tri)
            caught += later
        except CoreSE3Error as exc:
            v.fail(join(key, "file"), f"bad mesh {fname!r}: {without_contents(str(exc), path)}")
        except Exception as exc:      # meshio objects can be malformed in many ways
            v.fail(join(key, "file"), f"bad mesh {fname!r}: {type(exc).__name__}: {without_contents(str(exc), path)}")
        for w in caught:
            if issubclass(w.category, MeshWarning):
                v.warn(join(key, "file"), f"{fname}: {w.message}")
            else:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        with open(path, "rb") as fh:
            digest = hashlib.sha256(fh.read()).hexdigest()
        spec = dict(file=fname) if hint is None else dict(file=fname, d1_hint=hint)
        if tri != "error":
            spec["triangles"] = tri
        return mesh, spec, digest
    gen = v.string(d, "generator", key, choices=tuple(GENERATORS))
    kind = GENERATORS[gen]
    values = v.section(d, key, kind, first=("generator",))
    # a missing optional key: the function's own default (which the Param documents)
    kw = {k: x for k, x in values.items() if k in d or kind.param(k).required or k == "backend"}
    if "backend" in kw:
        kw["backend"] = M.resolve_backend(kw["backend"])
    _refuse_too_many(v, key, kind, kw)
    try:
        # the generator's own warnings (a steep grading: errors.MeshWarning) become the
        # scenario's, named by file and key, so that the command line prints them and --strict
        # refuses them
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", MeshWarning)
            mesh = kind.build(**kw)
    except CoreSE3Error as exc:
        # a grading the generator refuses ('grade: ...', 'grading: ...') is named at its key, and
        # a value its message names alone at that key ('angle must be in (0, 2 pi] [rad], got 90':
        # mesh.angle, not [mesh]); the message says the generator once
        msg = str(exc)
        v.fail(join(key, "grade") if "grade" in kw and msg.startswith("grad") else user_key(key, kind, exc),
               msg if msg.startswith(gen) else f"{gen}: {msg}")
    except ValueError as exc:                  # a user's generator
        v.fail(user_key(key, kind, exc), f"{gen}: {exc}")
    for w in caught:
        if issubclass(w.category, MeshWarning):
            v.warn(join(key, "grade") if "grade" in kw else key, f"{gen}: {w.message}")
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return mesh, dict(generator=gen, **kw), None


def _refuse_too_many(v, key, kind, kw):
    """A ScenarioError for a generator's values that make more than MAX_ELEMENTS elements
    (the product of its ``counts``, or its largest ``extent`` over ``size`` squared)."""
    if len(kind.counts) == 2:
        nx, ny = (kw[p] for p in kind.counts)
        if nx * ny > MAX_ELEMENTS:
            v.fail(key, f"{nx} x {ny} elements exceed the limit of {MAX_ELEMENTS}")
    if "size" in kw and kind.extent:
        extent = max(kw[p] for p in kind.extent if p in kw)
        if (extent / kw["size"]) ** 2 > 4 * MAX_ELEMENTS:
            v.fail(join(key, "size"), f"size {kw['size']:g} makes about {(extent / kw['size']) ** 2:.3g} elements "
                                      f"on an outline {extent:g} across, over the limit of {MAX_ELEMENTS}")


def _box(v, d, key, X, scale):
    """Mask of points X inside the box {x = [lo, hi], y = ..., z = ..., tol} (missing = unbounded)."""
    v.table(d, key, ("x", "y", "z", "tol"))
    if not any(c in d for c in "xyz"):
        v.fail(key, "an empty box selects every node (not a line): give x, y and/or z = [lo, hi]")
    tol = v.number(d, "tol", key, default=1e-9 * scale, bounds=Bounds(lo=0.0))
    mask = np.ones(len(X), bool)
    for i, c in enumerate("xyz"):
        if c in d:
            lo, hi = v.vector(d, c, key, n=2)
            if hi < lo:
                v.fail(join(key, c), f"expected [lo, hi] with lo <= hi, got {[lo, hi]}")
            mask &= (X[:, i] >= lo - tol) & (X[:, i] <= hi + tol)
    return mask


def edges_section(v, doc, mesh):
    """User node sets [edges.NAME] box = {...} or nodes = [...] (added to mesh.edges)."""
    out = {}
    scale = mesh.length_scale
    for name, t in v.names_table(doc, "edges").items():
        key = join("edges", name)
        if name in mesh.edges:
            v.fail(key, f"node set {name!r} is already defined by the mesh")
        v.table(t, key, EDGE.keys())
        if ("box" in t) == ("nodes" in t):
            v.fail(key, "give exactly one of 'box' or 'nodes'")
        if "box" in t:
            nodes = np.nonzero(_box(v, t["box"], join(key, "box"), mesh.X, scale))[0]
            nodes = _order_along(mesh, nodes)
            spec = dict(box=t["box"])
        else:
            nodes = np.asarray(node_ids(v, t, key, mesh), np.int64)
            spec = dict(nodes=nodes.tolist())
        if len(nodes) == 0:
            v.fail(key, "selects no nodes")
        mesh.edges[name] = nodes
        out[name] = spec
    return out


def _order_along(mesh, nodes):
    """Order a node set along the mesh edges joining its nodes (unchanged if not a line)."""
    if len(nodes) < 2:
        return nodes
    inset = np.zeros(mesh.n_nodes, bool)
    inset[nodes] = True
    segs = mesh.edge_nodes[inset[mesh.edge_nodes].all(1)]
    if len(segs) == 0:
        return nodes
    order = M.chain_order([tuple(s) for s in segs.tolist()])
    # a line visits every node once (a block of nodes gave a walk that repeats one and skips another)
    return order if sorted(order) == sorted(np.asarray(nodes).tolist()) else nodes


def is_line(mesh, nodes):
    """True if consecutive nodes of the set are joined by mesh edges."""
    if len(nodes) < 2:
        return True
    key = set(map(tuple, np.sort(mesh.edge_nodes, 1).tolist()))
    return all(tuple(sorted((int(a), int(b)))) in key for a, b in zip(nodes[:-1], nodes[1:]))


def _int_list(v, d, k, key, n, what="node"):
    """A non-empty array of existing ids, each once (a node listed three times would carry a
    nodal load three times)."""
    path = join(key, k)
    x = d[k]
    if not isinstance(x, list) or not x or any(isinstance(i, bool) or not isinstance(i, int) for i in x):
        v.fail(path, f"expected a non-empty array of integer ids, got {tname(x)} {show(x)}")
    bad = [i for i in x if i < 0 or i >= n]
    if bad:
        v.fail(path, f"ids {bad[:5]} do not exist (valid: 0 .. {n - 1})")
    ids, counts = np.unique(x, return_counts=True)
    if counts.max() > 1:
        i = int(np.argmax(counts))
        v.fail(path, f"{what} {int(ids[i])} is listed {int(counts[i])} times: list every {what} once")
    return x


def _near_nodes(v, t, key, mesh):
    """``nodes = {near = [x, y, z], tol = ...}`` (or ``near = [[x, y, z], ...]``): the node at each
    point (``Mesh.node_at``: the nearest, within tol)."""
    path = join(key, "nodes")
    v.table(t, path, ("near", "tol"), required=("near",))
    pts = t["near"]
    pts = pts if isinstance(pts, list) and pts and all(isinstance(p, list) for p in pts) else [pts]
    tol = v.number(t, "tol", path, default=None, bounds=Bounds(lo=0.0, lo_open=True))
    out = []
    for i, p in enumerate(pts):
        x = v.vector({"near": p}, "near", path if len(pts) == 1 else f"{path}.near[{i}]")
        try:
            out.append(mesh.node_at(x, tol))
        except CoreSE3Error as exc:
            v.fail(join(path, "near"), str(exc))
    if len(set(out)) != len(out):
        v.fail(join(path, "near"), f"two points find the same node ({out}): give each node once")
    return out


def regions_section(v, doc, mesh):
    """Named element sets: the mesh's (e.g. Gmsh physical surfaces) and [regions.NAME]
    (box of element centroids, or ids), selected on the unrefined mesh: with [mesh] refine
    their descendants (so that every level has the same regions); added to mesh.regions."""
    regions = mesh.regions
    lineage = getattr(mesh, "_lineage", [mesh])
    base, levels = lineage[0], len(lineage) - 1
    centroids = base.X[base.quads].mean(1)
    scale = mesh.length_scale
    for name, t in v.names_table(doc, "regions").items():
        key = join("regions", name)
        if name in regions:
            v.fail(key, f"region {name!r} is already defined by the mesh file")
        v.table(t, key, REGION.keys())
        if ("box" in t) == ("elements" in t):
            v.fail(key, "give exactly one of 'box' (element centroids inside) or 'elements'")
        if "box" in t:
            ids = np.nonzero(_box(v, t["box"], join(key, "box"), centroids, scale))[0]
        else:
            ids = np.unique(_int_list(v, t, "elements", key, base.n_elements, what="element"))
            if getattr(base, "element_numbering", None):
                v.warn(join(key, "elements"), f"{base.element_numbering}; if the ids come from the file (Gmsh shows "
                                              "its tags), select the elements by a physical surface (a region of "
                                              "the file, by name) or a box instead; ids from core_se3's own output "
                                              "(a VTU file's cell ids, a message) are right")
        ids = M.descendants(ids, levels)
        if len(ids) == 0:
            v.fail(key, "selects no elements")
        regions[name] = np.asarray(ids, np.int64)
    return regions


def region_ref(v, d, key, regions):
    """Element ids of d['region'] (None = all elements) and the validated name."""
    if "region" not in d:
        return None, None
    name = v.string(d, "region", key)
    if name not in regions:
        v.fail(join(key, "region"), f"unknown region {name!r}{did_you_mean(name, regions)}; defined "
                                    f"regions: {sorted(regions) or 'none'} (see [regions.NAME])")
    return regions[name], name


def nodes_ref(v, t, key, mesh, required=True, regions=None):
    """Validated node selection of a table: 'edge' (a named node set), 'nodes' (ids) or, where
    ``regions`` are given, 'region' (the nodes of a region's elements)."""
    given = [k for k in ("edge", "nodes", "region") if k in t]
    if len(given) > 1:
        v.fail(key, f"give one of 'edge', 'nodes'{' or region' if regions is not None else ''}, "
                    f"not {' and '.join(map(repr, given))}")
    if "region" in t and regions is not None:
        _, name = region_ref(v, t, key, regions)
        return dict(region=name, nodes=np.unique(mesh.quads[regions[name]]).tolist())
    if "edge" in t:
        name = v.string(t, "edge", key)
        if name not in mesh.edges:
            v.fail(join(key, "edge"), f"unknown edge {name!r}{did_you_mean(name, mesh.edges)}; the mesh has: "
                                       f"{', '.join(sorted(mesh.edges)) or 'no named edges'}")
        return dict(edge=name)
    if "nodes" in t:
        return dict(nodes=node_ids(v, t, key, mesh))
    if required:
        v.fail(key, "missing the node selection: give 'edge' (a named node set) or 'nodes' (ids)"
               + (" or 'region'" if regions is not None else ""))
    return {}


def selection(mesh, s):
    """Node ids of a validated selection (a union of named lines: their nodes, each once)."""
    if isinstance(s.get("edge"), list):
        return np.unique(np.concatenate([mesh.edges[n] for n in s["edge"]]))
    return mesh.edges[s["edge"]] if "edge" in s else np.asarray(s["nodes"], np.int64)


def probes_section(v, doc, mesh):
    out = []
    seen = set()
    for i, t in enumerate(v.array_of_tables(doc, "probes")):
        key = f"probes[{i}]"
        v.table(t, key, PROBE.keys(), required=PROBE.required())
        name = v.string(t, "name", key)
        if not name or name in seen:
            v.fail(join(key, "name"), f"probe names must be unique and non-empty, got {name!r}")
        seen.add(name)
        sel = nodes_ref(v, t, key, mesh)
        if "edge" in sel and not is_line(mesh, mesh.edges[sel["edge"]]):
            v.fail(join(key, "edge"), f"node set {sel['edge']!r} is not a line of element edges, so it has no "
                                      "midpoint to record: select a line (or one node, nodes = [ID])")
        try:
            along_line(mesh, selection(mesh, sel), name)
        except CoreSE3Error as exc:
            v.fail(join(key, next(k for k in ("edge", "nodes", "region") if k in sel)), str(exc))
        out.append(dict(name=name, **sel))
    return out
