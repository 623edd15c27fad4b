"""A control session: an equilibrium held with its factorisation, moved warm to new commands.

    s = Session.from_scenario("examples/gripper.toml")          # cold solve once, factor once
    st = s.update(coil=[0.0, 0.0, 0.062])                         # warm, on the held factors
    st.g, st.probes["tip_px"]["x"]
    J = s.jacobian(["tip_px"], ["coil"])                          # d tip / d B, same factors

An update follows the straight command path p(t) = p0 + t (p1 - p0), t from 0 to 1, in
sub-steps, each a predictor and a corrector on the held factors (``control.corrector``); a
failed sub-step (the path test, the node-turn limit, no convergence) is halved, and after
``max_splits`` halvings the command is refused with a ControlError that names the reason --
the session then stays where it was.  Nothing is rebuilt that did not change: the variables
are assigned in place (the compiled loads read them at call time), the sparsity pattern, the
compiled evaluation and the factors are kept, and probes are computed only when read.

A part far from the origin is held relative to it, as load stepping and path following hold
their iterates (``solvers.origin.part_origin``): the corrector's frames are the part's positions
minus that origin (exact), so the updates iterate as those of the part at the origin, bit for
bit; the states' frames ``g`` are in the problem's coordinates (to their round-off eps |x0|),
their probe displacements as exact as at the origin.  Before, the README cantilever at
x0 = 1e4 could not start a session (the residual stalled at 4.8e-7; 2.6e-2 at 1e9).
"""
from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, fields

import numpy as np

from ..design import ProbePosition, Quantity, SolveWith, Variable, sensitivity
from ..design.sensitivity import OnPart
from ..errors import ControlError, ConvergenceError, ElementTooDistortedError, OptionError, SingularSystemError
from ..model.base import overrides
from ..model.magnetics import MagneticLoad, dipole_sources
from ..model.solving import dipole_warning
from ..results.recorder import initial_state
from ..solvers import NewtonOptions, newton_solve
from ..solvers.newton import MAX_LOAD_TURN
from ..solvers.options import split_options, unknown_keywords
from ..solvers.origin import part_origin
from .commands import Commands, scenario_variables
from .corrector import Corrector
from .options import ControlOptions

__all__ = ["Session", "State", "Work"]

_HOOKS = ("update_multipliers", "limit_increment", "start_error")


@dataclass(frozen=True)
class Work:
    """What an update of a session took.

    Attributes
    ----------
    iterations, factorizations, substeps, splits : int
        Back-substitutions, fresh factorisations, sub-steps of the command path, halvings.
    time : float
        Wall time [s].

    Example
    -------
    >>> Work(iterations=3, substeps=1).factorizations
    0
    """

    iterations: int = 0
    factorizations: int = 0
    substeps: int = 0
    splits: int = 0
    time: float = 0.0


class State:
    """A converged state of a session.

    Attributes
    ----------
    g : (n, 4, 4) ndarray
        The nodal frames; ``lam``: the load factor; ``values``: variable name -> values.  The
        arrays are read-only views (g is the session's own frames): copy them to change them.
    work : Work
        What the update took; its fields are also read as attributes of the state
        (``iterations``, ``factorizations``, ``substeps``, ``splits``, ``time`` [s]).
    probes : dict
        name -> dict(x (3,) position, u (3,) displacement, R (3, 3) rotation) of every probe
        of the problem, computed at the first read.
    local : tuple, optional
        (frames relative to an origin, that origin (3,)) of the same state, for a part far from
        the origin (``solvers.origin.part_origin``): the displacements are read from them, as
        exact as for the part at the origin.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01)); p.add_probe("tip", "x1")
    >>> st = State(p, p.mesh.g0, 0.0, {}, Work(iterations=2, substeps=1))
    >>> st.probes["tip"]["x"].tolist(), st.iterations
    ([2.0, 0.0, 0.0], 2)
    """

    def __init__(self, problem, g, lam, values, work=Work(), local=None):
        # read-only views: g is the session's own frames (a state's g scaled in place for a picture
        # moved the session there -- the same command returned it, the Jacobian was taken at it on
        # the factors of the equilibrium, and the next update failed)
        self.problem, self.lam = problem, float(lam)
        self.g, self.values = _read_only(g), {k: _read_only(v) for k, v in values.items()}
        self.work, self._local = work, local
        self._probes = None

    iterations = property(lambda self: self.work.iterations)
    factorizations = property(lambda self: self.work.factorizations)
    substeps = property(lambda self: self.work.substeps)
    splits = property(lambda self: self.work.splits)
    time = property(lambda self: self.work.time)

    @property
    def probes(self):
        if self._probes is None:
            g0, gu = self.problem.mesh.g0, self.g
            if self._local is not None:              # u from the positions relative to the part
                gu, g0 = self._local[0], g0.copy()
                g0[:, :3, 3] -= self._local[1]
            out = {}
            for name, pr in self.problem.probes.items():
                x, R = pr.state(self.g)
                out[name] = dict(x=x, u=pr.state(gu)[0] - pr.state(g0)[0], R=R)
            self._probes = out
        return self._probes


def _read_only(a):
    """A read-only view of the array a (its owner may still write it)."""
    v = np.asarray(a).view()
    v.flags.writeable = False
    return v


def _load_factor(lam, who):
    """lam as a float, or OptionError: a bool, a string, None, an array or a non-finite number
    is no load factor (before, Session read True as 1.0 and failed on '1' or None with NumPy's
    TypeError)."""
    if (isinstance(lam, (bool, np.bool_)) or not isinstance(lam, (int, float, np.floating, np.integer))
            or not np.isfinite(lam)):
        raise OptionError(f"{who}: the load factor must be a finite number, got {lam!r}")
    return float(lam)


def _items(x):
    """A sequence argument as a list: one name (a string) or one object is a list of one (before,
    jacobian(q, "PB") iterated the string: the variables P and B)."""
    return [x] if isinstance(x, (str, Quantity, Variable)) else list(x)


def _given_start(g, problem):
    """A given start as proper rigid frames of the problem's mesh (``results.recorder.initial_state``,
    what ``Problem.solve`` checks its ``g_init`` with; a StepResult gives its frames), else an
    OptionError.  Before, only the shape was checked: rotations scaled by 1.001 (frames rounded in
    a file) converged in 8 iterations to a 'state' whose tip was 8.7e-4 of the README strip's
    length off the cold solve, and every update after it kept the non-rotations."""
    try:
        return initial_state(g, problem.mesh.g0)[0]
    except OptionError as exc:
        raise OptionError(f"Session: the start g is not a state of this problem -- {exc}") from None


def _named_besides(items, others):
    """The names of the loads or supports in ``items`` that are not in ``others`` (by identity)."""
    return ", ".join(str(getattr(x, "name", None) or type(x).__name__) for x in items
                     if not any(x is o for o in others)) or "none"


def _start_refused(problem, lam, given, reason):
    """Why a session could not start.  At load factor 0 without a given g the start is the
    reference state, the equilibrium of loads that vanish there: loads that do not (a constant
    scale) were reported as 'the start is not an equilibrium the corrector reaches', as if the
    user had given a wrong start -- they are named now."""
    head = f"the start is not an equilibrium the corrector reaches at load factor {lam:g}: {reason}"
    if lam != 0.0 or given:
        return head
    on = []
    for ld in problem.loads:
        try:
            f = float(np.abs(ld.evaluate(problem.mesh.g0, 0.0, False).f).max())
        except Exception:                    # (a load that cannot say: the plain message)
            continue
        if f > 0.0:
            on.append(f"{getattr(ld, 'name', type(ld).__name__)} (largest nodal value {f:.3g})")
    if not on:
        return head
    return (f"Session at load factor 0 starts from the reference state, the equilibrium where the loads vanish, "
            f"but {len(on)} load(s) do not vanish at load factor 0 (their scale there is not 0): {', '.join(on[:3])}"
            f"{' ...' if len(on) > 3 else ''}; the corrector could not reach their equilibrium from the reference "
            f"state ({reason}).  Start the session at a load factor that load stepping reaches from 0 (loads that "
            "scale with it: the default scale), or give g, a state in equilibrium at load factor 0")


def _check_problem(problem):
    """ControlError for what a session cannot hold."""
    if problem.element.stateful:
        raise ControlError(f"a control session needs a path-independent element; {problem.element_name!r} keeps an "
                           "incremental strain (use the default element)")
    hooked = [ld for ld in problem.loads if any(overrides(ld, h) for h in _HOOKS)]
    if hooked:
        raise ControlError(f"a control session does not support the load {hooked[0].name!r} (contact: its "
                           "multipliers and step cap need load stepping, Problem.solve)")
    problem.check_element(stacklevel=4)      # the coarse-mesh warning, as Problem.solve gives it


class Session:
    """An equilibrium of ``problem`` at the load factor ``lam`` with its factorisation, moved warm
    by :meth:`update` (module docstring).

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (supports checked here).
    lam : float
        The load factor of the first equilibrium.
    variables : sequence of core_se3.design.Variable
        The commands, by their names (``FieldVariable(p, field, name="coil")``, ...).
    g : (n, 4, 4) array, optional
        A start near the equilibrium (default: a cold solve by load stepping from the flat state
        in ``steps`` steps, default the problem's ``solve_defaults`` or 10).
    options : ControlOptions, optional
        The controls; keywords override its fields.

    The session owns the values of its variables: change them by :meth:`update` (a change made
    on the problem behind its back is seen by the corrector's residuals, but not by the state's
    ``values`` or the predictor's start).

    Attributes
    ----------
    state : State
        The current equilibrium (``g``, ``lam``, ``values`` are its).
    stats : dict
        Totals: updates, refused, substeps, splits, iterations (``counts``: residual evaluations,
        factorisations, back-substitutions).

    Example
    -------
    A cantilever under a tip force: a warm update of the force's magnitude equals the cold solve.

    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.design import LoadMagnitude
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0)); p.add_probe("tip", "x1")
    >>> s = Session(p, 1.0, [LoadMagnitude(p, p.loads[0], name="P")])
    >>> st = s.update(P=1.01)                             # on the factors of the first equilibrium
    >>> cold = p.solve(steps=10).final.probes["tip"]["u"]
    >>> bool(np.abs(st.probes["tip"]["u"] - cold).max() < 1e-8 * 10.0), st.factorizations
    (True, 0)
    """

    def __init__(self, problem, lam=1.0, variables=(), g=None, options=None, steps=None, **kw):
        opts, kw = split_options(ControlOptions, options, dict(kw))
        unknown_keywords("Session", kw, [f.name for f in fields(ControlOptions)])
        lam = _load_factor(lam, "Session")
        _check_problem(problem)
        problem.check_supports()
        self.problem, self.options = problem, opts
        self.commands = Commands(variables, problem)
        self._fields = self._fields_now()     # the arrays its field variables set (_check_unchanged)
        self._loads = list(problem.loads)    # what the lists below and the part's origin were made of
        self._supports, self._material = list(problem.supports), problem.material   # (_check_unchanged)
        self._turning = [ld for ld in problem.loads if overrides(ld, "direction_turn")]
        # magnets in the field of a point dipole: their states are checked for its resolution
        self._near = [ld for ld in problem.loads if isinstance(ld, MagneticLoad) and dipole_sources(ld.field)]
        self._unresolved = False
        self._stamp = 0
        self._corr = Corrector(problem, opts)
        self._origin = part_origin(problem)   # the corrector's frames are relative to it (module docstring)
        self.stats = dict(updates=0, refused=0, substeps=0, splits=0, iterations=0)
        t0 = time.perf_counter()
        given = g is not None
        g = self._cold(lam, steps) if g is None else _given_start(g, problem)
        out = self._corr.step(self._local(g), lam, self._stamp, check_path=False)
        if not out.ok:
            raise ControlError(_start_refused(problem, lam, given, out.reason))
        self._g = out.g                   # the corrector's frames of the state (relative to the origin)
        self._r = out.residual            # the free residual at the state (the next predictor's start)
        nf = out.factorizations + self._start_sign(given, lam)
        self.state = self._state(out.g, lam, Work(out.iterations, nf, 1, 0, time.perf_counter() - t0))
        self._check_resolution()

    def _start_sign(self, given, lam):
        """Record det K's sign at the start (the last accepted state where it is known, and that
        state in words: a change between accepted states means a critical point crossed); 1 if
        it factored for it.  From a given g the factors are made at the converged start (before,
        the sign was the guess's: the snap roof at load factor 0.627 from a guess halfway between
        its stable and its unstable state, det K < 0 there, converged onto the far, stable branch,
        det K > 0, and the session then refused every Jacobian as 'past a critical point')."""
        c, factored = self._corr, 0
        if given and c.F_g is not self._g:
            try:
                c.factor(self._g, lam, self._stamp, keep=True)
                factored = 1
            except (SingularSystemError, ElementTooDistortedError):
                pass                         # a critical point at the start: its sign is not known
        known = c.F_g is self._g or not given        # a cold start converged where its factors are
        self._sign = c.det_sign() if known else None
        self._sign_at = f"the session's start (load factor {lam:.6g})"
        return factored

    @classmethod
    def from_scenario(cls, scn, lam=None, variables=None, **kw):
        """The session of a scenario (a path or a ``core_se3.scenario.Scenario``) at ``lam``
        (default its [solver] lam_end), with ``variables`` (default
        ``control.commands.scenario_variables``: its fields by name, its loads as load0, ...);
        rtol, dtol and the cold solve's steps from its [solver] unless given.

        Example
        -------
        >>> from core_se3 import scenario
        >>> scn = scenario.loads('''
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
        ... ''')
        >>> s = Session.from_scenario(scn)
        >>> list(s.values), s.update(load0=2.0).lam
        (['load0'], 1.0)
        """
        from ..scenario import Scenario, load
        if not isinstance(scn, Scenario):
            scn = load(scn)
        sv = scn.solver
        kw.setdefault("rtol", sv["rtol"])
        kw.setdefault("dtol", sv["dtol"])
        kw.setdefault("steps", sv["steps"])
        variables = scenario_variables(scn) if variables is None else variables
        try:
            return cls(scn.problem, sv["lam_end"] if lam is None else lam, variables, **kw)
        except ConvergenceError as exc:
            if sv.get("control") != "arclength" or kw.get("g") is not None:
                raise
            # the cold start steps the load; a scenario traced by arc length may pass a limit point
            raise ConvergenceError(
                f"{exc} -- the scenario's [solver] control = \"arclength\": the session's cold start steps the "
                "load factor and cannot pass a limit point; start it from a state of the arc-length run "
                "(r = scenario.load(path).run(out=DIR); Session.from_scenario(path, lam=r.doc['steps'][-1]"
                "['load_factor'], g=r.g)), or at a load factor before the limit point",
                getattr(exc, "result", None)) from exc

    # ------------------------------------------------------------------ the state ------
    @property
    def g(self):
        return self.state.g

    @property
    def lam(self):
        return self.state.lam

    @property
    def values(self):
        return self.state.values

    @property
    def variables(self):
        return self.commands.variables

    @property
    def counts(self):
        """Residual evaluations, factorisations and back-substitutions so far."""
        return dict(self._corr.counts)

    def close(self):
        """Release the factors."""
        self._corr.close()

    def _cold(self, lam, steps):
        d = self.problem.solve_defaults
        steps = steps or (d.get("steps") if isinstance(d.get("steps"), int) else None) or 10
        opts = NewtonOptions(rtol=self.options.rtol, dtol=self.options.dtol,
                             linear_solver=self.options.linear_solver or self.problem.linear_solver)
        if lam == 0.0:
            return self.problem.mesh.g0.copy()
        return newton_solve(self.problem, steps=steps, lam_end=lam, options=opts).final.g

    def _local(self, g):
        """A copy of the problem's frames g in the corrector's coordinates: the positions relative
        to the part's origin (module docstring)."""
        g = np.array(g, float)
        if self._origin is not None:
            g[..., :3, 3] -= self._origin
        return g

    def _state(self, g, lam, work):
        """The State of the corrector's frames g: in the problem's coordinates, with g for the
        probes' displacements when it is relative to an origin."""
        if self._origin is None:
            return State(self.problem, g, lam, self.commands.values(), work)
        whole = g.copy()
        whole[..., :3, 3] += self._origin
        return State(self.problem, whole, lam, self.commands.values(), work, (g, self._origin))

    def _assign(self, values, g=None, lam=None):
        """Assign values; with (g, lam), return the exact change of the free residual there
        (None if not linear: ``Commands.assign``)."""
        dr = self.commands.assign(values, None if g is None else self.problem, g, lam)
        self._stamp += 1
        self._material = self.problem.material          # a MaterialVariable sets it: the session's own
        self._fields = self._fields_now()                # what its field variables set, now
        return dr

    def _check_unchanged(self, what):
        """ControlError when the problem is no longer the one the session holds factors, a residual
        and a state of: its loads changed (a load added after the session: a contact, which a session
        refuses, was followed as a bare penalty, the README strip's tip 1.2e-3 from Problem.solve's;
        a new magnet near a point dipole or a turning load escaped the session's checks; or one
        removed), its supports changed (before: a support added made the next update fail with
        NumPy's 'operands could not be broadcast', and the Jacobian was the old problem's, the
        README strip's tip d z / d P 1.0e-3 with its z held), or its material was set outside the
        session (``Problem.material``, ``set_material``: before, the old state was returned as the
        current one, the strip at twice E with its tip at z = 3.01 where Problem.solve gives 1.62,
        with the old law's Jacobian), or a field that a variable of the session sets was set
        outside it (``field.B = ...``: before, the magnetic strip's field set from 0.3 to 0.6 left
        ``update(B=[0, 0, 0.3])`` returning the old state, tip z 0.398 where the problem's field
        gives 0.590, and the Jacobian of the old factors)."""
        p, kinds, said = self.problem, [], []
        for kind, now, held in (("loads", p.loads, self._loads), ("supports", p.supports, self._supports)):
            if len(now) != len(held) or any(a is not b for a, b in zip(now, held)):
                kinds.append(kind)
                said.append(f"{kind} added: {_named_besides(now, held)}; removed: {_named_besides(held, now)}")
        if p.material is not self._material:
            kinds.append("material")
            said.append("the material set by Problem.material or set_material, not by a session's update")
        moved = [f"{what} = {np.round(now, 12).tolist()} (the state's: {np.round(self._fields[key][1], 12).tolist()})"
                 for key, (what, now) in self._fields_now().items() if not np.array_equal(now, self._fields[key][1])]
        if moved:
            kinds.append("fields")
            said.append(f"{', '.join(moved)}, set outside the session: set it back and command the change with "
                        "update(name=...)")
        if kinds:
            raise ControlError(f"{what}: the problem's {' and '.join(kinds)} changed after the session was made "
                               f"({'; '.join(said)}); the session's state, factors and residual are of the problem "
                               "as it was: make a new Session of the problem as it is now")

    def _fields_now(self):
        """(field, attribute) -> a copy of the arrays the session's field variables set (a uniform
        field's B, a gradient field's B0 and G): what ``_check_unchanged`` compares."""
        out = {}
        for v in self.variables.values():
            f = getattr(v, "field", None)
            for attr in ("B", "B0", "G") if f is not None else ():
                if isinstance(getattr(f, attr, None), np.ndarray):
                    out[(id(f), attr)] = (f"{v.name}'s field {attr}", np.array(getattr(f, attr), float))
        return out

    # ------------------------------------------------------------------ updates --------
    def update(self, lam=None, **values):
        """Move the equilibrium to the load factor ``lam`` (default: unchanged) and new values of
        variables (``name=values``; the others keep theirs); returns the new :class:`State`.

        The command path is followed in sub-steps (module docstring); OptionError for a bad
        command (unknown name, wrong size, not finite, outside the bounds), ControlError when
        the path cannot be followed (the session then stays at its state before the command).

        Example
        -------
        >>> from core_se3 import Problem, Material, mesh
        >>> from core_se3.design import LoadMagnitude
        >>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
        >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
        >>> s = Session(p, 0.5, [LoadMagnitude(p, p.loads[0], name="P")])
        >>> st = s.update(lam=1.0, P=2.0)
        >>> st.lam, st.values["P"].tolist(), st.substeps >= 1
        (1.0, [2.0], True)
        """
        t0 = time.perf_counter()
        self._check_unchanged("update")
        lam0 = self.lam
        lam1 = lam0 if lam is None else _load_factor(lam, "update")
        new = self.commands.parse(values)
        x1 = {k: x for k, x in new.items() if not np.array_equal(x, self.values[k])}
        if not x1 and lam1 == lam0:
            return self.state
        if lam1 != lam0 and self.problem.has_prescribed_motion:
            raise ControlError("update(lam=...) with a prescribed motion of the load factor (rotate_edge, prescribe) "
                               "is not supported by a session; change the variables only, or solve with Problem.solve")
        x0 = {k: self.values[k] for k in x1}
        try:
            g, r, counts = self._follow(lam0, lam1, x0, x1)
            # the renewal and the stability check factor at g: an error or interrupt there too
            # keeps the values of the state (before, the problem kept the new ones under the old state)
            factored, why = self._checked(g, lam1, self._corr.settle(g, lam1, self._stamp, counts[0]))
        except BaseException:
            self._assign(x0)                 # refused or interrupted: the values of the state kept
            raise
        if factored:
            counts = (counts[0], counts[1] + 1) + counts[2:]      # factors at the new state: checked
        if why:
            self._assign(x0)
            self._count(*counts, refused=1)
            raise ControlError(f"update refused: {self._describe(lam0, lam1, x0, x1)} {why}.  The session stays at "
                               "its state before the command")
        self._note_sign(g, lam1)
        self._r, self._g = r, g
        self._count(*counts, updates=1)
        self.state = self._state(g, lam1, Work(*counts, time.perf_counter() - t0))
        self._check_resolution()
        return self.state

    def _checked(self, g, lam, renewed):
        """(factored, why) for the converged state g of an update: with factors made there (a
        renewal, or with ``stability_check`` made here: ``factored``), '' or why the state is
        refused -- a critical point crossed (:meth:`_crossed`), or, with ``stability_check``, a
        singular tangent at g (before, a singular tangent skipped the check and the state was
        accepted)."""
        if not renewed:
            # (an unknown sign so far -- a start whose tangent could not be factored -- is taken
            # here: before, it turned the check off for the whole session, without a word)
            if not self.options.stability_check or self._corr.F_g is g:
                return False, ""
            try:
                self._corr.factor(g, lam, self._stamp, keep=True)
            except (SingularSystemError, ElementTooDistortedError) as exc:
                return False, (f"ends where the tangent cannot be factored ({exc}): a critical point (bifurcation "
                               f"or limit point) at load factor {lam:.6g} itself, where the equilibrium does not "
                               "follow the commands smoothly and its stability is not known")
        why = self._crossed(g, lam)
        return True, f"leads past a critical point: {why}" if why else ""

    def _crossed(self, g, lam):
        """'' or why the state g at lam lies past a critical point: the sign of det K of the held
        factors, made at g, differs from that at the last accepted state where it is known (a
        bifurcation, where the path goes on smoothly and the path test does not see it, or a limit
        point); worded by the direction of the change."""
        sign = self._corr.det_sign() if self._corr.F_g is g else None
        if sign is None or self._sign is None or sign == self._sign:
            return ""
        word = {1: "positive", -1: "negative"}
        why = (f"det K changed sign from {word[self._sign]} at {self._sign_at} to {word[sign]} at the state at load "
               f"factor {lam:.6g}: a critical point (a bifurcation or limit point) lies between them")
        if sign < 0:
            return (why + ", so that equilibrium is unstable and not the one the body takes; go back, or trace the "
                    "path with arc length (core_se3.solvers.arc_length) and a perturbation")
        return (why + "; the states before were on an unstable branch, and the path followed from them need not be "
                "the one the body takes through the critical point; trace it with arc length "
                "(core_se3.solvers.arc_length)")

    def _note_sign(self, g, lam):
        """Record det K's sign at the accepted state g (when factors were made there)."""
        sign = self._corr.det_sign() if self._corr.F_g is g else None
        if sign is not None:
            self._sign, self._sign_at = sign, f"the last accepted state where it was known (load factor {lam:.6g})"

    def _check_resolution(self):
        """A MeshWarning when the state comes within ``magnetics.DIPOLE_RESOLUTION`` element sizes
        of a point dipole (``model.solving.dipole_warning``, as ``Problem.solve`` warns at its
        final state): once when it gets there, again only after it has left (not at every update
        of a control loop)."""
        if not self._near:
            return
        warning = dipole_warning(self._near, self.g, self.lam)
        if warning is not None and not self._unresolved:
            warnings.warn(warning, stacklevel=3)
        self._unresolved = warning is not None

    def _follow(self, lam0, lam1, x0, x1):
        """Follow the command path p0 -> p1 in sub-steps (module docstring): (frames, free
        residual or None, (iterations, factorisations, substeps, splits)); ControlError when
        refused."""
        g, t, dt = self._g, 0.0, 1.0
        its = nf = subs = splits = 0
        r, lam_r = self._r, lam0            # the free residual at (g, lam_r) and the assigned values
        while t < 1.0:
            t_try = min(1.0, t + dt)
            lam_t = lam1 if t_try == 1.0 else lam0 + t_try * (lam1 - lam0)
            if self._turning and lam1 != lam0:
                turn = max(ld.direction_turn(g, lam0 + t * (lam1 - lam0), lam_t) for ld in self._turning)
                if turn > MAX_LOAD_TURN:            # a turning field: the solver's split rule
                    dt = (t_try - t) / max(2.0, np.ceil(turn / (0.95 * MAX_LOAD_TURN)))
                    continue
            linear = r is not None and lam_t == lam_r
            dr = self._assign(x1 if t_try == 1.0 else {k: x0[k] + t_try * (x1[k] - x0[k]) for k in x1},
                              g if linear else None, lam_t)
            r = r + dr if linear and dr is not None else None
            out = self._corr.step(g, lam_t, self._stamp, r0=r)
            its, nf, subs = its + out.iterations, nf + out.factorizations, subs + 1
            if out.ok:
                g, t, r, lam_r = out.g, t_try, out.residual, lam_t
                if out.iterations <= 6:
                    dt = min(2.0 * dt, 1.0)
                continue
            splits += 1
            dt /= 2.0
            if dt < 2.0 ** -self.options.max_splits:
                self._count(its, nf, subs, splits, refused=1)
                at = self._describe(lam0, lam1, x0, x1, t)
                raise ControlError(
                    f"update refused: {self._describe(lam0, lam1, x0, x1)} could not be followed beyond {at} "
                    f"(t = {t:.6g} of the command path; the sub-step to t = {t_try:.6g} failed after "
                    f"{self.options.max_splits} halvings): {out.reason}.  The session stays at its state "
                    "before the command; send a smaller change, or trace the path with arc length "
                    "(core_se3.solvers.arc_length) if it passes a limit point there")
        return g, r, (its, nf, subs, splits)

    def _count(self, its, nf, subs, splits, updates=0, refused=0):
        st = self.stats
        for k, v in (("updates", updates), ("refused", refused), ("substeps", subs), ("splits", splits),
                     ("iterations", its)):
            st[k] += v

    @staticmethod
    def _describe(lam0, lam1, x0, x1, t=None):
        """The command p0 -> p1 (or, with t, the point p0 + t (p1 - p0) of its path) in words."""
        def show(a):
            return np.round(a, 12).tolist() if np.size(a) > 1 else float(np.round(np.ravel(a)[0], 12))
        if t is not None:
            parts = [f"{k} = {show(x0[k] + t * (x1[k] - x0[k]))}" for k in x1]
            return ", ".join(([f"load factor {lam0 + t * (lam1 - lam0):.6g}"] if lam1 != lam0 else []) + parts)
        parts = [f"{k} {show(x0[k])} -> {show(x1[k])}" for k in x1]
        return "the command " + ", ".join(([f"load factor {lam0:g} -> {lam1:g}"] if lam1 != lam0 else []) + parts)

    # ------------------------------------------------------------------ sensitivities --
    def jacobian(self, quantities, variables=None, method="auto"):
        """The total derivatives of ``quantities`` by ``variables`` at the current state
        (``design.sensitivity``) on the session's factors: one back-substitution per variable
        component (direct) or per quantity component (adjoint, transposed solves), whichever is
        fewer; the factors are made afresh only when the held ones are not at this state.

        Parameters
        ----------
        quantities : sequence
            ``design`` quantities, or probe names (their positions, ``ProbePosition``); one
            name or quantity alone is a list of one.
        variables : sequence, optional
            Variable names or ``design`` variables (default all of the session's; one alone
            is a list of one; an empty list is an OptionError).
        method : str
            'auto', 'direct' or 'adjoint'.

        Returns
        -------
        core_se3.design.Sensitivity
            ``values`` and ``jacobian`` (nq, nx).

        Example
        -------
        >>> from core_se3 import Problem, Material, mesh
        >>> from core_se3.design import LoadMagnitude
        >>> p = Problem(mesh.rectangle(10.0, 1.0, 16, 1), Material(1.2e6, 0.0, 0.1))
        >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1e-6)); p.add_probe("tip", "x1")
        >>> s = Session(p, 1.0, [LoadMagnitude(p, p.loads[0], name="P")])
        >>> J = s.jacobian(["tip"]).jacobian                  # d tip / dP = P L^3 / (3 EI): linear range
        >>> round(float(J[2, 0]) / (1e-6 * 10.0 ** 3 / 300), 2)
        1.0
        """
        self._check_unchanged("jacobian")
        qs = [self.quantity(q) for q in _items(quantities)]
        vs = list(self.variables.values()) if variables is None else \
            [v if isinstance(v, Variable) else self.commands.lookup(v) for v in _items(variables)]
        for v in vs:
            self.commands.check(v)
        if not vs:
            raise OptionError("jacobian: no variables to differentiate by (the session's: "
                              f"{', '.join(self.variables) or 'none'}); name at least one")
        c = self._corr
        if c.F is None or c.F_g is not self._g or c.F_stamp != self._stamp:
            c.factor(self._g, self.lam, self._stamp)
        why = self._crossed(self._g, self.lam)
        if why:
            raise ControlError(f"jacobian: the session's state lies past a critical point: {why}; its Jacobian is "
                               "not the plant's response")
        if self._origin is not None:        # on the frames relative to the part (module docstring)
            qs = [OnPart(q, self._origin) for q in qs]
        try:
            return sensitivity(self.problem, self._g, self.lam, qs, vs, method, solve_with=SolveWith(factorization=c.F))
        finally:
            self._material = self.problem.material      # a MaterialVariable's partials restore the law anew

    def quantity(self, q):
        """A ``design`` quantity as given, or the position of the probe named q
        (``ProbePosition``, made once per name)."""
        if isinstance(q, Quantity):
            return q
        if isinstance(q, str):
            cache = self.__dict__.setdefault("_probe_quantities", {})
            if q not in cache:
                cache[q] = ProbePosition(self.problem, q)
            return cache[q]
        raise OptionError(f"jacobian: a quantity is a core_se3.design Quantity or a probe name, got {q!r}")
