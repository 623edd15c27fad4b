"""Scenario files (TOML): schema, validation before anything runs, and the Problem they describe.

    scn = scenario.load("gripper.toml")      # parse + validate; raises ScenarioError(file, key)
    prob = scn.problem                       # the core_se3.Problem, supports checked
    scn.spec                                 # the validated scenario, defaults filled in

Validation happens in one pass, in file order of dependence: mesh (generator or file) ->
named node sets and element regions -> material -> fields and magnets -> supports -> loads
-> probes -> solver -> output; then the Problem is built and its supports are checked for a
free rigid-body motion.  Every error is a ScenarioError naming the file, the dotted key
(``loads[2].force``) and what was expected.  The schema, with one example per feature, is in
docs/SCENARIOS.md.

Load-factor scaling: every load, prescribed rotation and field carries ``scale``: "linear"
(s = lam, the default), "constant" (s = 1), or a table [[lam0, s0], [lam1, s1], ...] (lam
strictly increasing; linear in between, constant outside).
"""
from __future__ import annotations

import difflib
import hashlib
import json
import math
import os

import numpy as np

from . import mesh as M
from .errors import CoreSE3Error, ScenarioError

try:                                  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:           # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["Scenario", "load", "loads", "from_dict", "dumps", "make_scale", "GENERATORS"]

_REQ = object()
MAX_ELEMENTS = 1_000_000

TOP_KEYS = ("name", "description", "units", "mesh", "edges", "regions", "material", "fields",
            "magnets", "supports", "loads", "probes", "solver", "output")

# generator -> (function, [(parameter, kind)]); kinds: pos (> 0), real, count (int >= 1), angle (> 0)
GENERATORS = {
    "rectangle": (M.rectangle, [("L", "pos"), ("width", "pos"), ("nx", "count"), ("ny", "count"),
                                ("x0", "real?")]),
    "cylinder_arch": (M.cylinder_arch, [("R", "pos"), ("angle", "pos"), ("width", "pos"),
                                        ("nx", "count"), ("ny", "count")]),
    "cylinder_panel": (M.cylinder_panel, [("R", "pos"), ("length", "pos"), ("theta0", "real"),
                                          ("theta1", "real"), ("nt", "count"), ("nl", "count")]),
    "annulus": (M.annulus, [("r_in", "pos"), ("r_out", "pos"), ("angle", "pos"), ("nr", "count"),
                            ("nt", "count")]),
}
MATERIAL_KEYS = ("E", "nu", "h", "shear_factor", "drilling", "rho")
ELASTIC_KEYS = ("E", "nu", "h", "shear_factor", "drilling")
SUPPORT_KEYS = {"clamp": (), "fix": ("dofs",), "rotate": ("axis", "angle", "point", "free", "scale")}
LOAD_KEYS = {
    "edge_force": ("force", "follower", "scale"),
    "edge_moment": ("moment", "follower", "scale"),
    "nodal": ("force", "moment", "follower", "scale"),
    "pressure": ("p", "direction", "follower", "scale", "region"),
    "body_force": ("q", "scale", "region"),
    "gravity": ("g", "rho", "scale", "region"),
}
FIELD_KEYS = {"uniform": ("B", "scale", "rotate"), "gradient": ("B", "G", "x0", "scale"),
              "dipole": ("m", "x0", "scale", "mu0")}
SOLVER_DEFAULTS = dict(steps=10, lam_end=1.0, rtol=1e-10, dtol=1e-10, max_iter=30, max_cutbacks=12,
                       element="default", linear_solver="auto", control="load")
ARCLENGTH_DEFAULTS = dict(method="crisfield", dlam0=None, max_steps=200, psi=0.0, target_iter=5,
                          ds_max_factor=8.0, stability=True)
OUTPUT_DEFAULTS = dict(vtu=True, vtu_every=1, plots=True, picture=True, picture_steps=1, view=None)
# solver keys that do not change the converged states (left out of the --resume fingerprint);
# max_steps only decides where an arc-length path stops, so a resume may raise it
NON_PHYSICAL = ("rtol", "dtol", "max_iter", "max_cutbacks", "linear_solver", "max_steps")


# ----------------------------------------------------------------------------- scaling
def make_scale(spec):
    """Load-factor scaling s(lam) from a validated spec ("linear", "constant" or a table)."""
    if spec == "linear":
        return lambda lam: lam
    if spec == "constant":
        return lambda lam: 1.0
    t = np.asarray(spec, float)
    return lambda lam: float(np.interp(lam, t[:, 0], t[:, 1]))


# ----------------------------------------------------------------------------- validator
def _tname(v):
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, int):
        return "an integer"
    if isinstance(v, float):
        return "a number"
    if isinstance(v, str):
        return "a string"
    if isinstance(v, list):
        return "an array"
    if isinstance(v, dict):
        return "a table"
    return type(v).__name__


def _show(v):
    s = repr(v)
    return s if len(s) <= 60 else s[:57] + "..."


class _V:
    """Typed access to a parsed TOML document; every failure is a ScenarioError(file, key)."""

    def __init__(self, file):
        self.file = file

    def fail(self, key, msg):
        raise ScenarioError(msg, self.file, key)

    def table(self, d, key, allowed, required=()):
        if not isinstance(d, dict):
            self.fail(key, f"expected a table, got {_tname(d)} {_show(d)}")
        for k in d:
            if k not in allowed:
                near = difflib.get_close_matches(str(k), list(allowed), n=1)
                hint = f"; did you mean {near[0]!r}?" if near else ""
                self.fail(_join(key, k), f"unknown key {k!r}{hint} (allowed here: {', '.join(allowed)})")
        for k in required:
            if k not in d:
                self.fail(_join(key, k), "missing required key")
        return d

    def number(self, d, k, key, default=_REQ, lo=None, lo_open=False, hi=None, hi_open=False):
        path = _join(key, k)
        if k not in d:
            if default is _REQ:
                self.fail(path, "missing required key (a number)")
            return default
        v = d[k]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(path, f"expected a number, got {_tname(v)} {_show(v)}")
        v = float(v)
        if not math.isfinite(v):
            self.fail(path, f"expected a finite number, got {v}")
        if lo is not None and (v <= lo if lo_open else v < lo):
            self.fail(path, f"expected a number {'>' if lo_open else '>='} {lo:g}, got {v:g}")
        if hi is not None and (v >= hi if hi_open else v > hi):
            self.fail(path, f"expected a number {'<' if hi_open else '<='} {hi:g}, got {v:g}")
        return v

    def integer(self, d, k, key, default=_REQ, lo=None, hi=None):
        path = _join(key, k)
        if k not in d:
            if default is _REQ:
                self.fail(path, "missing required key (an integer)")
            return default
        v = d[k]
        if isinstance(v, bool) or not isinstance(v, int):
            self.fail(path, f"expected an integer, got {_tname(v)} {_show(v)}")
        if lo is not None and v < lo:
            self.fail(path, f"expected an integer >= {lo}, got {v}")
        if hi is not None and v > hi:
            self.fail(path, f"expected an integer <= {hi}, got {v}")
        return v

    def boolean(self, d, k, key, default=_REQ):
        path = _join(key, k)
        if k not in d:
            if default is _REQ:
                self.fail(path, "missing required key (true or false)")
            return default
        if not isinstance(d[k], bool):
            self.fail(path, f"expected true or false, got {_tname(d[k])} {_show(d[k])}")
        return d[k]

    def string(self, d, k, key, default=_REQ, choices=None):
        path = _join(key, k)
        if k not in d:
            if default is _REQ:
                self.fail(path, "missing required key (a string)" if not choices else
                          f"missing required key (one of {', '.join(map(repr, choices))})")
            return default
        v = d[k]
        if not isinstance(v, str):
            self.fail(path, f"expected a string, got {_tname(v)} {_show(v)}")
        if choices is not None and v not in choices:
            near = difflib.get_close_matches(v, list(choices), n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            self.fail(path, f"unknown value {v!r}{hint} (expected one of {', '.join(map(repr, choices))})")
        return v

    def vector(self, d, k, key, n=3, default=_REQ, nonzero=False):
        path = _join(key, k)
        if k not in d:
            if default is _REQ:
                self.fail(path, f"missing required key (an array of {n} numbers)")
            return default
        v = d[k]
        if (not isinstance(v, list) or len(v) != n
                or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v)):
            self.fail(path, f"expected an array of {n} numbers, got {_tname(v)} {_show(v)}")
        v = [float(x) for x in v]
        if not all(math.isfinite(x) for x in v):
            self.fail(path, f"expected finite numbers, got {v}")
        if nonzero and not any(v):
            self.fail(path, "expected a non-zero vector")
        return v

    def matrix3(self, d, k, key):
        path = _join(key, k)
        v = d.get(k, _REQ)
        if v is _REQ:
            self.fail(path, "missing required key (a 3x3 array of numbers)")
        if not isinstance(v, list) or len(v) != 3:
            self.fail(path, f"expected a 3x3 array of numbers, got {_tname(v)} {_show(v)}")
        return [self.vector({"row": r}, "row", f"{path}[{i}]") for i, r in enumerate(v)]

    def scale(self, d, key, default="linear"):
        path = _join(key, "scale")
        if "scale" not in d:
            return default
        v = d["scale"]
        if isinstance(v, str):
            return self.string(d, "scale", key, choices=("linear", "constant"))
        if not isinstance(v, list) or len(v) < 2:
            self.fail(path, 'expected "linear", "constant" or a table [[lam, s], ...] of at least two '
                            f"points, got {_tname(v)} {_show(v)}")
        rows = [self.vector({"p": r}, "p", f"{path}[{i}]", n=2) for i, r in enumerate(v)]
        lam = [r[0] for r in rows]
        if any(b <= a for a, b in zip(lam, lam[1:])):
            self.fail(path, f"the load factors of a scale table must increase strictly, got {lam}")
        return rows

    def array_of_tables(self, doc, k):
        v = doc.get(k, [])
        if isinstance(v, dict):
            self.fail(k, f"expected an array of tables ([[{k}]]), got a single table ([{k}])")
        if not isinstance(v, list) or any(not isinstance(x, dict) for x in v):
            self.fail(k, f"expected an array of tables ([[{k}]]), got {_tname(v)} {_show(v)}")
        return v

    def names_table(self, doc, k):
        v = doc.get(k, {})
        if not isinstance(v, dict):
            self.fail(k, f"expected a table of named entries ([{k}.NAME]), got {_tname(v)} {_show(v)}")
        for name, t in v.items():
            if not isinstance(t, dict):
                self.fail(_join(k, name), f"expected a table, got {_tname(t)} {_show(t)}")
        return v


def _join(key, k):
    if not key:
        return str(k)
    return f"{key}.{k}"


# ----------------------------------------------------------------------------- scenario
class Scenario:
    """A validated scenario: ``spec`` (normalised, JSON-serialisable), ``mesh``, named node sets
    and element ``regions`` (name -> element ids), the ``problem`` built from it, and the
    ``fingerprint`` of everything that determines the converged states (for --resume)."""

    def __init__(self, spec, mesh, regions, problem, file, fingerprint, raw):
        self.spec = spec
        self.mesh = mesh
        self.regions = regions
        self.problem = problem
        self.file = file
        self.fingerprint = fingerprint
        self.raw = raw

    @property
    def name(self):
        return self.spec["name"]

    @property
    def solver(self):
        return self.spec["solver"]

    @property
    def output(self):
        return self.spec["output"]

    def load_factors(self):
        """The load factors of the requested steps (excluding the initial state lam = 0)."""
        s = self.solver
        if s.get("load_factors") is not None:
            return list(s["load_factors"])
        return [s["lam_end"] * k / s["steps"] for k in range(1, s["steps"] + 1)]

    def run(self, out=None, resume=False, progress=None, **kw):
        from .runner import run
        return run(self, out=out, resume=resume, progress=progress, **kw)


def load(path):
    """Read and validate a scenario file (TOML)."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise ScenarioError(f"cannot read the scenario file: {exc.strerror or exc}", path) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"not UTF-8 text ({exc.reason} at byte {exc.start})", path) from None
    return loads(text, file=path, base_dir=os.path.dirname(os.path.abspath(path)))


def loads(text, file="<string>", base_dir="."):
    """Parse and validate scenario TOML text."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"not valid TOML: {exc}", file) from None
    name = os.path.splitext(os.path.basename(file))[0] if not file.startswith("<") else "scenario"
    return from_dict(doc, file=file, base_dir=base_dir, default_name=name)


def from_dict(doc, file="<dict>", base_dir=".", default_name="scenario"):
    """Validate a scenario given as nested dicts/lists (the parsed TOML) and build its Problem."""
    v = _V(file)
    v.table(doc, "", TOP_KEYS, required=("mesh", "material"))
    spec = {}
    spec["name"] = v.string(doc, "name", "", default=default_name)
    spec["description"] = v.string(doc, "description", "", default="")
    spec["units"] = v.string(doc, "units", "", default="")

    mesh, mspec, file_regions, file_digest = _mesh(v, doc["mesh"], base_dir)
    spec["mesh"] = mspec
    spec["edges"] = _edges(v, doc, mesh)
    regions = _regions(v, doc, mesh, file_regions)
    spec["regions"] = {k: r.tolist() for k, r in regions.items()}
    spec["material"] = _material(v, doc["material"], regions)
    spec["fields"] = _fields(v, doc)
    spec["magnets"] = _magnets(v, doc, regions, spec["fields"])
    spec["supports"] = _supports(v, doc, mesh, regions)
    spec["loads"] = _loads(v, doc, mesh, regions, spec["material"])
    spec["probes"] = _probes(v, doc, mesh)
    spec["solver"] = _solver(v, doc)
    if spec["solver"]["control"] == "arclength":
        for i, sp in enumerate(spec["supports"]):
            if sp["type"] == "rotate":
                v.fail(f"supports[{i}].type", "arc length scales the loads only: a prescribed "
                       'rotation is not supported with control = "arclength"')
    spec["output"] = _output(v, doc)
    problem = _build(v, spec, mesh, regions)
    phys = {k: spec[k] for k in spec if k not in ("output", "description")}
    phys["solver"] = {k: x for k, x in spec["solver"].items() if k not in NON_PHYSICAL}
    blob = json.dumps(phys, sort_keys=True) + (file_digest or "")
    fp = hashlib.sha256(blob.encode()).hexdigest()
    return Scenario(spec, mesh, regions, problem, file, fp, doc)


# ----------------------------------------------------------------------------- sections
def _mesh(v, d, base_dir):
    key = "mesh"
    if not isinstance(d, dict):
        v.fail(key, f"expected a table, got {_tname(d)}")
    if ("generator" in d) == ("file" in d):
        v.fail(key, "give exactly one of 'generator' (" + ", ".join(GENERATORS) + ") or 'file' "
                    "(a mesh meshio reads: Gmsh .msh, .vtu, ...)")
    if "file" in d:
        v.table(d, key, ("file", "d1_hint"))
        fname = v.string(d, "file", key)
        hint = v.vector(d, "d1_hint", key, default=[1.0, 0.0, 0.0], nonzero=True)
        path = fname if os.path.isabs(fname) else os.path.join(base_dir, fname)
        if not os.path.isfile(path):
            v.fail(_join(key, "file"), f"mesh file {fname!r} does not exist (looked for {path})")
        raw, why = _read_meshio(path)
        if raw is None:
            v.fail(_join(key, "file"), f"cannot read mesh file {fname!r}: {why}")
        try:
            mesh = M.from_meshio(raw, d1_hint=hint)
        except CoreSE3Error as exc:
            v.fail(_join(key, "file"), f"bad mesh {fname!r}: {exc}")
        except Exception as exc:      # meshio objects can be malformed in many ways
            v.fail(_join(key, "file"), f"bad mesh {fname!r}: {type(exc).__name__}: {exc}")
        with open(path, "rb") as fh:
            digest = hashlib.sha256(fh.read()).hexdigest()
        return mesh, dict(file=fname, d1_hint=hint), _file_regions(raw), digest
    gen = v.string(d, "generator", key, choices=tuple(GENERATORS))
    fn, params = GENERATORS[gen]
    v.table(d, key, ("generator",) + tuple(p for p, _ in params))
    kw = {}
    for p, kind in params:
        if kind == "count":
            kw[p] = v.integer(d, p, key, lo=1, hi=100_000)
        elif kind == "pos":
            kw[p] = v.number(d, p, key, lo=0.0, lo_open=True)
        elif kind == "real":
            kw[p] = v.number(d, p, key)
        elif kind == "real?":
            if p in d:
                kw[p] = v.number(d, p, key)
    counts = [kw[p] for p, kind in params if kind == "count"]
    if counts[0] * counts[1] > MAX_ELEMENTS:
        v.fail(key, f"{counts[0]} x {counts[1]} elements exceed the limit of {MAX_ELEMENTS}")
    try:
        mesh = fn(**kw)
    except CoreSE3Error as exc:
        v.fail(key, f"{gen}: {exc}")
    return mesh, dict(generator=gen, **kw), {}, None


def _read_meshio(path):
    """(meshio.Mesh, None) or (None, reason).  meshio reports some unreadable files by printing
    and calling sys.exit; both are caught here so that a bad file is an ordinary error."""
    import contextlib
    import io as _io
    import meshio
    buf = _io.StringIO()
    try:
        with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
            raw = meshio.read(path)
        _physical_sets(raw)
        return raw, None
    except (Exception, SystemExit) as exc:
        said = " ".join(buf.getvalue().split())
        what = f"{type(exc).__name__}: {exc}" if not isinstance(exc, SystemExit) else ""
        return None, "; ".join(x for x in (what, said) if x) or "meshio could not read it"


def _physical_sets(raw):
    """Named cell sets from Gmsh physical tags (``gmsh:physical`` cell data and field_data
    name -> [tag, dim]) when the reader left ``cell_sets`` empty (Gmsh 2.2 files)."""
    phys = (raw.cell_data or {}).get("gmsh:physical")
    if raw.cell_sets or phys is None or not raw.field_data:
        return
    dims = {"vertex": 0, "line": 1, "triangle": 2, "quad": 2}
    sets = {}
    for name, fd in raw.field_data.items():
        fd = np.asarray(fd).ravel()
        if len(fd) < 2:
            continue
        tag, dim = int(fd[0]), int(fd[1])
        blocks = [np.nonzero(np.asarray(p) == tag)[0] if dims.get(cb.type) == dim else
                  np.zeros(0, np.int64) for cb, p in zip(raw.cells, phys)]
        if any(len(b) for b in blocks):
            sets[str(name)] = blocks
    raw.cell_sets = sets


def _file_regions(raw):
    """Element sets of quad cells named in the file (e.g. Gmsh physical surfaces), as ids into
    the concatenated quad blocks (the element order of mesh.from_meshio)."""
    out, offset = {}, 0
    offsets = []
    for cb in raw.cells:
        offsets.append(offset if cb.type == "quad" else None)
        if cb.type == "quad":
            offset += len(cb.data)
    for name, blocks in (raw.cell_sets or {}).items():
        ids = []
        for off, blk in zip(offsets, blocks):
            if off is not None and blk is not None and len(blk):
                ids.extend((off + np.asarray(blk, np.int64)).tolist())
        if ids:
            out[str(name)] = np.unique(ids)
    return out


def _box(v, d, key, X, scale):
    """Mask of points X inside the box {x = [lo, hi], y = ..., z = ..., tol} (missing = unbounded)."""
    v.table(d, key, ("x", "y", "z", "tol"))
    tol = v.number(d, "tol", key, default=1e-9 * scale, lo=0.0)
    mask = np.ones(len(X), bool)
    for i, c in enumerate("xyz"):
        if c in d:
            lo, hi = v.vector(d, c, key, n=2)
            if hi < lo:
                v.fail(_join(key, c), f"expected [lo, hi] with lo <= hi, got {[lo, hi]}")
            mask &= (X[:, i] >= lo - tol) & (X[:, i] <= hi + tol)
    return mask


def _edges(v, doc, mesh):
    """User node sets [edges.NAME] box = {...} or nodes = [...] (added to mesh.edges)."""
    out = {}
    scale = float(np.linalg.norm(mesh.X.max(0) - mesh.X.min(0))) or 1.0
    for name, t in v.names_table(doc, "edges").items():
        key = _join("edges", name)
        if name in mesh.edges:
            v.fail(key, f"node set {name!r} is already defined by the mesh")
        v.table(t, key, ("box", "nodes"))
        if ("box" in t) == ("nodes" in t):
            v.fail(key, "give exactly one of 'box' or 'nodes'")
        if "box" in t:
            nodes = np.nonzero(_box(v, t["box"], _join(key, "box"), mesh.X, scale))[0]
            nodes = _order_along(mesh, nodes)
            spec = dict(box=t["box"])
        else:
            nodes = np.asarray(_int_list(v, t, "nodes", key, mesh.n_nodes), np.int64)
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
    order = M._chain([tuple(s) for s in segs.tolist()])
    return order if len(order) == len(nodes) else nodes


def _is_line(mesh, nodes):
    """True if consecutive nodes of the set are joined by mesh edges."""
    if len(nodes) < 2:
        return True
    key = set(map(tuple, np.sort(mesh.edge_nodes, 1).tolist()))
    return all(tuple(sorted((int(a), int(b)))) in key for a, b in zip(nodes[:-1], nodes[1:]))


def _int_list(v, d, k, key, n):
    path = _join(key, k)
    x = d[k]
    if not isinstance(x, list) or not x or any(isinstance(i, bool) or not isinstance(i, int) for i in x):
        v.fail(path, f"expected a non-empty array of integer ids, got {_tname(x)} {_show(x)}")
    bad = [i for i in x if i < 0 or i >= n]
    if bad:
        v.fail(path, f"ids {bad[:5]} do not exist (valid: 0 .. {n - 1})")
    return x


def _regions(v, doc, mesh, file_regions):
    regions = dict(file_regions)
    centroids = mesh.X[mesh.quads].mean(1)
    scale = float(np.linalg.norm(mesh.X.max(0) - mesh.X.min(0))) or 1.0
    for name, t in v.names_table(doc, "regions").items():
        key = _join("regions", name)
        if name in regions:
            v.fail(key, f"region {name!r} is already defined by the mesh file")
        v.table(t, key, ("box", "elements"))
        if ("box" in t) == ("elements" in t):
            v.fail(key, "give exactly one of 'box' (element centroids inside) or 'elements'")
        if "box" in t:
            ids = np.nonzero(_box(v, t["box"], _join(key, "box"), centroids, scale))[0]
        else:
            ids = np.unique(_int_list(v, t, "elements", key, mesh.n_elements))
        if len(ids) == 0:
            v.fail(key, "selects no elements")
        regions[name] = np.asarray(ids, np.int64)
    return regions


def _region_ref(v, d, key, regions):
    """Element ids of d['region'] (None = all elements) and the validated name."""
    if "region" not in d:
        return None, None
    name = v.string(d, "region", key)
    if name not in regions:
        v.fail(_join(key, "region"), f"unknown region {name!r}; defined regions: "
                                     f"{sorted(regions) or 'none'} (see [regions.NAME])")
    return regions[name], name


def _material(v, d, regions):
    key = "material"
    v.table(d, key, MATERIAL_KEYS + ("regions",), required=("E", "nu", "h"))
    out = _material_values(v, d, key, base=None)
    out["regions"] = {}
    reg = d.get("regions", {})
    if not isinstance(reg, dict):
        v.fail(_join(key, "regions"), f"expected a table of [material.regions.NAME], got {_tname(reg)}")
    for name, t in reg.items():
        k2 = _join(_join(key, "regions"), name)
        if name not in regions:
            v.fail(k2, f"unknown region {name!r}; defined regions: {sorted(regions) or 'none'}")
        v.table(t, k2, MATERIAL_KEYS)
        vals = _material_values(v, t, k2, base=out)
        for other in out["regions"]:
            if np.intersect1d(regions[other], regions[name]).size:
                v.fail(k2, f"material regions {other!r} and {name!r} overlap: an element would get "
                           "two materials")
        out["regions"][name] = vals
    return out


def material_index(spec_material, regions, n_elements):
    """(list of property dicts, (m,) index into it): the material of every element."""
    mats = [{k: spec_material[k] for k in MATERIAL_KEYS}]
    index = np.zeros(n_elements, np.int64)
    for name, vals in spec_material["regions"].items():
        vals = {k: vals[k] for k in MATERIAL_KEYS}
        if vals not in mats:
            mats.append(vals)
        index[regions[name]] = mats.index(vals)
    return mats, index


def _material_values(v, d, key, base):
    b = base or {}
    out = {}
    out["E"] = v.number(d, "E", key, default=b.get("E", _REQ), lo=0.0, lo_open=True)
    out["nu"] = v.number(d, "nu", key, default=b.get("nu", _REQ), lo=-1.0, lo_open=True, hi=0.5,
                         hi_open=True)
    out["h"] = v.number(d, "h", key, default=b.get("h", _REQ), lo=0.0, lo_open=True)
    out["shear_factor"] = v.number(d, "shear_factor", key, default=b.get("shear_factor", 1.0),
                                   lo=0.0, lo_open=True)
    out["drilling"] = v.number(d, "drilling", key, default=b.get("drilling", 1.0), lo=0.0)
    out["rho"] = v.number(d, "rho", key, default=b.get("rho", None), lo=0.0)
    return out


def _fields(v, doc):
    out = {}
    for name, t in v.names_table(doc, "fields").items():
        key = _join("fields", name)
        typ = v.string(t, "type", key, choices=tuple(FIELD_KEYS))
        v.table(t, key, ("type",) + FIELD_KEYS[typ])
        f = dict(type=typ, scale=v.scale(t, key))
        if typ == "uniform":
            f["B"] = v.vector(t, "B", key)
            if "rotate" in t:
                k2 = _join(key, "rotate")
                r = v.table(t["rotate"], k2, ("axis", "angle", "start", "end"), required=("axis", "angle"))
                rot = dict(axis=v.vector(r, "axis", k2, nonzero=True), angle=v.number(r, "angle", k2),
                           start=v.number(r, "start", k2, default=0.0),
                           end=v.number(r, "end", k2, default=1.0))
                if rot["end"] <= rot["start"]:
                    v.fail(_join(k2, "end"), f"expected end > start ({rot['start']:g}), got {rot['end']:g}")
                if not any(f["B"]):
                    v.fail(_join(key, "B"), "a rotating field needs a non-zero B (its initial direction)")
                f["rotate"] = rot
        elif typ == "gradient":
            f["B"] = v.vector(t, "B", key)
            f["G"] = v.matrix3(t, "G", key)
            f["x0"] = v.vector(t, "x0", key, default=[0.0, 0.0, 0.0])
        else:
            f["m"] = v.vector(t, "m", key, nonzero=True)
            f["x0"] = v.vector(t, "x0", key)
            f["mu0"] = v.number(t, "mu0", key, default=None, lo=0.0, lo_open=True)
        out[name] = f
    return out


def _magnets(v, doc, regions, fields):
    out = []
    for i, t in enumerate(v.array_of_tables(doc, "magnets")):
        key = f"magnets[{i}]"
        v.table(t, key, ("Br", "Br_frame", "region", "field", "mu0"))
        if ("Br" in t) == ("Br_frame" in t):
            v.fail(key, "give exactly one of 'Br' (lab vector [T]) or 'Br_frame' (components "
                        "[T] along the reference directors d1, d2, d3)")
        m = {}
        if "Br" in t:
            m["Br"] = v.vector(t, "Br", key)
        else:
            m["Br_frame"] = v.vector(t, "Br_frame", key)
        _, m["region"] = _region_ref(v, t, key, regions)
        m["mu0"] = v.number(t, "mu0", key, default=None, lo=0.0, lo_open=True)
        if not fields:
            v.fail(key, "a magnet needs an applied field: define one in [fields.NAME]")
        if "field" in t:
            m["field"] = v.string(t, "field", key, choices=tuple(fields))
        elif len(fields) == 1:
            m["field"] = next(iter(fields))
        else:
            v.fail(_join(key, "field"), f"several fields are defined ({', '.join(fields)}): name one")
        out.append(m)
    if fields and not out:
        v.fail("fields", "fields are defined but no [[magnets]] use them")
    return out


def _nodes_ref(v, t, key, mesh, required=True, regions=None):
    """Validated node selection of a table: 'edge' (a named node set), 'nodes' (ids) or, where
    ``regions`` are given, 'region' (the nodes of a region's elements)."""
    given = [k for k in ("edge", "nodes", "region") if k in t]
    if len(given) > 1:
        v.fail(key, f"give one of 'edge', 'nodes'{' or region' if regions is not None else ''}, "
                    f"not {' and '.join(map(repr, given))}")
    if "region" in t and regions is not None:
        _, name = _region_ref(v, t, key, regions)
        return dict(region=name, nodes=np.unique(mesh.quads[regions[name]]).tolist())
    if "edge" in t:
        name = v.string(t, "edge", key)
        if name not in mesh.edges:
            near = difflib.get_close_matches(name, list(mesh.edges), n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            v.fail(_join(key, "edge"), f"unknown edge {name!r}{hint}; the mesh has: "
                                       f"{', '.join(sorted(mesh.edges)) or 'no named edges'}")
        return dict(edge=name)
    if "nodes" in t:
        return dict(nodes=_int_list(v, t, "nodes", key, mesh.n_nodes))
    if required:
        v.fail(key, "missing the node selection: give 'edge' (a named node set) or 'nodes' (ids)"
               + (" or 'region'" if regions is not None else ""))
    return {}


def _sel(mesh, s):
    return mesh.edges[s["edge"]] if "edge" in s else np.asarray(s["nodes"], np.int64)


def _supports(v, doc, mesh, regions):
    sup = v.array_of_tables(doc, "supports")
    if not sup:
        v.fail("supports", "no supports: the shell could move as a rigid body; add e.g. "
                           '[[supports]] type = "clamp", edge = "x0"')
    out = []
    for i, t in enumerate(sup):
        key = f"supports[{i}]"
        typ = v.string(t, "type", key, choices=tuple(SUPPORT_KEYS))
        v.table(t, key, ("type", "edge", "nodes", "region") + SUPPORT_KEYS[typ])
        s = dict(type=typ, **_nodes_ref(v, t, key, mesh, regions=regions))
        if typ == "fix":
            d = t.get("dofs", None)
            if (not isinstance(d, list) or not d
                    or any(isinstance(x, bool) or not isinstance(x, int) or not 0 <= x <= 5 for x in d)):
                v.fail(_join(key, "dofs"), "expected a non-empty array of dof numbers 0..5 (0-2 "
                                           f"translations along d1..d3, 3-5 rotations), got {_show(d)}")
            s["dofs"] = sorted(set(d))
        elif typ == "rotate":
            s["axis"] = v.vector(t, "axis", key, nonzero=True)
            s["angle"] = v.number(t, "angle", key)
            s["point"] = v.vector(t, "point", key, default=None)
            fr = t.get("free", [])
            if not isinstance(fr, list) or any(x not in ("x", "y", "z") for x in fr):
                v.fail(_join(key, "free"), f'expected an array of lab axes "x", "y", "z", got {_show(fr)}')
            s["free"] = fr
            s["scale"] = v.scale(t, key)
        out.append(s)
    return out


def _loads(v, doc, mesh, regions, material):
    out = []
    for i, t in enumerate(v.array_of_tables(doc, "loads")):
        key = f"loads[{i}]"
        typ = v.string(t, "type", key, choices=tuple(LOAD_KEYS))
        nodal = typ in ("edge_force", "edge_moment", "nodal")
        v.table(t, key, ("type",) + (("edge", "nodes") if nodal else ()) + LOAD_KEYS[typ])
        ld = dict(type=typ, scale=v.scale(t, key))
        if nodal:
            ld.update(_nodes_ref(v, t, key, mesh))
            ld["follower"] = v.boolean(t, "follower", key, default=False)
            if typ != "nodal" and "edge" in ld and not _is_line(mesh, mesh.edges[ld["edge"]]):
                v.fail(_join(key, "edge"), f"node set {ld['edge']!r} is not a line of element edges; "
                                           "an edge load needs one (use type = \"nodal\")")
        if typ == "edge_force":
            ld["force"] = v.vector(t, "force", key)
        elif typ == "edge_moment":
            ld["moment"] = v.vector(t, "moment", key)
        elif typ == "nodal":
            ld["force"] = v.vector(t, "force", key, default=[0.0, 0.0, 0.0])
            ld["moment"] = v.vector(t, "moment", key, default=[0.0, 0.0, 0.0])
            if "force" not in t and "moment" not in t:
                v.fail(key, "a nodal load needs 'force' and/or 'moment'")
        elif typ == "pressure":
            ld["p"] = v.number(t, "p", key)
            ld["follower"] = v.boolean(t, "follower", key, default=False)
            if ld["follower"] and "direction" in t:
                v.fail(_join(key, "direction"), "a follower pressure acts along the current normal; "
                                                "'direction' is only for dead pressure")
            ld["direction"] = v.vector(t, "direction", key, default=[0.0, 0.0, 1.0], nonzero=True)
        elif typ == "body_force":
            ld["q"] = v.vector(t, "q", key)
        elif typ == "gravity":
            ld["g"] = v.vector(t, "g", key, default=[0.0, 0.0, -9.81])
            rho = v.number(t, "rho", key, default=None, lo=0.0)
            if rho is None and material["rho"] is None and not material["regions"]:
                v.fail(_join(key, "rho"), "gravity needs a density: give 'rho' here or in [material]")
            ld["rho"] = rho
        if not nodal:
            _, ld["region"] = _region_ref(v, t, key, regions)
        out.append(ld)
    return out


def _probes(v, doc, mesh):
    out = []
    seen = set()
    for i, t in enumerate(v.array_of_tables(doc, "probes")):
        key = f"probes[{i}]"
        v.table(t, key, ("name", "edge", "nodes"), required=("name",))
        name = v.string(t, "name", key)
        if not name or name in seen:
            v.fail(_join(key, "name"), f"probe names must be unique and non-empty, got {name!r}")
        seen.add(name)
        out.append(dict(name=name, **_nodes_ref(v, t, key, mesh)))
    return out


def _solver(v, doc):
    d = doc.get("solver", {})
    key = "solver"
    v.table(d, key, tuple(SOLVER_DEFAULTS) + ("load_factors",) + tuple(ARCLENGTH_DEFAULTS))
    s = dict(SOLVER_DEFAULTS)
    s["control"] = v.string(d, "control", key, default="load", choices=("load", "arclength"))
    s["steps"] = v.integer(d, "steps", key, default=10, lo=1, hi=100_000)
    s["lam_end"] = v.number(d, "lam_end", key, default=1.0)
    if s["lam_end"] == 0:
        v.fail(_join(key, "lam_end"), "expected a non-zero final load factor, got 0")
    s["rtol"] = v.number(d, "rtol", key, default=1e-10, lo=0.0, lo_open=True, hi=1.0)
    s["dtol"] = v.number(d, "dtol", key, default=1e-10, lo=0.0, lo_open=True, hi=1.0)
    s["max_iter"] = v.integer(d, "max_iter", key, default=30, lo=1, hi=1000)
    s["max_cutbacks"] = v.integer(d, "max_cutbacks", key, default=12, lo=0, hi=50)
    s["element"] = v.string(d, "element", key, default="default", choices=("default", "seed"))
    s["linear_solver"] = v.string(d, "linear_solver", key, default="auto",
                                  choices=("auto", "mumps", "superlu"))
    if s["control"] != "arclength":
        extra = [k for k in ARCLENGTH_DEFAULTS if k in d]
        if extra:
            v.fail(_join(key, extra[0]), 'an arc-length control: only with control = "arclength"')
        if "load_factors" in d:
            both = [k for k in ("steps", "lam_end") if k in d]
            if both:
                v.fail(_join(key, both[0]), "give either load_factors or steps and lam_end, not both")
            s["load_factors"] = _load_factors(v, d["load_factors"], _join(key, "load_factors"))
            s["steps"], s["lam_end"] = len(s["load_factors"]), s["load_factors"][-1]
        return s
    if "load_factors" in d:
        v.fail(_join(key, "load_factors"), 'explicit load factors are for control = "load"; arc length '
                                          "chooses its own (lam_end, dlam0)")
    s["method"] = v.string(d, "method", key, default="crisfield", choices=("crisfield", "riks"))
    s["dlam0"] = v.number(d, "dlam0", key, default=s["lam_end"] / s["steps"])
    if s["dlam0"] == 0 or s["dlam0"] * s["lam_end"] < 0:
        v.fail(_join(key, "dlam0"), f"expected a first load-factor step of the sign of lam_end, got {s['dlam0']:g}")
    s["max_steps"] = v.integer(d, "max_steps", key, default=200, lo=1, hi=100_000)
    s["psi"] = v.number(d, "psi", key, default=0.0, lo=0.0)
    s["target_iter"] = v.integer(d, "target_iter", key, default=5, lo=1, hi=100)
    s["ds_max_factor"] = v.number(d, "ds_max_factor", key, default=8.0, lo=1.0)
    s["stability"] = v.boolean(d, "stability", key, default=True)
    if s["element"] != "default":
        v.fail(_join(key, "element"), "arc length needs the default (path-independent) element")
    return s


def _load_factors(v, x, path):
    """Explicit load factors of the steps: finite, non-zero, strictly monotone from 0."""
    if (not isinstance(x, list) or not x
            or any(isinstance(a, bool) or not isinstance(a, (int, float)) for a in x)):
        v.fail(path, f"expected a non-empty array of numbers, got {_tname(x)} {_show(x)}")
    lam = [float(a) for a in x]
    if not all(math.isfinite(a) for a in lam):
        v.fail(path, f"expected finite load factors, got {lam}")
    steps = np.diff([0.0] + lam)
    if np.any(steps == 0) or np.any(np.sign(steps) != np.sign(steps[0])):
        v.fail(path, "the load factors must move strictly in one direction from 0 (no repeats, no "
                     f"reversals: trace a path that turns back with arc length), got {lam}")
    return lam


def _output(v, doc):
    d = doc.get("output", {})
    key = "output"
    v.table(d, key, tuple(OUTPUT_DEFAULTS) + ("dir",))
    o = {}
    o["dir"] = v.string(d, "dir", key, default=None)
    o["vtu"] = v.boolean(d, "vtu", key, default=True)
    o["vtu_every"] = v.integer(d, "vtu_every", key, default=1, lo=1)
    o["plots"] = v.boolean(d, "plots", key, default=True)
    o["picture"] = v.boolean(d, "picture", key, default=True)
    o["picture_steps"] = v.integer(d, "picture_steps", key, default=1, lo=1, hi=50)
    if o["picture_steps"] > 1 and not o["vtu"]:
        v.fail(_join(key, "picture_steps"), "a picture of several steps is drawn from the VTU files: "
                                            "needs vtu = true")
    if isinstance(d.get("view"), list) and len(d["view"]) == 3:
        o["view"] = v.vector(d, "view", key, n=3)
    else:
        o["view"] = v.vector(d, "view", key, n=2, default=None)
    return o


# ----------------------------------------------------------------------------- building
def _build(v, spec, mesh, regions):
    """The Problem of a validated spec; failures of the core's own checks are keyed too."""
    from .material import Material
    from .problem import Problem
    from .errors import SingularSystemError
    from .solver import check_supports
    from .region_material import RegionMaterial
    mat = spec["material"]
    s = spec["solver"]
    mats, index = material_index(mat, regions, mesh.n_elements)
    elastic = [tuple(m[k] for k in ELASTIC_KEYS) for m in mats]
    try:
        if len(set(elastic[i] for i in np.unique(index))) > 1:
            if s["element"] != "default":
                v.fail("solver.element", "per-region elastic properties need the default element")
            law = RegionMaterial([Material(*e) for e in elastic], index)
        else:
            law = Material(**{k: mat[k] for k in ELASTIC_KEYS})
        prob = Problem(mesh, law, element=s["element"], linear_solver=s["linear_solver"])
    except ScenarioError:
        raise
    except CoreSE3Error as exc:
        v.fail("material", str(exc))
    axes = {"x": 0, "y": 1, "z": 2}
    for i, sp in enumerate(spec["supports"]):
        key = f"supports[{i}]"
        nodes = _sel(mesh, sp)
        try:
            if sp["type"] == "clamp":
                prob.clamp(nodes)
            elif sp["type"] == "fix":
                prob.fix(nodes, sp["dofs"])
            else:
                point = sp["point"] if sp["point"] is not None else mesh.X[nodes].mean(0)
                prob.rotate_edge(nodes, sp["axis"], sp["angle"], point=point,
                                 free=[axes[a] for a in sp["free"]], scale=make_scale(sp["scale"]))
        except CoreSE3Error as exc:
            v.fail(key, str(exc))
    for i, ld in enumerate(spec["loads"]):
        key = f"loads[{i}]"
        sc = make_scale(ld["scale"])
        try:
            _add_load(prob, ld, mesh, regions, mat, sc)
        except CoreSE3Error as exc:
            v.fail(key, str(exc))
    if spec["magnets"]:
        _add_magnets(v, prob, spec, mesh, regions)
    for pr in spec["probes"]:
        prob.add_probe(pr["name"], _sel(mesh, pr))
    try:
        check_supports(prob, mesh.g0)
    except SingularSystemError as exc:
        v.fail("supports", str(exc))
    return prob


def _add_load(prob, ld, mesh, regions, mat, sc):
    typ = ld["type"]
    elems = regions[ld["region"]] if ld.get("region") else None
    if typ == "edge_force":
        prob.add_edge_force(_sel(mesh, ld), ld["force"], follower=ld["follower"], scale=sc)
    elif typ == "edge_moment":
        prob.add_edge_moment(_sel(mesh, ld), ld["moment"], follower=ld["follower"], scale=sc)
    elif typ == "nodal":
        prob.add_nodal_load(_sel(mesh, ld), force=ld["force"], moment=ld["moment"],
                            follower=ld["follower"], scale=sc)
    elif typ == "pressure":
        prob.add_pressure(ld["p"], direction=ld["direction"], follower=ld["follower"], scale=sc,
                          elements=elems)
    elif typ == "body_force":
        prob.add_body_force(ld["q"], scale=sc, elements=elems)
    elif typ == "gravity":
        from .loads import SurfaceLoad
        for rho, h, ids in _densities(ld, mat, regions, mesh, elems):
            if rho == 0 or len(ids) == 0:
                continue
            # rho h g per unit reference area (Problem.add_gravity, with the region's thickness)
            prob.loads.append(SurfaceLoad(mesh, rho * h * np.asarray(ld["g"]), False, ids, sc, "gravity"))


def _densities(ld, mat, regions, mesh, elems):
    """[(rho, h, element ids)] for a gravity load: its own rho or the material's, and the
    thickness, per group of loaded elements that share both."""
    sel = np.arange(mesh.n_elements) if elems is None else np.asarray(elems)
    mats, index = material_index(mat, regions, mesh.n_elements)
    rho = np.array([np.nan if m["rho"] is None else m["rho"] for m in mats])[index[sel]]
    if ld["rho"] is not None:
        rho[:] = ld["rho"]
    h = np.array([m["h"] for m in mats])[index[sel]]
    if np.any(np.isnan(rho)):
        raise ScenarioError("gravity needs a density on every loaded element; some have none "
                            "(give 'rho' in [material] or in the load)")
    out = []
    for r, t in sorted(set(zip(rho.tolist(), h.tolist()))):
        out.append((r, t, sel[(rho == r) & (h == t)]))
    return out


def _add_magnets(v, prob, spec, mesh, regions):
    try:
        from . import fields as F
    except ImportError:
        v.fail("magnets", "magnetic loads need core_se3.fields, which this installation does not have")
    if not hasattr(prob, "add_magnetic"):
        v.fail("magnets", "this version of core_se3.Problem has no add_magnetic")
    built = {}
    for name, f in spec["fields"].items():
        sc = make_scale(f["scale"])
        key = _join("fields", name)
        try:
            if f["type"] == "uniform":
                direction = None
                if "rotate" in f:
                    direction = _rotating_direction(f["B"], f["rotate"])
                built[name] = F.UniformField(f["B"], scale=sc, direction=direction)
            elif f["type"] == "gradient":
                built[name] = F.GradientField(f["B"], f["G"], x0=f["x0"], scale=sc)
            else:
                kw = {} if f["mu0"] is None else {"mu0": f["mu0"]}
                built[name] = F.DipoleField(f["m"], f["x0"], scale=sc, **kw)
        except CoreSE3Error as exc:
            v.fail(key, str(exc))
    for i, m in enumerate(spec["magnets"]):
        key = f"magnets[{i}]"
        elems = regions[m["region"]] if m.get("region") else None
        if "Br" in m:
            Br = np.asarray(m["Br"], float)
        else:
            # components along the reference directors, one lab vector per element of the selection
            sel = np.arange(mesh.n_elements) if elems is None else elems
            R0 = mesh.g0[mesh.quads[sel], :3, :3].mean(1)          # (k, 3, 3) mean reference frame
            U, _, Vt = np.linalg.svd(R0)
            Br = np.einsum("kij,j->ki", U @ Vt, np.asarray(m["Br_frame"], float))
        mu0 = m["mu0"]
        if mu0 is None:
            mu0 = F.MU0 * (1e6 if spec["units"] == "N-mm-MPa" else 1.0)
        try:
            _magnetic_load(prob, mesh, Br, built[m["field"]], elems, mu0, spec["material"], regions)
        except CoreSE3Error as exc:
            v.fail(key, str(exc))


def _magnetic_load(prob, mesh, Br, field, elems, mu0, mat, regions):
    """Problem.add_magnetic, split into groups of equal thickness when h differs per region
    (the magnetisation's loads per unit area are h/mu0 B^r x B^a)."""
    from .magnetics import MagneticLoad, Magnetisation
    sel = np.arange(mesh.n_elements) if elems is None else np.asarray(elems)
    mats, index = material_index(mat, regions, mesh.n_elements)
    h_all = np.array([m["h"] for m in mats])[index]
    if len(np.unique(h_all)) == 1:                   # one thickness: the Problem's own front end
        prob.add_magnetic(Br, field, elements=elems, mu0=mu0)
        return
    h = h_all[sel]
    Br = np.broadcast_to(np.asarray(Br, float), (len(sel), 3))
    for t in np.unique(h):
        part = h == t
        prob.loads.append(MagneticLoad(Magnetisation(mesh, Br[part], float(t), sel[part], mu0), field))


def _rotating_direction(B, rot):
    """direction(lam): B/|B| turned about ``axis`` by angle * clip((lam - start)/(end - start), 0, 1)."""
    from . import se3
    b = np.asarray(B, float) / np.linalg.norm(B)
    axis = np.asarray(rot["axis"], float) / np.linalg.norm(rot["axis"])
    a, s, e = rot["angle"], rot["start"], rot["end"]

    def direction(lam):
        t = min(max((lam - s) / (e - s), 0.0), 1.0)
        return se3.exp_so3(a * t * axis) @ b
    return direction


# ----------------------------------------------------------------------------- writing
def dumps(doc):
    """TOML text of a scenario given as nested dicts/lists (tables, arrays of tables, values)."""
    lines = []
    _dump_table(doc, [], lines)
    return "\n".join(lines).strip() + "\n"


def _dump_key(k):
    k = str(k)
    return k if k and all(c.isalnum() or c in "-_" for c in k) else json.dumps(k)


def _dump_value(x):
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        return repr(float(x))                  # float(): NumPy 2 scalars repr as np.float64(...)
    if isinstance(x, str):
        return json.dumps(x)
    if isinstance(x, (list, tuple)):
        return "[" + ", ".join(_dump_value(y) for y in x) + "]"
    if isinstance(x, dict):
        return "{" + ", ".join(f"{_dump_key(k)} = {_dump_value(y)}" for k, y in x.items()) + "}"
    if isinstance(x, np.generic):
        return _dump_value(x.item())
    raise TypeError(f"cannot write {type(x).__name__} to TOML")


def _dump_table(d, path, lines):
    def is_aot(x):
        return isinstance(x, list) and x and all(isinstance(y, dict) for y in x)
    for k, x in d.items():
        if not isinstance(x, dict) and not is_aot(x):
            lines.append(f"{_dump_key(k)} = {_dump_value(x)}")
    for k, x in d.items():
        if isinstance(x, dict):
            p = path + [_dump_key(k)]
            lines.append("")
            lines.append(f"[{'.'.join(p)}]")
            _dump_table(x, p, lines)
        elif is_aot(x):
            for y in x:
                p = path + [_dump_key(k)]
                lines.append("")
                lines.append(f"[[{'.'.join(p)}]]")
                _dump_table(y, p, lines)
