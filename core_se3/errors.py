"""Exception hierarchy: every failure names its cause and the likely fix; nothing fails silently.

Every exception derives from :class:`CoreSE3Error`; the ones caused by invalid input also derive
from :class:`ValueError`.  :func:`did_you_mean` is the one helper that turns a misspelt name into
a suggestion, used by every message that rejects a name (keys, regions, edges, cases, elements,
fields, load kinds).

Example
-------
>>> from core_se3.errors import did_you_mean
>>> did_you_mean("plam", ["palm", "tips"])
"; did you mean 'palm'?"
"""
from __future__ import annotations

import difflib
import math
import warnings

__all__ = ["CoreSE3Error", "MaterialError", "MeshError", "LoadError", "SupportError",
           "SingularSystemError", "ConvergenceError", "ElementTooDistortedError", "ScenarioError",
           "CheckpointError", "OptionError", "DesignError", "ContactError", "ParallelError",
           "LinearSolverError", "ControlError", "ResultFileError", "ScenarioWarning", "SupportWarning", "ElementWarning", "MeshWarning",
           "AccuracyWarning", "OptionWarning", "LoadWarning", "PathWarning", "AngleWarning", "did_you_mean",
           "angle_in_degrees", "warn_angle", "TURNS_MAX", "edge_turn_error"]


def did_you_mean(name, choices):
    """``"; did you mean 'X'?"`` for the closest of ``choices`` to ``name``, else ``""``.

    Case differences count as close (``br`` suggests ``Br``).

    Parameters
    ----------
    name : str
        The name that was not found (converted with ``str``).
    choices : iterable of str
        The valid names.

    Returns
    -------
    str
        The hint, to append to an error message, or the empty string when nothing is close
        (difflib's similarity ratio below 0.6, after case folding).

    Example
    -------
    >>> did_you_mean("br", ["Br", "h"]), did_you_mean("zz", ["Br", "h"])
    ("; did you mean 'Br'?", '')
    """
    choices = [str(c) for c in choices]
    name = str(name)
    folded = {c.lower(): c for c in choices}
    if name.lower() in folded and folded[name.lower()] != name:
        return f"; did you mean {folded[name.lower()]!r}?"
    near = difflib.get_close_matches(name, choices, n=1)
    if not near:
        near = [folded[m] for m in difflib.get_close_matches(name.lower(), list(folded), n=1)]
    return f"; did you mean {near[0]!r}?" if near else ""


class CoreSE3Error(Exception):
    """Base class of all errors raised by core_se3.

    Catch it to handle every failure of the package in one place; the subclasses name the cause
    (input errors also derive from :class:`ValueError`).  Raised during ``newton_solve`` after
    the start, any of them carries ``result``: the steps that converged before it.

    Example
    -------
    >>> from core_se3 import CoreSE3Error, Material
    >>> try:
    ...     Material(E=1.0, nu=0.7, h=0.1)
    ... except CoreSE3Error as exc:
    ...     print(type(exc).__name__, isinstance(exc, ValueError))
    MaterialError True
    """


class MaterialError(CoreSE3Error, ValueError):
    """Invalid material parameters (E <= 0, nu outside (-1, 0.5), h <= 0, non-finite).

    Raised by :class:`~core_se3.Material` and :class:`~core_se3.RegionMaterial` when they are
    built, and when a property that differs between regions is read as one number.  The message
    names the parameter and the value; give a value in the stated range (or, for a
    RegionMaterial, use ``per_element(name)``).

    Example
    -------
    >>> from core_se3 import Material
    >>> Material(E=1.0, nu=0.5, h=0.1)
    Traceback (most recent call last):
    ...
    core_se3.errors.MaterialError: Poisson's ratio nu must lie in (-1, 0.5), got 0.5
    """


class MeshError(CoreSE3Error, ValueError):
    """Degenerate or inconsistent mesh (zero-area or inverted quads, bad connectivity, ...).

    Raised when a :class:`~core_se3.mesh.Mesh` is built (frames not in SE(3), collapsed, clockwise
    or non-convex quads, a non-manifold edge), by the generators and the file reader, when a
    node set or region name is unknown (with the closest name), and when a state (frames g,
    increments eta) given to ``Problem.evaluate`` or ``retract`` does not have one entry per node
    of the mesh.  Fix the mesh, the name or the array the message gives.

    Example
    -------
    >>> from core_se3 import mesh
    >>> mesh.rectangle(1.0, 1.0, 2, 1).node_set("X1")
    Traceback (most recent call last):
    ...
    core_se3.errors.MeshError: unknown node set 'X1'; did you mean 'x1'?; node sets: ['x0', 'x1', 'y0', 'y1'], regions: []
    """


class LoadError(CoreSE3Error, ValueError):
    """Invalid load specification (NaN or infinite values, unknown edge, bad direction).

    Raised when a load, applied field or magnetisation is built (``Problem.add_*``, the Load and
    Field classes): a value that is not finite, a key the load kind does not have (with the
    closest one), a field that is not curl- and divergence-free.  Correct the value the message
    names.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.add_load("edge_force", "x1", forc=(0.0, 0.0, 1.0))
    Traceback (most recent call last):
    ...
    core_se3.errors.LoadError: load kind 'edge_force' has no parameter 'forc'; did you mean 'force'?; its parameters: follower, force
    """


class ContactError(LoadError):
    """Invalid contact or obstacle specification: an unknown obstacle kind, a radius or size that
    is not positive and finite, a motion that is not a proper rigid transform, an obstacle that
    already intersects the undeformed shell, contact nodes outside the contact elements.

    Raised by ``Problem.add_obstacle`` and the obstacle classes (``core_se3.model.obstacles``);
    ``param`` names the offending key when there is one (scenario files report it as
    ``obstacles[i].KEY``).  Correct the value the message names, or move the obstacle off the shell.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.add_obstacle("sphere", centre=(0.5, 0.0, 0.0), radius=0.2)     # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.ContactError: obstacle 'sphere' already intersects the undeformed shell: ...
    >>> p.add_obstacle("sphere", centre=(0.5, 0.0, 0.0), radius=-0.2)
    Traceback (most recent call last):
    ...
    core_se3.errors.ContactError: sphere radius must be positive and finite, got -0.2
    """


class SupportError(CoreSE3Error, ValueError):
    """Invalid support specification (unknown edge or node, conflicting constraints).

    Raised by ``Problem.clamp``, ``fix``, ``rotate_edge``, ``prescribe`` and the ``add_*_support``
    methods for an empty selection, node ids that do not exist, a zero rotation axis or a free
    direction that is not a body axis.  A support that leaves a rigid-body motion free is a
    :class:`SingularSystemError` instead.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.clamp([])
    Traceback (most recent call last):
    ...
    core_se3.errors.SupportError: node selection [] is empty
    """


class OptionError(CoreSE3Error, ValueError):
    """An unknown name (element, load kind, field, linear solver, ...) or an invalid solver
    option (steps < 1, non-finite load factors, ...).

    Raised by the registries (with the closest registered name), by
    :class:`~core_se3.NewtonOptions` / :class:`~core_se3.ArcLengthOptions` (a value outside its
    range) and by the solvers (a keyword they do not take).  Use a name or value the message
    lists.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01), element="defualt")
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: unknown element 'defualt'; did you mean 'default'?; registered: default, seed
    """


class SingularSystemError(CoreSE3Error):
    """The tangent is singular: usually a missing support (rigid-body motion left free).

    Raised before solving by ``Problem.check_supports`` (naming the free translation or the axis
    of the free rotation), and by the linear solvers when a factorisation breaks down or its
    backward error or solution growth shows a (near-)singular tangent.  Add supports; if it
    appears only late on a load path, the state is at or near a critical point (use arc length).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01)).check_supports()
    Traceback (most recent call last):
    ...
    core_se3.errors.SingularSystemError: no supports: the shell can move as a rigid body; clamp or fix some nodes
    """


class ConvergenceError(CoreSE3Error):
    """Newton failed even after the allowed step cut-backs.

    ``result`` keeps every load step that converged before the failure.  Raised by
    ``newton_solve`` (also when load control has snapped past a limit point: the message then
    suggests arc length), ``arc_length`` and ``displacement_control``.  Use smaller steps, more
    cut-backs or iterations, or a path-following control; ``result`` can be plotted or written
    as it is.

    Parameters
    ----------
    message : str
        The cause: the load factor reached, the reason of the last failed try, a hint.
    result : core_se3.Result, optional
        The steps that converged (None if there is none to keep).

    Example
    -------
    >>> from core_se3 import ConvergenceError, Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 4.0))
    >>> try:
    ...     p.solve(steps=1, max_iter=2, max_cutbacks=0)     # a large step, two iterations
    ... except ConvergenceError as exc:
    ...     print(len(exc.result.steps), exc.result.final.load_factor)
    1 0.0
    """

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


class ElementTooDistortedError(CoreSE3Error):
    """A relative rotation across an element edge reached pi, where the logarithm is cut.

    Raised by the default element when an edge turns by more than ``MAX_EDGE_ANGLE`` (0.97 pi),
    by a prescribed motion that turns nodes by more than 0.9 pi within one step, and by a
    ``RotationComponentSpring`` whose node has turned by nearly pi.  The solvers treat it as a
    failed try and cut the step back; if it persists, refine the mesh (or the load step).  At the
    reference frames (the element's build) the turn is the user's frames, and the message names
    the two nodes, the turn and its axis, and asks for consistent frames (d1 along the shell, a
    mesh file's ``d1_hint``) instead.

    Example
    -------
    >>> from core_se3 import mesh, lie
    >>> from core_se3.fem import edge_twists
    >>> m = mesh.rectangle(1.0, 1.0, 1, 1)
    >>> g = m.g0.copy(); g[1, :3, :3] = lie.exp_so3([0.0, 0.0, 3.1])     # node 1 turned by 3.1 rad
    >>> edge_twists(g, m.edge_nodes)
    Traceback (most recent call last):
    ...
    core_se3.errors.ElementTooDistortedError: edge [0, 1] turns by 3.100 rad (>= 3.047); the relative rotation across an element must stay below pi: refine the mesh or the load step
    """


def edge_turn_error(edge_nodes, e, angle, limit, mesh):
    """The ElementTooDistortedError of mesh edge ``e`` (its nodes ``edge_nodes[e]``) turning by
    ``angle`` >= ``limit`` [rad], naming the nodes by the whole mesh's ids: a rank's part of a
    distributed run (``mesh.whole_ids``, parallel.local) numbers them locally, and the message
    named those local ids (a strip's tip edge [46, 47] read [22, 23] on two ranks).

    Example
    -------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> part = SimpleNamespace(whole_ids=(np.array([3]), np.array([46, 47, 7, 8])))
    >>> str(edge_turn_error(np.array([[0, 1], [2, 3]]), 0, 3.056, 3.047, part))[:24]
    'edge [46, 47] turns by 3'
    """
    ids = getattr(mesh, "whole_ids", None)
    a, b = (int(i) if ids is None else int(ids[1][i]) for i in edge_nodes[e])
    return ElementTooDistortedError(
        f"edge {[a, b]} turns by {angle:.3f} rad (>= {limit:.3f}); the relative rotation across an element must "
        "stay below pi: refine the mesh or the load step")


def _located(message, file=None, key=None):
    """``file: [key]: message`` (the parts present) for errors and warnings about an input file."""
    where = ": ".join(x for x in (file, f"[{key}]" if key else None) if x)
    return f"{where}: {message}" if where else message


class ScenarioError(CoreSE3Error, ValueError):
    """An invalid scenario file: ``file`` and dotted ``key`` name where, the message what was
    expected and what was found.

    Raised by ``scenario.load``, ``loads`` and ``from_dict`` (and by ``Scenario.with_overrides``)
    before anything is solved; ``detail`` is the message without the location.  Edit the key the
    message names.

    Parameters
    ----------
    message : str
        What was expected and what was found.
    file : str, optional
        The scenario file (``"<string>"`` for text, ``"<dict>"`` for a dict).
    key : str, optional
        The dotted key, e.g. ``loads[2].force``.

    Example
    -------
    >>> from core_se3 import scenario, ScenarioError
    >>> try:
    ...     scenario.from_dict({"mesh": {"generator": "rectangle"}})
    ... except ScenarioError as exc:
    ...     print(exc.file, exc.key, "|", exc)
    <dict> material | <dict>: [material]: missing required key
    """

    def __init__(self, message, file=None, key=None):
        self.file, self.key, self.detail = file, key, message
        super().__init__(_located(message, file, key))


class CheckpointError(CoreSE3Error):
    """A checkpoint that is missing, unreadable or belongs to another scenario.

    Raised by ``scenario.run`` (``core-se3 run``): ``--resume`` without a checkpoint, a checkpoint
    of a changed scenario (its fingerprint differs) or of another control, or a new run into a
    directory that holds one.  Run without ``--resume`` (with ``--force`` to start over) or use
    another output directory.

    Example
    -------
    >>> import tempfile
    >>> from core_se3.io import Checkpoint
    >>> Checkpoint(tempfile.mkdtemp()).load()      # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.CheckpointError: no checkpoint to resume from: ...checkpoint.npz does not exist (run without --resume first)
    """


class DesignError(CoreSE3Error, ValueError):
    """An invalid design problem (``core_se3.design``): a target on a node, probe or region that
    does not exist, a variable the problem does not have (no magnet on a region, no such field),
    bounds that exclude the start or are empty, a norm bound the chosen optimiser cannot hold.

    Raised when a design variable, target or ``Design`` is built and when an optimisation is
    started; a target that is valid but not reached is not an error (the result says "did not
    reach the target: misfit X").  Fix the name or the bound the message gives.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.design import NodePosition
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> NodePosition(p, [99])
    Traceback (most recent call last):
    ...
    core_se3.errors.DesignError: node ids [99] do not exist (the mesh has 6 nodes: 0 .. 5)
    """


class ControlError(CoreSE3Error):
    """A command that a control session (``core_se3.control.Session``) refuses: a session the
    model cannot have (a path-dependent element, contact, a prescribed motion of the load
    factor), or an update it cannot follow on the equilibrium path -- the corrector leaves the
    path (a limit point or a snap onto another branch), turns nodes too far, or fails to converge
    even after the command was split ``max_splits`` times.  The session stays at the state before
    the command; the message says where the path was lost and why.  Send smaller command changes,
    or trace the path with arc length (``core_se3.solvers.arc_length``).

    Example
    -------
    >>> from core_se3.errors import ControlError
    >>> issubclass(ControlError, CoreSE3Error)
    True
    """


class ResultFileError(CoreSE3Error, ValueError):
    """A file that is not a result document (``core_se3.results.read_json``): not JSON, a top
    level that is not a JSON object (a list, a number, a string), or an object of another schema
    or version.  ``file`` names the file; the message says what was found and what was expected.
    Pass the ``result.json`` a run wrote (``core-se3 run``, ``core-se3 bench run``).

    Parameters
    ----------
    message : str
        What was found and what was expected.
    file : str, optional
        The file.

    Example
    -------
    >>> exc = ResultFileError("top level is a list, expected a JSON object", "r.json")
    >>> str(exc), exc.file, isinstance(exc, ValueError)
    ('r.json: top level is a list, expected a JSON object', 'r.json', True)
    """

    def __init__(self, message, file=None):
        self.file, self.detail = file, message
        super().__init__(f"{file}: {message}" if file is not None else message)


class ScenarioWarning(UserWarning):
    """An implausible but valid scenario value: ``file`` and dotted ``key`` name where, the
    message why it is implausible and the likely fix.

    Collected in ``Scenario.warnings`` and issued with :func:`warnings.warn` when a scenario is
    loaded; ``core-se3 run`` prints them before the run, and ``--strict`` (``strict=True``)
    makes each one a :class:`ScenarioError`.

    Parameters
    ----------
    message : str
        Why the value is implausible, and the fix.
    file, key : str, optional
        As for :class:`ScenarioError`.

    Example
    -------
    >>> w = ScenarioWarning("|Br| = 100 T exceeds 2 T", "grip.toml", "magnets[0]")
    >>> str(w), w.key
    ('grip.toml: [magnets[0]]: |Br| = 100 T exceeds 2 T', 'magnets[0]')
    """

    def __init__(self, message, file=None, key=None):
        self.file, self.key, self.detail = file, key, message
        super().__init__(_located(message, file, key))


class ParallelError(CoreSE3Error, ValueError):
    """A problem or an option that the distributed solver (``core_se3.parallel``, runs under
    ``mpirun``) cannot take: a load kind without a distributed form (give the Load a
    ``localized(part)`` method, docs/PARALLEL.md), a control other than load stepping asked for
    explicitly with ``solver="distributed"``, an unknown partitioner or linear solver, or
    mpi4py/petsc4py missing.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.solve(control="arclength", solver="distributed")
    Traceback (most recent call last):
    ...
    core_se3.errors.ParallelError: the distributed solver steps the load (control='load'); control 'arclength' runs serially (drop solver='distributed')
    """


class LinearSolverError(SingularSystemError):
    """An iterative linear solver (``[solver] linear = "gamg"`` or ``"hypre"`` in a distributed
    run) did not reach its tolerance, or its answer failed the true-residual check.  Newton
    treats it like a singular tangent after the first step (the step is cut back).  Use the
    direct solver (``linear = "mumps"``), or loosen ``ksp_rtol`` / raise ``ksp_max_it`` in the
    PETSc options (docs/PARALLEL.md).

    Example
    -------
    >>> issubclass(LinearSolverError, SingularSystemError)
    True
    """


class SupportWarning(UserWarning):
    """A support that did not hold what it names, measured on the solved state.

    ``Problem.fix`` holds body-frame dofs *incrementally*: each Newton update g <- g exp(eta)
    has the held components of eta zero.  When the nodes turn about an axis other than the held
    one, the held directions turn with them (a held translation) or finite rotations about two
    free axes do not commute (one held rotation): the held component drifts from zero at second
    order and the state depends on the load steps (a non-holonomic support).  Issued by
    ``Problem.solve`` when the drift exceeds ``DRIFT_TOL`` (``model.prescribed.held_dof_drift``);
    a clamp, a pin (translations held), a hinge or a symmetry plane (the node turns about the
    held axis only) holds exactly, and so do the lab supports ``add_lab_support`` and
    ``add_rotation_component_support``.

    Example
    -------
    >>> from core_se3.errors import SupportWarning
    >>> issubclass(SupportWarning, UserWarning)
    True
    """


class ElementWarning(UserWarning):
    """An element used where it is known to give wrong answers that converge.

    Issued by the seed's scheme (``element = "seed"``, kept for comparison with the paper) on
    thin meshes, where it locks: measured by ``python -m comparison`` (the locking study), with
    element size / thickness 12.5 the cantilever, roll-up and arch do not converge, and the
    torsion strip 10 x 4 at L/h = 1e4 (element size / thickness 1000) converged to 130 times
    the torsion constant of the default element and of the DOLFINx reference.  Issued when a
    solve starts (``Problem.check_element``) for the default element on coarse meshes of thin
    curved shells (an element along a free edge whose out-of-plane edge turn phi has
    phi^3 L / h > 2, ``fem.element_default.COARSE_THIN_CURVED``), where a membrane-dominated
    shell can come out spuriously flexible (the Scordelis-Lo roof 2x2 at R/h 1e4: 10.9 times its
    deflection; docs/ELEMENTS.md).  Issued when the element is built where the nodes' normals
    contradict the positions (``fem.warp.check_chord_normals``: a plate given a sphere's normals
    came out 0.45 of its deflection).

    Example
    -------
    >>> from core_se3.errors import ElementWarning
    >>> issubclass(ElementWarning, UserWarning)
    True
    """


class MeshWarning(UserWarning):
    """A mesh made as asked that is known to give erratic answers.

    Issued by the structured generators' ``grade`` (``mesh.generators.spacing``) when
    neighbouring elements differ in width by more than ``MAX_GROWTH`` (2): on the thin
    Scordelis-Lo roof, meshes graded toward the free edge are within 0.8 ... 1.02 of the
    converged deflection wherever the growth is at most 1.7, and erratic beyond 2 (the 2x2 at
    R/h 1e3: 0.66 ... 5.6 as the first width changes; benchmarks/results/roof_layer.md).
    Issued at the end of a solve when a point dipole lies within
    ``model.magnetics.DIPOLE_RESOLUTION`` (10) element sizes of the magnetised material: the
    nodal quadrature of its loads is off by about (size / distance)^2 (a strip refined along
    its length only converged 83 % off).

    Example
    -------
    >>> from core_se3.errors import MeshWarning
    >>> issubclass(MeshWarning, UserWarning)
    True
    """


class AccuracyWarning(UserWarning):
    """A linear solution that double precision cannot give to 1e-4 (``solvers.linear``), or one
    whose prescribed motion (``Problem.prescribe``) is not linear in the load factor, so that the
    linear analysis holds the chord of its target at lam_end rather than the linearised motion
    (give rigid motions with ``rotate_edge`` / ``move_edge``, linearised exactly, or use load
    control).

    The factorisation is backward stable, so its error is that of the system: about its
    condition number times the round-off.  Very thin shells are ill-conditioned (the membrane
    stiffness exceeds the bending stiffness by (L/h)^2): the pinched hemisphere on 64x64
    elements is good to about 1e-3 at R/h 1e5 and to 5 ... 9 % at 1e6, where different
    factorisations of the same system differ by 1.6e-3 and 3 % (measured, issue 30).

    Example
    -------
    >>> from core_se3.errors import AccuracyWarning
    >>> issubclass(AccuracyWarning, UserWarning)
    True
    """


class OptionWarning(UserWarning):
    """A solver option given that the chosen control does not use.

    Issued by ``Problem.solve`` with ``control="linear"`` (and ``Problem.solve_linear``) for a
    load-stepping option given in the call: ``steps`` other than 1 or a Newton control
    (``NewtonOptions``: tolerances, iterations, cut-backs, ...) other than its default.  A linear
    analysis is one solve at lam_end, so the option changes nothing; a scenario file warns of
    ``[solver] steps`` with ``control = "linear"`` the same way (a :class:`ScenarioWarning`).
    Drop the option, or solve with load control (``control="load"``) to step the load.

    Example
    -------
    >>> import warnings
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1e-3))
    >>> with warnings.catch_warnings(record=True) as said:
    ...     warnings.simplefilter("always")
    ...     _ = p.solve_linear(steps=10)
    >>> [type(w.message).__name__ for w in said]
    ['OptionWarning']
    """


class LoadWarning(UserWarning):
    """A load asked for that adds nothing: gravity on elements whose density is zero (the load's
    ``rho``, or the material's ``rho``).  Zero is a valid density (a sweep that starts from a
    weightless shell), so it is not refused; give a positive ``rho`` (to the load, or
    ``Material(..., rho=...)``, ``[material] rho``), or drop the load.

    Example
    -------
    >>> from core_se3.errors import LoadWarning
    >>> issubclass(LoadWarning, UserWarning)
    True
    """


class PathWarning(UserWarning):
    """An arc-length path (``solvers.arc_length``) that stopped after ``max_steps`` points short
    of the end it was given (``lam_end``, ``stop_at``): its Result ends where the steps ran out,
    not at that end.  Before, it was returned without a word (ds_max = 1e-6 to lam_end = 1: 200
    steps ending at lam = 0.05).  Raise max_steps (a resumed path continues from its last
    ArcState), or the arc length (dlam0, ds_max).  A scenario file's run fails instead, saying so.

    Example
    -------
    >>> from core_se3.errors import PathWarning
    >>> issubclass(PathWarning, UserWarning)
    True
    """


#: a path's angle [rad] (a prescribed rotation, an obstacle's or a field's turn) of more than
#: TURNS_MAX turns is likely degrees (360 -> 57 turns, 45 -> 7.2, 30 -> 4.8); real paths turn 1 or 2
TURNS_MAX = 3


class AngleWarning(UserWarning):
    """An angle [rad] so large that it is likely in degrees: an orientation (a box obstacle's
    rotation vector, a mesh generator's ``angle0``) of more than a turn, or the turn of a path
    (``Problem.rotate_edge`` / ``move_edge``, an obstacle's rotating motion) of more than
    :data:`TURNS_MAX` turns.  Every angle of core_se3 is in radians (the one exception, a
    scenario's ``hole_deg``, says so in its name); ``rotate_edge(..., angle=90)`` meant a quarter
    turn and rolled the edge 14.3 times.  Give the angle in radians (``numpy.radians``).  A
    meant angle of many turns (a field turning 10 times) is silenced around the call with
    ``warnings.catch_warnings()`` and ``warnings.simplefilter("ignore", AngleWarning)``, as the
    message says (:data:`SILENCE_ANGLE`).  A scenario file says the same as a
    :class:`ScenarioWarning` naming its key.

    Example
    -------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as said:
    ...     warnings.simplefilter("always")
    ...     _ = warn_angle(90.0, "rotate_edge: angle")
    >>> print(said[0].message)                        # doctest: +NORMALIZE_WHITESPACE
    rotate_edge: angle = 90 rad is 14.3 turns (more than 3): angles are in radians (90 degrees is 1.5708 rad); if
    the angle is meant, silence this warning around the call: with warnings.catch_warnings():
    warnings.simplefilter("ignore", core_se3.errors.AngleWarning)
    """


#: how to silence an AngleWarning of an angle that is meant (said in its message)
SILENCE_ANGLE = ("if the angle is meant, silence this warning around the call: with warnings.catch_warnings(): "
                 'warnings.simplefilter("ignore", core_se3.errors.AngleWarning)')


def angle_in_degrees(angle, path=True):
    """The message for an angle [rad] that is likely degrees (:class:`AngleWarning`), else None:
    a path's angle beyond :data:`TURNS_MAX` turns, an orientation's (``path`` False) beyond one.

    Example
    -------
    >>> angle_in_degrees(2 * math.pi), angle_in_degrees(45.0, path=False)
    (None, '45 rad is more than a turn: angles are in radians (45 degrees is 0.785398 rad)')
    """
    try:
        a = float(angle)
    except (TypeError, ValueError):
        return None                          # (not a number: the caller's own error says so)
    turns = abs(a) / (2 * math.pi)
    if turns > (TURNS_MAX if path else 1) and math.isfinite(a):
        said = f"{a:g} rad is {turns:.3g} turns (more than {TURNS_MAX})" if path else f"{a:g} rad is more than a turn"
        return f"{said}: angles are in radians ({a:g} degrees is {math.radians(a):.6g} rad)"
    return None


def warn_angle(angle, what, path=True):
    """An :class:`AngleWarning` about ``what`` (e.g. ``"rotate_edge: angle"``) where
    :func:`angle_in_degrees` has a message, said at the first line outside core_se3 (the user's
    call, however deep the angle entered); returns ``angle``.

    Example
    -------
    >>> warn_angle(1.5, "rotate_edge: angle")        # a quarter turn in radians: nothing said
    1.5
    """
    msg = angle_in_degrees(angle, path)
    if msg is not None:
        import os
        import sys
        here, f, level = os.path.dirname(os.path.abspath(__file__)) + os.sep, sys._getframe(0), 1
        while f.f_back is not None and os.path.abspath(f.f_code.co_filename).startswith(here):
            f, level = f.f_back, level + 1
        warnings.warn(AngleWarning(f"{what} = {msg}; {SILENCE_ANGLE}"), stacklevel=level)
    return angle
