"""The validated scenario: :func:`load` (a TOML file), :func:`loads` (TOML text),
:func:`from_dict` (parsed documents) and the :class:`Scenario` they return.

Validation happens in one pass, in file order of dependence: mesh (generator or file) ->
named node sets and element regions -> material -> fields and magnets -> supports -> loads
-> probes -> solver -> output; then the Problem is built and its supports are checked for a
free rigid-body motion.  Every error is a ScenarioError naming the file, the dotted key
(``loads[2].force``) and what was expected.  The schema, with one example per feature, is in
docs/SCENARIOS.md.
"""
from __future__ import annotations

import copy
import hashlib
import json
import os
import warnings
from collections import namedtuple

from ..errors import ScenarioError
from .build import build_problem
from .design_section import design_section
from .keys import check_key, repeated_value, split_dotted
from .geometry import edges_section, mesh_section, probes_section, refine_guard, regions_section
from .obstacles import obstacles_section
from ..model import SUPPORTS
from .physics import (NON_PHYSICAL, fields_section, loads_section, magnets_section,
                      material_section, output_section, solver_section, supports_section)
from .units import keyed_angles as _keyed_angles, plausibility, unit_defaults, units_section
from .plugins import load_plugins
from .schema import SCENARIO
from .validate import Validator, make_scale

try:                                  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:           # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["Scenario", "load", "loads", "from_dict", "TOP_KEYS", "split_dotted"]

EXTENSIBLE = ("steps", "lam_end", "load_factors")     # load control: not in the fingerprint
MAX_SCENARIO_BYTES = 16 * 2 ** 20        # a scenario file is text of a few kB; refuse what cannot be one
TOP_KEYS = SCENARIO.keys()

Source = namedtuple("Source", "file raw base_dir default_name strict")
Source.__doc__ = """Where a Scenario comes from and how it was read: file (a path, "<string>" or "<dict>"),
raw (the parsed document), base_dir (of relative paths), default_name, strict (warnings as errors)."""


class Scenario:
    """A validated scenario: ``spec`` (normalised, JSON-serialisable), ``mesh``, named node sets
    and element ``regions`` (name -> element ids), the ``problem`` built from it (whose
    ``solve()`` runs the scenario's own [solver] settings), and the ``fingerprint`` of
    everything that determines the converged states (for --resume).

    Made by :func:`load`, :func:`loads` and :func:`from_dict` (not by hand).  ``name``,
    ``solver`` and ``output`` are the spec's sections; :meth:`load_factors` the requested load
    factors; :meth:`with_overrides` a changed copy; :meth:`run` runs it with output.

    Attributes
    ----------
    spec : dict
        The validated document with every default filled in.
    mesh : core_se3.mesh.Mesh
        The mesh; ``regions``: name -> element ids.
    problem : core_se3.Problem
        The shell problem, supports checked.
    file : str
        The source (a path, ``"<string>"`` or ``"<dict>"``); ``raw``: the parsed document;
        ``base_dir``, ``default_name``, ``strict``: how it was read (the constructor takes these
        five as one :data:`Source`).
    fingerprint : str
        SHA-256 of the physical content (solver tolerances, limits and outputs left out).

    Example
    -------
    >>> scn = loads('''
    ... [mesh]
    ... generator = "rectangle"
    ... L = 10.0
    ... width = 1.0
    ... nx = 8
    ... ny = 1
    ... [material]
    ... E = 1.2e6
    ... nu = 0.0
    ... h = 0.1
    ... [[supports]]
    ... type = "clamp"
    ... edge = "x0"
    ... [[loads]]
    ... type = "edge_force"
    ... edge = "x1"
    ... force = [0.0, 0.0, 0.5]
    ... [solver]
    ... steps = 3
    ... ''')
    >>> len(scn.problem.solve().steps), scn.with_overrides({"solver.steps": 2}).solver["steps"]
    (4, 2)
    """

    def __init__(self, spec, mesh, regions, problem, fingerprint, source):
        self.spec = spec
        self.mesh = mesh
        self.regions = regions
        self.problem = problem
        self.fingerprint = fingerprint
        self.file, self.raw, self.base_dir, self.default_name, self.strict = source
        self.warnings = []            # ScenarioWarning: implausible values (scenario/units.py)
        self.physical = {}            # what the fingerprint hashes (to name a changed key)
        self.mesh_digest = None
        self.numbers = None

    def load_numbers(self):
        """The dimensionless load numbers of the magnets and loads (``scenario.units``), at
        full load; computed once."""
        if self.numbers is None:
            from .units import load_numbers
            self.numbers = load_numbers(self)
        return self.numbers

    @property
    def name(self):
        return self.spec["name"]

    @property
    def solver(self):
        return self.spec["solver"]

    @property
    def output(self):
        return self.spec["output"]

    @property
    def fields(self):
        """name -> the applied Field of [fields.NAME] (the objects the magnets use)."""
        return getattr(self.problem, "scenario_parts", {}).get("fields", {})

    @property
    def load_objects(self):
        """The Load objects of every [[loads]] entry (a list per entry)."""
        return getattr(self.problem, "scenario_parts", {}).get("loads", [])

    def design(self):
        """The :class:`core_se3.design.Design` of the [design] section (ScenarioError without one);
        building it turns the magnets of design regions into the design's own loads.  Each call
        builds it on the scenario's problem as the file gives it: a problem that an earlier design
        changed (its loads, left at that design's values) is built again -- a second design
        on it started from the first's result, and a load variable's multiplier, relative to the
        load it found, was written to optimised.toml as one of the file's load (the gravity sag:
        reached, but `core-se3 run` of the file sagged 11.43 for the design's 5.0)."""
        if "design" not in self.spec:
            raise ScenarioError("the scenario has no [design] section", self.file, "design")
        from .design_section import build_design
        if getattr(self.problem, "design_built", False):
            self.problem = self.with_overrides({}).problem
        design = build_design(self)
        self.problem.design_built = True
        return design

    def load_factors(self):
        """The load factors of the requested steps (excluding the initial state lam = 0)."""
        s = self.solver
        if s["control"] == "linear":
            return [s["lam_end"]]                   # one solve, at the final load factor
        if s.get("load_factors") is not None:
            return list(s["load_factors"])
        return [s["lam_end"] * k / s["steps"] for k in range(1, s["steps"] + 1)]

    def with_overrides(self, overrides):
        """A new Scenario with the dotted keys of ``overrides`` set in the document and validated
        anew: ``{"material.E": 2e6, "fields.coil.B": [0, 0, 0.05], "loads[0].force": [...],
        "solver.steps": 20}`` (a parameter sweep changes one key at a time)."""
        doc = copy.deepcopy(self.raw)
        for key, value in overrides.items():
            check_key(doc, key, self.file)            # a misspelt section or name: did you mean
            _set_dotted(doc, key, value, self.file)
        return from_dict(doc, file=self.file, base_dir=self.base_dir, default_name=self.default_name,
                         strict=self.strict)

    def run(self, out=None, resume=False, progress=None, **kw):
        """Run the scenario with output and checkpoints (``scenario.runner.run``)."""
        from .runner import run
        return run(self, out=out, resume=resume, progress=progress, **kw)



def _refuse_bent_tables(v, spec):
    """Arc length: a load's or field's scale table that bends (``ScaleTable.kinks``) is refused
    naming its key: the load factor is the path's parameter, q = d f_ext / d lam jumps at the
    bend (at a peak it vanishes), and the run failed there naming a limit point or a NaN load
    factor (the snap roof under a table 0 -> 0.6 -> 0, or bent at 0.3)."""
    scaled = [(f"loads[{i}].scale", ld.get("scale")) for i, ld in enumerate(spec["loads"])]
    scaled += [(f"fields.{name}.scale", f.get("scale")) for name, f in spec["fields"].items()]
    for key, sc in scaled:
        kinks = getattr(make_scale(sc), "kinks", ()) if sc is not None else ()
        if kinks:
            v.fail(key, f"the table bends at load factor {kinks[0]:g}: arc length takes the load factor as "
                        "the path's parameter, not as a load history (q = d f_ext / d lam jumps there); give "
                        'a straight scale (two points, "linear" or "constant") with control = "arclength", '
                        'or control = "load" for a load history')


def _set_dotted(doc, key, value, file):
    """Set ``a.b[2].c`` = value in nested dicts/lists (missing tables are created)."""
    parts = split_dotted(key, file)
    node = doc
    for p, nxt in zip(parts[:-1], parts[1:]):
        try:
            if isinstance(p, int):
                node = node[p]
            else:
                node = node.setdefault(p, [] if isinstance(nxt, int) else {})
        except (IndexError, TypeError, AttributeError):
            raise ScenarioError(f"the override key {key!r} does not exist in the scenario", file, key) from None
    try:
        node[parts[-1]] = value
    except (IndexError, TypeError):
        raise ScenarioError(f"the override key {key!r} does not exist in the scenario", file, key) from None


def load(path, strict=False):
    """Read and validate a scenario file (TOML).

    Parameters
    ----------
    path : str or path-like
        The file (UTF-8 TOML, schema in docs/SCENARIOS.md); relative mesh files are found from
        its directory.
    strict : bool, optional
        Make every plausibility warning (``Scenario.warnings``) a ScenarioError.

    Returns
    -------
    Scenario
        Named after the file's stem unless it gives a ``name``.  Every problem is a
        :class:`~core_se3.errors.ScenarioError` naming the file and the key.

    Example
    -------
    >>> import pathlib, tempfile
    >>> from core_se3.scenario import dumps
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "strip.toml"
    >>> _ = path.write_text(dumps({"mesh": {"generator": "rectangle", "L": 1.0, "width": 1.0, "nx": 2, "ny": 1},
    ...                             "material": {"E": 1e3, "nu": 0.0, "h": 0.01},
    ...                             "supports": [{"type": "clamp", "edge": "x0"}]}))
    >>> scn = load(path)
    >>> scn.name, scn.mesh.n_elements, scn.solver["steps"]
    ('strip', 2, 10)
    """
    from ..io import read_input_file
    path = os.fspath(path)
    try:
        os.stat(path)
        data = read_input_file(path, MAX_SCENARIO_BYTES, "a scenario file")
    except ValueError as exc:
        raise ScenarioError(str(exc), path) from None
    except OSError as exc:
        raise ScenarioError(f"cannot read the scenario file: {exc.strerror or exc}", path) from None
    try:
        text = data.decode("utf-8-sig")      # a byte order mark (Windows editors write one) is not TOML's
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"not UTF-8 text ({exc.reason} at byte {exc.start})", path) from None
    return loads(text, file=path, base_dir=os.path.dirname(os.path.abspath(path)), strict=strict)


def loads(text, file="<string>", base_dir=".", strict=False):
    """Parse and validate scenario TOML text.

    Parameters
    ----------
    text : str
        The TOML document.
    file : str, optional
        Its name in messages (and, without a leading '<', the default scenario name).
    base_dir : str, optional
        Directory of relative mesh files.

    Returns
    -------
    Scenario

    Example
    -------
    >>> loads("[mesh")                      # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.ScenarioError: <string>: not valid TOML: ...
    """
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"not valid TOML: {exc}", file) from None
    name = os.path.splitext(os.path.basename(file))[0] if not file.startswith("<") else "scenario"
    return from_dict(doc, file=file, base_dir=base_dir, default_name=name, strict=strict)


def from_dict(doc, file="<dict>", base_dir=".", default_name="scenario", strict=False):
    """Validate a scenario given as nested dicts/lists (the parsed TOML) and build its Problem.

    Parameters
    ----------
    doc : dict
        The document (TOML types: dicts, lists, str, int, float, bool).
    file : str, optional
        Its name in messages; ``base_dir``: directory of relative mesh files.
    default_name : str, optional
        The scenario's name when ``doc`` gives none.

    Returns
    -------
    Scenario

    Example
    -------
    A tolerance does not change the converged states (the fingerprint stays), a modulus does:

    >>> doc = {"mesh": {"generator": "rectangle", "L": 1.0, "width": 1.0, "nx": 2, "ny": 1},
    ...        "material": {"E": 1e3, "nu": 0.0, "h": 0.01}, "supports": [{"type": "clamp", "edge": "x0"}]}
    >>> scn = from_dict(doc)
    >>> [scn.with_overrides({k: v}).fingerprint == scn.fingerprint for k, v in [("solver.rtol", 1e-12), ("material.E", 2e3)]]
    [True, False]
    """
    v = Validator(file, strict=strict)
    v.table(doc, "", TOP_KEYS, required=SCENARIO.required())
    _huge_integers(v, doc)
    plugins = v.param(doc, "", SCENARIO.param("plugins"))
    digests = load_plugins(plugins, base_dir, file)        # the user's kinds, before anything reads a registry
    spec = {}
    spec["name"] = v.string(doc, "name", "", default=default_name)
    spec["description"] = v.string(doc, "description", "", default="")
    spec["units"] = v.string(doc, "units", "", default="")
    spec["many_turns"] = list(v.param(doc, "", SCENARIO.param("many_turns")))

    mesh, mspec, file_digest = _keyed_angles(mesh_section, v, doc["mesh"], base_dir)
    spec["mesh"] = mspec
    spec["edges"] = edges_section(v, doc, mesh)
    regions = regions_section(v, doc, mesh)
    refine_guard(v, doc, mspec.get("refine", 0))
    spec["regions"] = {k: r.tolist() for k, r in regions.items()}
    spec["material"] = material_section(v, doc["material"], regions)
    spec["fields"] = fields_section(v, doc)
    spec["magnets"] = magnets_section(v, doc, regions, spec["fields"], mesh, base_dir)
    spec["supports"] = supports_section(v, doc, mesh, regions)
    spec["loads"] = loads_section(v, doc, mesh, regions)
    unit_defaults(v, doc, spec)                         # gravity's g, a dipole's mu0 in the units
    spec["obstacles"] = obstacles_section(v, doc, regions)
    spec["probes"] = probes_section(v, doc, mesh)
    spec["solver"] = solver_section(v, doc)
    if spec["solver"]["control"] == "arclength":
        for i, sp in enumerate(spec["supports"]):
            if SUPPORTS[sp["type"]].moves:
                v.fail(f"supports[{i}].type", "arc length scales the loads only: a prescribed "
                       'motion is not supported with control = "arclength"')
    if spec["solver"]["control"] == "arclength":
        _refuse_bent_tables(v, spec)
    if spec["solver"]["control"] == "arclength" and spec["obstacles"]:
        v.fail("solver.control", 'contact with [[obstacles]] needs load control (control = "load"): arc '
                                 "length does not update the contact multipliers")
    if spec["solver"]["control"] == "linear" and spec["obstacles"]:
        v.fail("solver.control", 'contact with [[obstacles]] needs load control (control = "load"): a linear '
                                 "analysis would pass through the obstacles")
    spec["output"] = output_section(v, doc)
    design = design_section(v, doc, spec, mesh, regions)
    if design is not None:
        if spec["solver"]["control"] == "linear":
            v.fail("solver.control", 'a [design] optimises the nonlinear equilibrium of its poses (load stepping), '
                                     'so control = "linear" would hold only for the optimised scenario\'s own run, '
                                     'which would then miss the targets: use control = "load" with [design], or '
                                     "remove [design] for a linear analysis")
        spec["design"] = design
    spec["sweep"] = sweep_section(v, doc)
    problem = _keyed_angles(build_problem, v, spec, mesh, regions)
    units_section(v, doc, spec)
    # the name labels the run (results' "scenario", titles, the default out/NAME): no mechanics
    phys = {k: spec[k] for k in spec if k not in ("output", "description", "sweep", "name", "many_turns")}
    phys["magnets"] = [{k: (dict(x, path=None) if k == "Br_table" else x) for k, x in m.items()}
                       for m in spec["magnets"]]          # a table's digest, not where it lies
    phys["solver"] = {k: x for k, x in spec["solver"].items() if k not in NON_PHYSICAL}
    if spec["solver"]["control"] != "arclength":
        # the load factors may grow on --resume (a finished run extended to a higher lam_end);
        # the runner checks that the steps done are the first steps of the new ones
        phys["solver"] = {k: x for k, x in phys["solver"].items() if k not in EXTENSIBLE}
    if plugins:
        spec["plugins"] = list(plugins)
        phys["plugins"] = [list(d) for d in digests]        # a changed plugin changes the states
    blob = json.dumps(phys, sort_keys=True) + (file_digest or "")
    fp = hashlib.sha256(blob.encode()).hexdigest()
    scn = Scenario(spec, mesh, regions, problem, fp, Source(file, doc, base_dir, default_name, strict))
    # a checkpoint of a version that hashed the name too (same scenario, same name) still resumes
    scn.named_fingerprint = hashlib.sha256((json.dumps(dict(phys, name=spec["name"]), sort_keys=True)
                                            + (file_digest or "")).encode()).hexdigest()
    scn.physical = json.loads(json.dumps(phys))
    scn.mesh_digest = file_digest
    plausibility(v, scn)
    scn.warnings = v.warnings
    for w in scn.warnings:
        warnings.warn(w, stacklevel=2)
    return scn


def _huge_integers(v, doc, key=""):
    """A ScenarioError at the first integer beyond TOML's 64-bit ones: Python's TOML reader keeps
    any length, and ``E = 1`` followed by 400 zeros stopped every command with a bare
    'OverflowError: int too large to convert to float'."""
    items = doc.items() if isinstance(doc, dict) else enumerate(doc)
    for k, x in items:
        here = f"{key}[{k}]" if isinstance(k, int) else (f"{key}.{k}" if key else str(k))
        if isinstance(x, (dict, list)):
            _huge_integers(v, x, here)
        elif isinstance(x, int) and not isinstance(x, bool) and not -2 ** 63 <= x < 2 ** 63:
            v.fail(here, f"an integer of {len(str(abs(x)))} digits, beyond TOML's 64-bit integers (and any "
                         "number this key takes): check the value")


def sweep_section(v, doc):
    """[sweep]: dotted key -> non-empty array of values (``"fields.coil.B[2]" = [0.02, 0.04]``;
    unquoted dotted keys, nested tables, are flattened); every key must exist in the scenario."""
    d = doc.get("sweep", {})
    if not isinstance(d, dict):
        v.fail("sweep", f"expected a table of KEY = [values], got {type(d).__name__}")
    flat = {}

    def walk(t, prefix):
        for k, x in t.items():
            key = f"{prefix}.{k}" if prefix else str(k)
            if isinstance(x, dict):
                walk(x, key)
            else:
                flat[key] = x
    walk(d, "")
    for key, vals in flat.items():
        if not isinstance(vals, list) or not vals or any(isinstance(x, dict) for x in vals):
            v.fail(f"sweep.{key}", f"expected a non-empty array of values to sweep, got {vals!r}")
        if repeated_value(vals):
            v.fail(f"sweep.{key}", repeated_value(vals))
        try:
            check_key(doc, key, v.file)
        except ScenarioError as exc:
            v.fail(f"sweep.{key}", exc.detail)
    return flat
