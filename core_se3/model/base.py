"""The load extension point: the :class:`Load` base class, what its evaluation returns
(:class:`LoadEvaluation`), and the registry of load kinds (:data:`LOADS`) that the Python API,
scenario files, the catalogue and the docs read.

A load at the frames g (n, 4, 4) and load factor lam gives generalised nodal forces f (n, 6) in
the body frames (left trivialisation, seed eq. E32: a lab force F at a node does (R^T F) . eta_v
of virtual work, a lab moment M does (R^T M) . eta_w) and, for the tangent, the blocks of
-df/d eta along g_i <- g_i exp(eta_i): one (6, 6) block per node and, for loads that couple the
nodes of an element (follower pressure), (4, 4, 6, 6) blocks per element.

A new load kind is one file plus one registry line: a :class:`Load` subclass and
``register_load(LoadKind(name, target, params, build))``.  ``params`` declare the keys a scenario
file may give (their type and default); ``build(problem, nodes_or_elements, scale, **values)``
makes the load.  ``Problem.add_load(kind, where, **values)`` and ``[[loads]] type = "kind"`` in a
scenario file then both work.

Example
-------
>>> from core_se3.model import LOADS
>>> sorted(LOADS)
['body_force', 'edge_force', 'edge_moment', 'gravity', 'nodal', 'pressure']
>>> [p.name for p in LOADS["edge_force"].params]
['force', 'follower']
"""
from __future__ import annotations

import abc
from dataclasses import dataclass, field
from typing import Callable, ClassVar

import numpy as np

from ..errors import LoadError
from ..registry import REQUIRED, Kind, Param, Registry

__all__ = ["Evaluation", "Load", "LoadEvaluation", "conservative_loads", "force_scale_with_loads", "mesh_ids", "overrides", "Param", "LoadKind", "LOADS", "register_load", "load_kind",
           "REQUIRED", "linear_scale", "ScaleTable", "scale_knots", "finite_vector", "param_error", "check_given"]


def conservative_loads(loads):
    """Whether ``loads`` are conservative, judged by their kinds (:attr:`Load.conservative`):
    False when any one is not (a follower force or pressure, a dead moment on the rotations,
    contact, friction), True when every one is, None when some load does not say (a user's).
    Where False, sym K says nothing of stability, however small the tangent's skew part: a dead
    end moment's falls like (h/L)^2 (``solvers.stability.asymmetry``), and the roll-up at h/L
    1e-6 measured under ASYM_TOL, was counted as conservative and stopped on a spurious
    critical point.

    Example
    -------
    >>> from core_se3.model import NodalLoad
    >>> dead = NodalLoad(2, [1], [1.0], force=(0.0, 0.0, 1.0))
    >>> conservative_loads([dead]), conservative_loads([dead, NodalLoad(2, [1], [1.0], moment=(0, 1.0, 0))])
    (True, False)
    """
    said = [getattr(ld, "conservative", None) for ld in loads]
    if any(c is False for c in said):
        return False
    return True if all(c is True for c in said) else None


def linear_scale(lam):
    """The default load-factor programme s(lam) = lam."""
    return lam


class ScaleTable:
    """A piecewise-linear load-factor programme s(lam) through the points (lam_i, s_i), constant
    outside them (a load taken up and back, a field ramped then held).

    Load stepping lands a try on every table point ``knots`` inside a requested step
    (``solvers.newton``): between two points s is linear in lam, so the step checks see the
    load's whole history; a step across a peak would otherwise go from one side of it to the
    other without ever applying it (the hinged roof of examples/snap-roof.toml under a table up
    to 1.35 times its limit load and back, in 3 load steps, ended 'complete' on the unloaded roof).

    Parameters
    ----------
    table : sequence of (float, float)
        The points (lam_i, s_i), lam_i strictly increasing (at least two).

    Example
    -------
    >>> s = ScaleTable([[0.0, 0.0], [0.5, 1.0], [1.0, 0.0]])
    >>> s(0.25), s(0.75), s(2.0), s.knots, s.kinks
    (0.5, 0.5, 0.0, (0.0, 0.5, 1.0), (0.5,))
    """

    def __init__(self, table):
        t = np.asarray(table, float)
        if t.ndim != 2 or t.shape[1] != 2 or len(t) < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t[:, 0]) <= 0):
            raise LoadError(f"a scale table is at least two points [lam, s] with lam finite and strictly increasing, "
                            f"got {np.asarray(table).tolist()!r}")
        self.lam, self.s = t[:, 0].copy(), t[:, 1].copy()
        self.knots = tuple(float(x) for x in self.lam)
        slope = np.diff(self.s) / np.diff(self.lam)
        bend = np.abs(np.diff(slope)) > 1e-12 * np.abs(slope).max(initial=0.0)
        self.kinks = tuple(float(x) for x in self.lam[1:-1][bend])     # inner points where the slope changes

    def __call__(self, lam):
        return float(np.interp(lam, self.lam, self.s))

    def __repr__(self):
        return f"ScaleTable({np.column_stack([self.lam, self.s]).tolist()!r})"


def scale_knots(scale):
    """The load factors where the programme ``scale`` changes slope (a :class:`ScaleTable`'s
    points; none for any other callable, whose kinks are not known)."""
    return tuple(getattr(scale, "knots", ()))


@dataclass
class Evaluation:
    """The discrete equations at one state (g, lam).

    r: residual on the free dofs (nfree,); r_int, f_ext: internal and external generalised
    nodal forces (n, 6), r = (r_int - f_ext) restricted to the free dofs; force_scale: the
    element's round-off scale of r_int; energy: the elastic energy; K: the tangent dr/d eta on
    the free dofs (CSR) when asked for; stress, linearization: a mixed element's stresses at
    this state and what ``Problem.linear_stress`` needs (``fem.Element.mixed``).

    Example
    -------
    At the reference state r_int = 0, so r = -f_ext on the free dofs:

    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> ev = p.evaluate(p.mesh.g0, 1.0)
    >>> float(ev.energy), ev.r.shape, round(float(-ev.r.sum()), 12), ev.K.shape
    (0.0, (24,), 1.0, (24, 24))
    """
    r: np.ndarray
    r_int: np.ndarray
    f_ext: np.ndarray
    force_scale: float
    energy: float
    K: object = None
    stress: np.ndarray | None = None
    linearization: object = None


def mesh_ids(ids, n, what, error=LoadError):
    """``ids`` as an int64 array (k,) of whole numbers 0 <= id < n, else ``error`` naming
    ``what`` (e.g. "load 'nodal': nodes") and the range.  The compiled kernels write a load's
    forces by these ids without bounds checks: an id past the mesh crashed the process (NumPy: a
    bare IndexError), a negative one acted on a node counted from the end (on both backends).

    Example
    -------
    >>> mesh_ids([3, 1], 4, "nodes").tolist()
    [3, 1]
    >>> mesh_ids([3, -1], 4, "load 'nodal': nodes")
    Traceback (most recent call last):
    ...
    core_se3.errors.LoadError: load 'nodal': nodes must be ids 0 ... 3 of the mesh, got -1 ... 3
    """
    raw = np.asarray(ids)
    try:
        out = raw.astype(np.int64).ravel()
        whole = raw.ndim <= 1 and raw.dtype.kind != "b" and np.array_equal(out, raw.ravel())
    except (TypeError, ValueError):
        whole = False
    if not whole:
        raise error(f"{what} must be whole numbers (k,), got {raw.ravel()[:5].tolist()} of shape {raw.shape}")
    if out.size and (out.min() < 0 or out.max() >= n):
        raise error(f"{what} must be ids 0 ... {n - 1} of the mesh, got {out.min()} ... {out.max()}")
    return out


@dataclass
class LoadEvaluation:
    """Generalised nodal forces of one load and the blocks of -df/d eta.

    f: (n, 6) forces (body frames); node_blocks: (n, 6, 6) or None; element_blocks:
    (element ids (k,), blocks (k, 4, 4, 6, 6)) or None.

    Attributes
    ----------
    f : (n, 6) ndarray
        Force [force] and moment [force x length] on every node, body-frame components.
    node_blocks : (n, 6, 6) ndarray or None
        -df_i/d eta_i (None: no load stiffness, e.g. a follower force).
    element_blocks : tuple or None
        (element ids (k,), (k, 4, 4, 6, 6) blocks -df_a/d eta_b) for loads coupling the nodes of
        an element (follower pressure).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3.model import NodalLoad
    >>> ev = NodalLoad(2, [1], [1.0], force=(0.0, 0.0, 3.0)).evaluate(np.broadcast_to(np.eye(4), (2, 4, 4)), 1.0)
    >>> ev.f[1].tolist(), ev.node_blocks.shape, ev.element_blocks
    ([0.0, 0.0, 3.0, 0.0, 0.0, 0.0], (2, 6, 6), None)
    """
    f: np.ndarray
    node_blocks: np.ndarray | None = None
    element_blocks: tuple | None = None

    def checked(self, load, n_nodes, n_elements):
        """This evaluation after checking its shapes against the mesh (``load``: for the
        message); a LoadError naming the load and the shapes otherwise.  A user load's arrays
        of another shape were misread: a force (6,) or blocks (1, 6, 6) broadcast onto every
        node by NumPy, the blocks of the k loaded nodes (k, 6, 6) scattered onto nodes 0..k-1 by
        the compiled backend (NumPy: a bare broadcast error), and element ids past the mesh
        written out of bounds by it (a crash).

        Example
        -------
        >>> import numpy as np
        >>> from core_se3.model import NodalLoad
        >>> LoadEvaluation(np.zeros(6)).checked(NodalLoad(4, [3], [1.0]), 4, 1)
        Traceback (most recent call last):
        ...
        core_se3.errors.LoadError: load 'nodal' (NodalLoad): its evaluate returned f of shape (6,); a LoadEvaluation holds f (n_nodes, 6) = (4, 6) (every node, zero where the load does not act), node_blocks (4, 6, 6) or None, element_blocks (ids (k,) of elements 0..0, blocks (k, 4, 4, 6, 6)) or None
        """
        what = None
        ids = blocks = None
        if np.shape(self.f) != (n_nodes, 6):
            what = f"f of shape {np.shape(self.f)}"
        elif self.node_blocks is not None and np.shape(self.node_blocks) != (n_nodes, 6, 6):
            what = f"node_blocks of shape {np.shape(self.node_blocks)}"
        elif self.element_blocks is not None:
            ids, blocks = self.element_blocks
            ids = np.asarray(ids)
            if ids.ndim != 1 or np.shape(blocks) != (len(ids), 4, 4, 6, 6):
                what = f"element_blocks of shapes {ids.shape} (ids) and {np.shape(blocks)} (blocks)"
            elif len(ids) and (ids.dtype.kind not in "iu" or ids.min() < 0 or ids.max() >= n_elements):
                what = f"element ids {ids.min()} ... {ids.max()} (of dtype {ids.dtype})"
        if what is None:
            return self
        name = getattr(load, "name", None)
        raise LoadError(f"load {name!r} ({type(load).__name__}): its evaluate returned {what}; a LoadEvaluation holds f (n_nodes, 6) = "
                        f"({n_nodes}, 6) (every node, zero where the load does not act), node_blocks ({n_nodes}, 6, 6) "
                        f"or None, element_blocks (ids (k,) of elements 0..{n_elements - 1}, blocks (k, 4, 4, 6, 6)) or "
                        "None")


class Load(abc.ABC):
    """Base class of external loads (and of supports written as loads, e.g. penalty springs).

    Subclasses implement :meth:`evaluate`.  Class attributes say what the solvers may assume:
    ``scales_with_load_factor`` (False for supports such as lab springs: continuation's load
    direction q = df/dlam ignores them), ``approximate_tangent`` (True when the load stiffness
    is a finite-difference approximation), ``translation_invariant`` (True when the load's
    forces do not depend on where the shell is: load stepping then iterates on positions
    relative to the part when every load is so, ``solvers.equations.part_origin``; False here,
    the safe default for a load that reads positions, such as an obstacle or a field gradient).  :meth:`restraint` reports rigid-body restraints
    the load provides (for the support check), :meth:`output_fields` point fields for VTU
    files, :meth:`total` the resultant lab force and moment (for reports).

    Add an instance to a problem with ``Problem.add(load)``; register a kind
    (:func:`register_load`) to make it available by name and in scenario files.

    Loads that are supports (``support_force = True``: the penalty springs of
    ``model.supports``) are reported with the support reactions (``StepResult.reaction_force``),
    not with the applied loads.  Loads that are constraint forces (``constraint_force = True``:
    contact) are reported apart from the applied loads, per load name (``StepResult.contact``), with the scalars of
    :meth:`report`.  ``conservative`` says whether the load derives from a potential (its
    stiffness symmetric at equilibrium, its work path independent): True, False (a follower
    force or pressure, a dead moment on the rotations, contact and friction) or None, not said
    (a user's load: judged by the tangent's symmetry); :func:`conservative_loads` reads it.
    Solver hooks, optional (load-stepped Newton calls a hook only on the loads
    whose class overrides it, see :func:`overrides`; without them its path is unchanged):
    :meth:`limit_increment` caps a Newton increment; :meth:`start_error` refuses the start of a
    try (it is cut back); :meth:`update_multipliers` augments the
    load's multipliers at a converged state and the same load factor is solved again until it
    returns <= 1; :meth:`multipliers` / :meth:`set_multipliers` save and restore them (a failed
    try, a restart point).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> class TipLift(Load):                  # a dead lab force lam (0, 0, 1) on node k
    ...     def __init__(self, n, k):
    ...         self.n, self.k = n, k
    ...     def evaluate(self, g, lam, tangent=True):
    ...         f = np.zeros((self.n, 6))
    ...         f[self.k, :3] = g[self.k, :3, :3].T @ (lam * np.array([0.0, 0.0, 1.0]))
    ...         return LoadEvaluation(f)          # (its load stiffness is left out here)
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> ld = p.add(TipLift(p.mesh.n_nodes, 2))
    >>> p.external(p.mesh.g0, 0.5)[0][2].tolist()
    [0.0, 0.0, 0.5, 0.0, 0.0, 0.0]
    """

    kind: ClassVar[str] = ""
    scales_with_load_factor: ClassVar[bool] = True
    constraint_force: ClassVar[bool] = False
    support_force: ClassVar[bool] = False
    translation_invariant: bool = False
    approximate_tangent: bool = False
    conservative: bool | None = None
    name: str = "load"

    @abc.abstractmethod
    def evaluate(self, g, lam, tangent=True) -> LoadEvaluation:
        """Forces (and blocks if ``tangent``) at frames g (n, 4, 4) and load factor lam."""

    def restraint(self):
        """(nodes (k,), lab unit directions (k, q, 3)) this load holds like a support, or None."""
        return None

    def round_off_scale(self, ell):
        """The size [force] of the terms that cancel in this load's nodal forces (moments / ``ell``),
        whose round-off joins the residual's floor (``solvers.convergence``): a penalty spring
        k (x - X) subtracts two terms of size k |X|.  0.0 here (a load without cancellation)."""
        return 0.0

    def output_fields(self, g, lam):
        """Point fields (name -> (n, k)) for output; none by default."""
        return {}

    def direction_turn(self, g, lam0, lam1):
        """Hook: the largest angle [rad] through which the load's direction turns at the state g
        as the load factor goes from lam0 to lam1 (a rotating applied field); Newton splits a
        try whose turn exceeds ``solvers.newton.MAX_LOAD_TURN``.  0.0 here."""
        return 0.0

    def limit_increment(self, g, eta, lam):
        """Hook: the factor alpha in (0, 1] by which Newton scales the increment eta (n, 6) at
        (g, lam) before applying it (a step cap); 1.0 here."""
        return 1.0

    def start_error(self, g, lam):
        """Hook: why a Newton try must not start from (g, lam) (e.g. a moving obstacle that has
        swept deep into the shell over the increment: the try is cut back), '' if it may."""
        return ""

    def step_error(self, g0, lam0, g1, lam1):
        """Hook: why a converged step from the accepted state (g0, lam0) to (g1, lam1) must not be
        accepted (e.g. the shell passed through an obstacle between the two: the step is cut
        back), '' if it may."""
        return ""

    def active_set_changed(self, g0, lam0, g1, lam1):
        """Hook: True when the load's tangent switched between the states (a contact opened or
        closed): the load-control limit check then takes a new reference stiffness instead of
        calling the jump a limit point.  False here."""
        return False

    def failure_hint(self):
        """Hook: why the last failed Newton try could not converge, from this load's side (e.g.
        every contact node slips: no static equilibrium), or ''.  Named in the error."""
        return ""

    def predict_start(self, g0, lam0, g, lam, fixed):
        """Hook: the start of a Newton try at lam from the accepted state (g0, lam0), given the
        start g so far and the supported dofs fixed (n, 6) (e.g. contact nodes carried with a
        moving obstacle); g here."""
        return g

    def accept_state(self, g, lam):
        """Hook: (g, lam) has been accepted as a step of the path (a path-dependent load moves its
        history on, e.g. friction); nothing here."""

    def update_multipliers(self, g, lam):
        """Hook: at a converged state, the constraint error over its tolerance; when above 1 the
        load has augmented its multipliers and Newton solves the same load factor again.  0.0 here."""
        return 0.0

    def multipliers(self):
        """Hook: a copy of the load's multipliers (its state between solves), None here."""
        return None

    def set_multipliers(self, state=None):
        """Hook: restore :meth:`multipliers` (None: the initial ones); nothing here."""

    def report(self, g, lam):
        """Scalars to report per step for a constraint force (e.g. the penetration); none here."""
        return {}

    def compiled(self, pattern):
        """A compiled evaluation for the numba backend, ``add(g, lam, f, data, tangent)`` adding
        the forces into f (n, 6) and -df/deta into the CSR ``data`` of ``pattern``
        (``kernels.Pattern``); None (the default): the backend calls :meth:`evaluate` and
        scatters its blocks, so every load works with both backends."""
        return None


def overrides(load, hook):
    """True when the class of ``load`` overrides the :class:`Load` method ``hook`` (the solvers
    call the optional hooks only then).

    Example
    -------
    >>> from core_se3.model import NodalLoad, ContactLoad
    >>> overrides(NodalLoad(1, [0], [1.0]), "limit_increment"), ContactLoad.limit_increment is Load.limit_increment
    (False, False)
    """
    return getattr(type(load), hook, None) is not getattr(Load, hook)


@dataclass(frozen=True)
class LoadKind(Kind):
    """A registered load kind.

    target: 'line' (a named line of element edges or node ids: the load is spread along it),
    'nodes' (each selected node) or 'elements' (a region, default all elements).
    build(problem, selection, scale, **values) -> Load: makes the load (selection: node ids for
    'line'/'nodes', element ids or None for 'elements'; scale: the load-factor programme).
    check(values, given) -> (key, message) or None: checks across keys (``given``: the keys the
    user wrote).

    Attributes
    ----------
    name : str
        The kind's name (``Problem.add_load(name, ...)``, ``[[loads]] type = name``).
    target : str
        'line', 'nodes' or 'elements'.
    params : tuple of Param
        The keys it takes.
    build, check : callable
        As above (``check`` may be None).
    doc : str
        One line for the docs; ``extra``: free-form data of the kind.

    Example
    -------
    >>> k = load_kind("gravity")
    >>> k.target, [p.name for p in k.params], k.check is None
    ('elements', ['g', 'rho'], True)
    """
    name: str
    target: str
    params: tuple
    build: Callable
    check: Callable | None = None
    doc: str = ""
    extra: dict = field(default_factory=dict)

    def selection(self):
        return (("edge", "nodes"), ("scale",)) if self.target != "elements" else ((), ("region", "scale"))

    def __post_init__(self):
        super().__post_init__()
        if self.target not in ("line", "nodes", "elements"):
            raise TypeError(f"load kind {self.name!r}: target must be 'line', 'nodes' or 'elements'")


LOADS = Registry("load kind", LoadKind, reserved=("scale", "edge", "nodes", "region"))


def register_load(kind: LoadKind):
    """Add a load kind to the registry (its name must be new); returns it.

    Parameters
    ----------
    kind : LoadKind
        The kind; its ``target`` must be 'line', 'nodes' or 'elements'.

    Returns
    -------
    LoadKind
        ``kind``.  TypeError for anything but a LoadKind or a bad target, ValueError for a name
        that is already registered.

    Example
    -------
    >>> register_load(load_kind("gravity"))
    Traceback (most recent call last):
    ...
    ValueError: load kind 'gravity' is registered twice
    """
    return LOADS.add(kind)


def load_kind(name) -> LoadKind:
    """The registered kind ``name``; an OptionError naming the closest kind otherwise.

    Parameters
    ----------
    name : str
        A key of ``LOADS``.

    Returns
    -------
    LoadKind

    Example
    -------
    >>> load_kind("presure")
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: unknown load kind 'presure'; did you mean 'pressure'?; registered: body_force, edge_force, edge_moment, gravity, nodal, pressure
    """
    return LOADS.lookup(name)


def param_error(message, param):
    """A LoadError that names the offending key ``param`` (scenario files report it)."""
    exc = LoadError(message)
    exc.param = param
    return exc


def finite_vector(v, name):
    """A finite 3-vector or a LoadError naming it."""
    try:
        v = np.asarray(v, float)
    except (TypeError, ValueError):
        raise LoadError(f"{name} must be a finite 3-vector, got {v!r}") from None
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise LoadError(f"{name} must be a finite 3-vector, got {v!r}")
    return v


def check_given(kind, values):
    """The values a caller gives a load kind in Python, checked against its Params (a scenario
    file's validator checks its own): a number, a bool, a vector of ``n`` finite numbers; a
    LoadError naming the key (``param``) instead of NumPy's TypeError on a string, and a
    string taken as True (``follower="no"``).

    Example
    -------
    >>> check_given(load_kind("pressure"), {"p": "2"})
    Traceback (most recent call last):
    ...
    core_se3.errors.LoadError: load kind 'pressure': p must be a number (pressure [force/length^2]), got '2'
    """
    for p in kind.params:
        v = values.get(p.name)
        if v is None or p.kind not in ("number", "bool", "vector"):
            continue
        if p.kind == "vector":
            try:
                a = np.asarray(v, float)
            except (TypeError, ValueError):
                a = None
            ok = a is not None and a.shape == (p.n,) and bool(np.all(np.isfinite(a)))
            what = "a finite 3-vector" if p.n == 3 else f"a vector of {p.n} finite numbers"
        elif p.kind == "bool":
            ok, what = isinstance(v, (bool, np.bool_)), "True or False"
        else:
            ok = not isinstance(v, (str, bytes, bool, np.bool_)) and np.ndim(v) == 0 and np.asarray(v).dtype.kind in "iuf"
            what = "a number"
        if not ok:
            raise param_error(f"load kind {kind.name!r}: {p.name} must be {what} ({p.doc}), got {v!r}", p.name)


def force_scale_with_loads(element_scale, loads, ell):
    """The residual's round-off scale [force]: the element's (``Evaluation.force_scale``) and the
    loads' cancelling terms (``Load.round_off_scale``) added in quadrature.

    Example
    -------
    >>> force_scale_with_loads(3.0, [], 1.0)
    3.0
    """
    extra = [ld.round_off_scale(ell) for ld in loads]
    return float(np.sqrt(element_scale ** 2 + sum(e * e for e in extra))) if any(extra) else element_scale
