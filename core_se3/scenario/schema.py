"""The scenario sections that are not extension points, declared in the vocabulary of every kind
(``registry.Section`` of ``registry.Param``): the top level, ``[edges.NAME]``,
``[regions.NAME]``, ``[[magnets]]``, ``[[probes]]``, ``[[obstacles]]``' own keys and their
``motion``, ``[solver]``, ``[output]`` and ``[design]`` with its poses and targets' own keys.
The validators of ``scenario/`` read their keys, types and defaults from here; the registries
of the extension points (mesh generators, material laws, supports, loads, fields, obstacles,
design variables and targets) declare the rest.  :func:`schema_tables` gives the Markdown of
all of it (docs/SCENARIOS.md's tables are checked against it) and :func:`describe_kinds` the
text of ``core-se3 kinds``.

Example
-------
>>> OUTPUT.keys()
('dir', 'vtu', 'vtu_every', 'plots', 'picture', 'picture_steps', 'view')
>>> [p.default for p in SOLVER.params if p.name in ("rtol", "max_iter")]
[1e-10, 30]
"""
from __future__ import annotations

from ..design import EQUILIBRIA, METHODS
from ..fem import ELEMENTS
from ..fem.material_kinds import MATERIALS
from ..mesh import BACKENDS  # noqa: F401  (the generators' backends; documented with them)
from ..mesh.generator_kinds import GENERATORS
from ..model import FIELDS, LOADS, OBSTACLES, SUPPORTS
from ..model.contact import MODES
from ..registry import Param, Section
from ..solvers import ArcLengthOptions, NewtonOptions
from ..solvers.options import ITERATIONS, PREDICTORS

__all__ = ["SCENARIO", "EDGE", "REGION", "MAGNET", "PROBE", "OBSTACLE", "MOTION", "SOLVER", "ARCLENGTH",
           "OUTPUT", "DESIGN", "POSE", "TARGET", "SECTIONS", "REGISTRIES", "schema_tables", "describe_kinds",
           "LINEAR_SOLVERS", "PARALLEL_KEYS"]

_NEWTON = NewtonOptions()
_ARC = ArcLengthOptions()
LINEAR_SOLVERS = ("auto", "banded", "mumps", "superlu")
# [solver] keys of a distributed run (mpirun; docs/PARALLEL.md): serial runs ignore them
PARALLEL_KEYS = dict(linear=("mumps", "gamg", "hypre"), partition=("auto", "ptscotch", "parmetis", "rcb"))

SCENARIO = Section("scenario", (
    Param("name", "string", None, doc="used for the default output directory and titles (default: the file name)"),
    Param("description", "string", "", doc=""),
    Param("units", "string", "", doc='"SI", "N-mm-MPa" or "consistent"; required with magnets or gravity'),
    Param("plugins", "list", [], item="string",
          doc="Python files (relative to the scenario) or modules whose kinds the scenario uses"),
    Param("many_turns", "list", [], item="string",
          doc='the angle keys whose more than three turns are meant (no warning), e.g. ["fields.coil.rotate.angle"]'),
    Param("mesh", "table", doc="a generator or a file"), Param("edges", "table", None, doc="named node sets"),
    Param("regions", "table", None, doc="named element sets"), Param("material", "table", doc="the law"),
    Param("fields", "table", None, doc="applied fields by name"), Param("magnets", "any", None, doc="[[magnets]]"),
    Param("supports", "any", None, doc="[[supports]]"), Param("loads", "any", None, doc="[[loads]]"),
    Param("probes", "any", None, doc="[[probes]]"), Param("solver", "table", None, doc="steps and controls"),
    Param("output", "table", None, doc="files"), Param("obstacles", "any", None, doc="[[obstacles]]"),
    Param("design", "table", None, doc="an inverse problem"), Param("sweep", "table", None, doc="values to sweep")),
    doc="the top level of a scenario file")

EDGE = Section("edge", (
    Param("box", "any", None, doc="x, y, z = [lo, hi] (missing: unbounded) and tol: the nodes inside"),
    Param("nodes", "any", None, doc="ids, or {near = [x, y, z]} (the node at each point)")),
    doc="[edges.NAME]: a named node set, exactly one of box or nodes")
REGION = Section("region", (
    Param("box", "any", None, doc="the elements whose centroid lies inside"),
    Param("elements", "any", None, doc="ids")),
    doc="[regions.NAME]: a named element set, exactly one of box or elements")

MAGNET = Section("magnet", (
    Param("Br", "any", None, doc="remanent flux density [T]: a lab vector (or the magnitude of a pattern)"),
    Param("Br_frame", "vector", None, doc="components [T] along the reference directors d1, d2, d3"),
    Param("region", "string", None, doc="its elements (default all)"),
    Param("field", "string", None, doc="the [fields.NAME] it sits in (default the only one)"),
    Param("mu0", "number", None, lo=0.0, lo_open=True, doc="vacuum permeability in the model's units"),
    Param("direction", "string", None, choices=("radial", "tangential"), doc="a pattern about centre and axis"),
    Param("centre", "vector", None, doc="of a pattern (default the origin)"),
    Param("axis", "vector", None, nonzero=True, doc="of a pattern (default z)"),
    Param("Br_axial", "number", None, doc="of a pattern: along the axis [T]"),
    Param("Br_file", "string", None, doc="a CSV table per element or node")),
    doc="[[magnets]]: exactly one of Br, Br_frame or Br_file")

PROBE = Section("probe", (
    Param("name", "string", doc="unique"), Param("edge", "string", None, doc="a line of nodes"),
    Param("nodes", "any", None, doc="ids (or one node)")),
    doc="[[probes]]: the midpoint of a node set, recorded at every step")

MOTION = Section("motion", (
    Param("translate", "vector", None, doc="[length] at load factor 1"),
    Param("axis", "vector", None, nonzero=True, doc="of a rotation"),
    Param("angle", "number", 0.0, doc="[rad] at load factor 1"),
    Param("point", "vector", [0.0, 0.0, 0.0], doc="on the axis"),
    Param("scale", "any", "linear", doc='"linear", "constant" or a table [[lam, s], ...]')),
    doc="the rigid motion of an obstacle with the load factor")
OBSTACLE = Section("obstacle", (
    Param("name", "string", None, doc="unique (default the type)"),
    Param("region", "string", None, doc="the contact elements (default all)"),
    Param("motion", "table", None, doc="translate, axis, angle, point, scale", fields=MOTION.params),
    Param("mode", "string", "al", choices=MODES, doc="augmented Lagrangian or penalty"),
    Param("beta", "number", 1.0, lo=0.0, lo_open=True, doc="penalty factor on the shell's nodal stiffness"),
    Param("eps", "number", None, lo=0.0, lo_open=True, doc="C1 band [length] (default 1e-6 h)"),
    Param("tol", "number", None, lo=0.0, lo_open=True, doc="gap tolerance [length] (default 1e-6 h)"),
    Param("cap_depth", "number", None, lo=0.0, lo_open=True, doc="step cap [length] (default 0.05 h)"),
    Param("side", "string", "auto", choices=("auto", "top", "bottom", "mid"),
          doc="the contact face (mid: the mid-surface, for an edge pressed end-on)"),
    Param("friction", "number", 0.0, lo=0.0, doc="Coulomb's coefficient mu (0: frictionless)"),
    Param("faces", "any", "auto", doc='face samples: the obstacle\'s closest point on each contact face is held out '
          'too; true, false, or "auto" (when the obstacle is curved and smaller than the contact elements)')),
    doc="[[obstacles]]: the keys of every obstacle besides its kind's")


def _option(name, opts, doc, **kw):
    """A [solver] key whose default is the solver options' own (``solvers.options``)."""
    return Param(name, kw.pop("kind", "number"), getattr(opts, name), doc=doc, **kw)


SOLVER = Section("solver", (
    Param("control", "string", "load", choices=("load", "arclength", "linear"),
          doc="load stepping, path following past limit points (`core_se3/solvers/arclength.py`), or linear "
          "analysis: one solve at the reference state, the loads at `lam_end` (`core_se3/solvers/linear.py`)"),
    Param("steps", "integer", 10, lo=1, hi=100_000, doc="equal load-factor steps from 0 to `lam_end`"),
    Param("lam_end", "number", 1.0, doc="final load factor (≠ 0)"),
    Param("load_factors", "any", None, doc="explicit load factors of the steps, e.g. `[0.05, 0.2, 0.5, 1.0]`, moving "
          "strictly one way from 0 (instead of `steps` and `lam_end`; load control)"),
    _option("rtol", _NEWTON, "relative residual tolerance (`core_se3/solvers/convergence.py`)", lo=0.0, lo_open=True, hi=1.0, hi_open=True),
    _option("dtol", _NEWTON, "relative increment tolerance", lo=0.0, lo_open=True, hi=1.0, hi_open=True),
    _option("max_iter", _NEWTON, "Newton iterations per attempt", kind="integer", lo=1, hi=1000),
    _option("max_cutbacks", _NEWTON, "step halvings before a step fails", kind="integer", lo=0, hi=50),
    Param("element", "string", "default", choices=ELEMENTS, doc="a registered element (`seed`: the seed's, no `--resume`)"),
    Param("linear_solver", "string", "auto", choices=LINEAR_SOLVERS, doc="the sparse factorisation"),
    _option("iteration", _NEWTON, "Newton of load control: mixed integration point (the geometric stiffness sees "
            "linearly updated element stresses: large steps converge) or plain; the same converged states",
            kind="string", choices=ITERATIONS),
    _option("predictor", _NEWTON, "start of each step with a prescribed motion: the prescribed nodes moved, the rest "
            "kept, or the Euler predictor (capped by contact: a lifted edge carries the shell along)", kind="string",
            choices=PREDICTORS),
    _option("path_check", _NEWTON, "load control: accept a converged step only if its Newton corrections "
            "contracted; one that grew them may have converged onto another equilibrium and is cut back "
            "(docs/STEPS.md)", kind="bool"),
    _option("limit_check", _NEWTON, "load control: stop at a critical point, naming it: a step that snapped past a "
            "limit point, or a change of the sign of det K (a bifurcation, located to `critical_tol` of the load "
            "factor); false records it in `critical_points` and goes on along the unstable path", kind="bool"),
    _option("critical_tol", _NEWTON, "both controls: the relative accuracy in the load factor to which a critical "
            "point is located (the step that crossed it bisected; load control: with limit_check)", lo=0.0,
            lo_open=True, hi=1.0, hi_open=True),
    _option("max_substeps", _NEWTON, "load control: the most sub-steps into which a step may be split to keep a "
            "prescribed rotation or a turning field within its turn per try; beyond it the run stops naming the "
            "load and its turn", kind="integer", lo=1, hi=10_000_000),
    _option("snap_check", _NEWTON, "load control with contact: a step that moved a node by more than an element "
            "size is solved again in halves (a step that landed elsewhere is cut back); a jump that survives halving "
            "to 1/64 of the step is reported as a snap in `critical_points` (docs/STEPS.md)", kind="bool"),
    _option("friction_check", _NEWTON, "load control with Coulomb friction: an accepted state whose slipping nodes' "
            "friction exceeds the cone by more than `friction_tol` (the hardening's share, which grows with the slip "
            "of the step) is solved again at its load factor (docs/STEPS.md)",
            kind="bool"),
    _option("friction_halving", _NEWTON, "load control with friction: also solve a step over which a node changed its "
            "stick/slip status again in halves, refined until they agree with it to `friction_tol` of the path's "
            "displacement scale (off: its estimate does not shrink with the step on the walkers; docs/STEPS.md)",
            kind="bool"),
    _option("friction_tol", _NEWTON, "load control with friction: the friction check's tolerance, relative to the "
            "largest nodal friction A mu p (the hardening's excess force) and to the path's displacement scale "
            "(a step's halves)", lo=0.0, lo_open=True, hi=1.0, hi_open=True),
    _option("end_check", _NEWTON, "load control: count the negative eigenvalues of the symmetric tangent at the end "
            "of the solve (one factorisation; conservative loads without contact, with limit_check); more than at "
            "the start stops the run naming the step where they rose: an even number crossing zero within a step, "
            "which det K's sign does not show (docs/STEPS.md)", kind="bool"),
    _option("midpoint_probe", _NEWTON, "load control: a converged step that turned a node by more than 0.95 pi, "
            "or passed the load factor where the current stiffness extrapolates to zero (a limit point ahead), is "
            "checked by a step from its start to its midpoint load (one more Newton solve); det K of the other sign "
            "there (a jump over a critical point) or no convergence cuts it back (with limit_check; docs/STEPS.md)",
            kind="bool"),
    _option("refine_check", _NEWTON, "load control: a converged step of more than 7 Newton iterations is solved "
            "again in 4 parts from its start (about 4 more Newton solves); an end more than 1e-6 of the length "
            "scale from the step's (it converged onto another equilibrium) cuts it back (path_check on, no contact; "
            "docs/STEPS.md)", kind="bool"),
    _option("inertia_check", _NEWTON, "load control: count the negative eigenvalues of the symmetric tangent at "
            "every converged step (one more factorisation each; conservative loads only) so that an even number "
            "crossing zero within one step, which leaves the sign of det K, stops the run like a sign change "
            "(docs/STEPS.md)", kind="bool"),
    Param("linear", "string", "mumps", choices=PARALLEL_KEYS["linear"], doc="linear solver of a distributed run"),
    Param("partition", "string", "auto", choices=PARALLEL_KEYS["partition"], doc="partition of a distributed run"),
    Param("petsc", "table", None, doc="free-form PETSc options of a distributed run")),
    doc="[solver]: steps and controls")
ARCLENGTH = Section("arclength", (
    _option("method", _ARC, "cylindrical (crisfield) or normal plane (riks)", kind="string",
            choices=("crisfield", "riks")),
    Param("dlam0", "number", None, doc="load factor of the first predictor (default lam_end / steps)"),
    _option("max_steps", _ARC, "path points", kind="integer", lo=1, hi=100_000),
    _option("psi", _ARC, "weight of the load term", lo=0.0),
    _option("target_iter", _ARC, "iterations the arc length adapts toward", kind="integer", lo=1, hi=100),
    _option("ds_max_factor", _ARC, "largest arc length over the first", lo=1.0),
    _option("stability", _ARC, "count negative pivots, report critical points", kind="bool")),
    doc='[solver] keys of control = "arclength"')

OUTPUT = Section("output", (
    Param("dir", "string", None, doc="output directory, relative to the working directory as --out is (the "
          "scenario's input files are relative to the scenario file; a leading ~ is the home folder); default "
          "out/NAME; --out wins"),
    Param("vtu", "bool", True, doc="VTU series"),
    Param("vtu_every", "integer", 1, lo=1, doc="write every k-th step (and the last)"),
    Param("plots", "bool", True, doc="probes.png"),
    Param("picture", "bool", True, doc="shell.png"),
    Param("picture_steps", "integer", 1, lo=1, hi=50, doc="states drawn in shell.png (> 1: evenly spaced, read from "
          "the VTU files)"),
    Param("view", "any", None, doc="`[elevation, azimuth]` or `[elevation, azimuth, roll]` of the camera [deg] "
          "(default [20, -60])")),
    doc="[output]: files")

DESIGN = Section("design", (
    Param("method", "string", "least_squares", choices=METHODS, doc="the optimiser"),
    Param("max_iter", "integer", 50, lo=1, hi=10_000,
          doc="iterations (least squares: evaluations, rejected trial points included)"),
    Param("tolerance", "number", None, lo=0.0, doc="the largest misfit that counts as reaching the targets (in "
          "each target's unit: length, or degrees for angles)"),
    Param("tol", "number", 1e-12, lo=0.0, lo_open=True, doc="the optimiser's own tolerance"),
    Param("stop_at_tolerance", "bool", False, doc="stop at the first iteration within tolerance"),
    Param("equilibria", "string", "follow", choices=EQUILIBRIA,
          doc='"follow": each evaluation continues from the best point\'s equilibria; "ramp": each solves from the '
              'flat state by load stepping, as `core-se3 run` of the optimised scenario'),
    Param("variables", "any", doc="[[design.variables]]"), Param("poses", "any", None, doc="[[design.poses]]"),
    Param("targets", "any", doc="[[design.targets]]")),
    doc="[design]: an inverse problem on the scenario's shell")
POSE = Section("pose", (
    Param("name", "string", doc="unique"),
    Param("fields", "table", None, doc="field name -> [Bx, By, Bz] held in this pose"),
    Param("lam", "number", 1.0, doc="the load factor of the pose")),
    doc="[[design.poses]]")
TARGET = Section("target", (
    Param("pose", "string", None, doc="default the first pose"),
    Param("probe", "string", None, doc="a [[probes]] name"), Param("node", "integer", None, lo=0, doc="or a node id"),
    Param("components", "any", None, doc="the components compared (default all)"),
    Param("weight", "number", 1.0, lo=0.0, doc="of its misfit"),
    Param("scale", "number", None, lo=0.0, lo_open=True, doc="of its misfit, in the target's unit")),
    doc="[[design.targets]]: the keys of every target besides its kind's")

SECTIONS = (SCENARIO, EDGE, REGION, MAGNET, PROBE, OBSTACLE, MOTION, SOLVER, ARCLENGTH, OUTPUT, DESIGN, POSE,
            TARGET)


def _registries():
    from ..design.kinds import TARGETS, VARIABLES
    return (("[mesh] generator", GENERATORS), ("[material] law", MATERIALS), ("[[supports]] type", SUPPORTS),
            ("[[loads]] type", LOADS), ("[fields.NAME] type", FIELDS), ("[[obstacles]] type", OBSTACLES),
            ("[[design.variables]] type", VARIABLES), ("[[design.targets]] type", TARGETS))


REGISTRIES = _registries


def schema_tables():
    """name -> Markdown table: every section's keys and every registry's kinds (and each kind's
    keys), as docs/SCENARIOS.md shows them.

    Example
    -------
    >>> t = schema_tables()
    >>> t["[[supports]] type"].splitlines()[2]
    '| `clamp` | `edge` or `nodes` or `region` | position and rotation held at their reference values |'
    """
    out = {s.name: s.table() for s in SECTIONS}
    for where, reg in _registries():
        out[where] = reg.table()
        for name, kind in reg.items():
            out[f"{where} = {name}"] = kind.table()
    return out


def describe_kinds(section=None):
    """The text of ``core-se3 kinds [SECTION]``: every registry's kinds and their keys (one
    registry when ``section`` names it: 'loads', 'supports', ...).

    Example
    -------
    >>> print(describe_kinds("supports").splitlines()[1])
      clamp: edge or nodes or region -- position and rotation held at their reference values
    """
    lines = []
    for where, reg in _registries():
        if section and section not in where:
            continue
        lines.append(f"{where} ({reg.what}):")
        for name, kind in reg.items():
            lines.append(f"  {name}: {kind.summary()} -- {getattr(kind, 'doc', '')}")
    return "\n".join(lines)


_BLOCK = "<!-- schema: {} -->"
_END = "<!-- /schema -->"


def update_doc(text):
    """``text`` (docs/SCENARIOS.md) with every block between ``<!-- schema: NAME -->`` and
    ``<!-- /schema -->`` replaced by the table :func:`schema_tables` gives for NAME (a KeyError
    for an unknown NAME): the document's tables are the vocabulary's (tests/test_kind_contracts.py
    checks that the document is up to date; ``python scripts/schema_tables.py`` updates it).

    Example
    -------
    >>> print(update_doc("<!-- schema: output -->\\nold\\n<!-- /schema -->").splitlines()[1])
    | key | value | default | |
    """
    import re
    tables = schema_tables()

    def repl(m):
        return f"{_BLOCK.format(m.group(1))}\n{tables[m.group(1)]}\n{_END}"
    return re.sub(r"<!-- schema: (.+?) -->\n.*?<!-- /schema -->", repl, text, flags=re.S)

