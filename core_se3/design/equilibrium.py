"""Equilibria of a design: every evaluation starts from the last equilibrium of its pose and
follows the path in the design variables to the new values (x(t) = x_old + t (x_new - x_old),
t from 0 to 1, Newton with exponential updates at each t, halving the step of t on a failure).
Only when the path cannot be followed (after ``max_cutbacks`` halvings) is the pose solved
again from the flat state by load stepping (``Problem.solve``).

The residual is linear in most design variables (field, magnetisation, load magnitudes), so
the first Newton iterate from the old state is the tangent predictor of the direct method:
a small design step converges in two or three iterations.

Each new design point whose element changed (a material variable rebuilds it: thickness, E) has
the element's coarse-mesh check of ``Problem.solve`` (``Problem.check_element``: an element
along a free edge with phi^3 L / h > 2), once per accepted point, not per Newton iteration or
substep, and said at most once per design run (:class:`ElementCheck`): an optimiser that thins
a curved shell can otherwise walk into the coarse-mesh regime silently.

Example
-------
>>> import numpy as np
>>> from core_se3 import Problem, Material, mesh
>>> from core_se3.design import LoadMagnitude
>>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
>>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
>>> v = LoadMagnitude(p, p.loads[0])
>>> st = solve_flat(p, [v], [np.array([1.0])])
>>> st2, info = follow(p, [v], [np.array([1.5])], st)
>>> info["iterations"] <= 6, info["restarted"]
(True, False)
"""
from __future__ import annotations

import time
import warnings
from contextlib import contextmanager
from types import SimpleNamespace
from dataclasses import dataclass, field

import numpy as np

from ..backend import launched_rank
from ..errors import ConvergenceError, ElementTooDistortedError, ElementWarning
from ..solvers import NewtonOptions, make_solver
from ..solvers.newton_try import NewtonTry, augmented_try, hooked_loads

__all__ = ["EquilibriumState", "EquilibriumOptions", "ElementCheck", "follow", "solve_flat", "assign_all",
           "multipliers", "restore_multipliers"]


@dataclass(frozen=True)
class EquilibriumOptions:
    """Controls of the design's equilibrium solves.

    rtol, dtol: relative residual and increment tolerances (tight: the sensitivities are those of
    the exact equilibrium); max_iter: Newton iterations per try; max_cutbacks: halvings of the
    step in the design variables before a restart from the flat state; flat_steps: load steps of
    such a restart (and of a pose's first solve); linear_solver: None = the problem's.

    Example
    -------
    >>> EquilibriumOptions().rtol, EquilibriumOptions(flat_steps=4).flat_steps
    (1e-12, 4)
    """
    rtol: float = 1e-12
    dtol: float = 1e-12
    max_iter: int = 25
    max_cutbacks: int = 8
    flat_steps: int = 10
    linear_solver: str | None = None


@dataclass
class EquilibriumState:
    """A converged state of a pose: frames g, load factor lam, and the values x of the design
    variables (one array per variable) it is in equilibrium for.

    Example
    -------
    >>> import numpy as np
    >>> EquilibriumState(np.eye(4)[None], 1.0, [np.zeros(2)]).lam
    1.0
    """
    g: np.ndarray
    lam: float
    x: list
    stats: dict = field(default_factory=dict)
    multipliers: list | None = None


def design_point(variables, xs, most=6):
    """'label = value, ...' of the values xs (one array per variable), at most ``most`` of them.

    Example
    -------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> design_point([SimpleNamespace(labels=["h[0]", "h[1]"])], [np.array([0.1, 0.25])])
    'h[0] = 0.1, h[1] = 0.25'
    """
    pairs = [(lab, float(val)) for v, x in zip(variables, xs)
             for lab, val in zip(v.labels, np.atleast_1d(np.asarray(x, float)))]
    text = ", ".join(f"{lab} = {val:.6g}" for lab, val in pairs[:most])
    return text + (f", ... ({len(pairs)} values)" if len(pairs) > most else "")


class ElementCheck:
    """The element's coarse-mesh check (``Problem.check_element``, which ``Problem.solve`` gives
    every solve) along the equilibria of a design: at a design point whose element is not the
    one last checked (a material variable rebuilds it for its thickness or E), once per
    accepted point, each cause (the only one now: an element along a free edge with
    phi^3 L / h > 2) said at most once per design run, naming the design point where it was
    first met.  ``Design`` keeps one per run; :func:`follow` and :func:`solve_flat` make their
    own when not given one.

    Parameters
    ----------
    problem : core_se3.Problem, optional
        Its element counts as checked (the state a :func:`follow` starts from was solved).

    Attributes
    ----------
    said : dict
        cause -> the design point ('label = value, ...') where it was said.

    Example
    -------
    >>> import warnings
    >>> import numpy as np
    >>> from core_se3.catalogue import shell_course as sc
    >>> from core_se3.design import MaterialVariable
    >>> p, _ = sc.scordelis_lo(2, h=0.25)                      # phi^3 L / h = 1.78 on the free edge
    >>> h, check = MaterialVariable(p, [np.arange(4)], "h"), ElementCheck()
    >>> with warnings.catch_warnings(record=True) as said:
    ...     warnings.simplefilter("always")
    ...     for x in (0.25, 0.1, 0.05):                        # 4.4 and 8.9: coarse
    ...         h.assign([x]); check(p, [h], [np.array([x])])
    >>> len(said), check.said
    (1, {'coarse thin curved': 'h[0] = 0.1'})
    """

    CAUSE = "coarse thin curved"

    def __init__(self, problem=None):
        self.said = {}
        self._checked = None if problem is None else (problem.element, problem.mesh)

    def reset(self):
        """A new design run: nothing checked or said yet."""
        self.said, self._checked = {}, None

    def __call__(self, problem, variables, xs, stacklevel=2):
        """Check ``problem``'s element at the design point xs (the variables' values) unless it
        is the element last checked or the cause has been said (``stacklevel``: the warning's,
        counted from the caller)."""
        key = (problem.element, problem.mesh)
        if self._checked is not None and all(a is b for a, b in zip(key, self._checked)):
            return
        self._checked = key
        if self.CAUSE in self.said:
            return
        where = design_point(variables, xs)
        note = (f"The design's equilibrium met this first at the design point {where} (said once per design run; "
                f"the optimiser's later points may be as coarse).")
        # every rank of a distributed design checks the same whole problem: rank 0 says it
        if problem.check_element(warn=launched_rank() == 0, stacklevel=stacklevel + 1, note=note) is not None:
            self.said[self.CAUSE] = where

    @contextmanager
    def quiet(self, always=False):
        """A context in which ``Problem.solve``'s own coarse-mesh warning (an ElementWarning) is
        dropped: always (a design's solve from the flat state, which this check covers) or once
        this check has said it (the outputs' load paths after a design run)."""
        with warnings.catch_warnings():
            if always or self.said:
                warnings.simplefilter("ignore", ElementWarning)
            yield


def multipliers(problem):
    """The multipliers of the problem's augmented-Lagrangian loads (contact), one array per
    load (``Load.multipliers``), or None without such loads."""
    return [ld.multipliers() for ld in hooked_loads(problem, "update_multipliers")] or None


def restore_multipliers(problem, state):
    """Give the problem's augmented-Lagrangian loads the multipliers of ``state`` (an
    EquilibriumState): the contact forces, the tangent and so the sensitivities at a state are
    those of its own multipliers, not of the last solve's (another pose, a rejected trial)."""
    if state.multipliers is not None:
        for ld, m in zip(hooked_loads(problem, "update_multipliers"), state.multipliers):
            ld.set_multipliers(m)


def assign_all(variables, xs):
    """Assign the values xs (one array per variable) to the variables.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.design import LoadMagnitude
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01)); p.add_edge_force("x1", (0, 0, 1.0))
    >>> v = LoadMagnitude(p, p.loads[0]); assign_all([v], [np.array([2.0])]); v.P
    2.0
    """
    for v, x in zip(variables, xs):
        v.assign(x)


@contextmanager
def _load_stepping_defaults(problem):
    """The problem's ``solve_defaults`` (a scenario's [solver]) reduced to the options of load
    stepping while a design solves from the flat state by load stepping: a scenario traced by
    arc length keeps its path-following keys (method, dlam0, psi, ...) there, which load
    stepping refused with "newton_solve() got an unknown option 'method'"."""
    saved = problem.solve_defaults
    problem.solve_defaults = {k: v for k, v in saved.items() if k in NewtonOptions.__dataclass_fields__}
    try:
        yield
    finally:
        problem.solve_defaults = saved


def solve_flat(problem, variables, xs, lam=1.0, options=None, check=None, as_run=False):
    """Solve from the flat (reference) state by load stepping at the values xs.

    ``as_run``: with the problem's own steps and stability check (its ``solve_defaults``: a
    scenario's [solver], what ``core-se3 run`` of the optimised scenario does: a critical point
    on the path stops it with a ConvergenceError), not ``options.flat_steps`` and none.

    The element's coarse-mesh check is ``check``'s (an :class:`ElementCheck`; default a new
    one), which names the design point, in place of the one ``Problem.solve`` gives.

    Returns: EquilibriumState (``stats``: iterations, time).  ConvergenceError if it fails.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.design import LoadMagnitude
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01)); p.clamp("x0")
    >>> p.add_edge_force("x1", (0, 0, 1e-3)); v = LoadMagnitude(p, p.loads[0])
    >>> solve_flat(p, [v], [np.array([1.0])]).stats["restarted"]
    True
    """
    opts = options or EquilibriumOptions()
    t0 = time.perf_counter()
    assign_all(variables, xs)
    kw = dict(rtol=max(opts.rtol, 1e-12), dtol=max(opts.dtol, 1e-12), max_iter=opts.max_iter)
    if opts.linear_solver:
        kw["linear_solver"] = opts.linear_solver
    check = check or ElementCheck()
    check(problem, variables, xs, stacklevel=2)
    problem.element                                 # built (and its own warnings given) outside the quiet part
    steps, limit = opts.flat_steps, False
    if as_run:
        steps = problem.solve_defaults.get("steps", steps)
        limit = problem.solve_defaults.get("limit_check", True)
    with check.quiet(always=True), _load_stepping_defaults(problem):      # said above, with the design point
        res = problem.solve(steps=steps, lam_end=lam, control="load", limit_check=limit, **kw)
    its = sum(e["iterations"] for e in res.log)
    return EquilibriumState(res.final.g.copy(), lam, [np.array(x, float) for x in xs],
                            dict(iterations=its, substeps=len(res.log), cutbacks=0, restarted=True,
                                 time=time.perf_counter() - t0), multipliers(problem))


def _newton(problem, g, lam, opts, solver, run=None):
    """Newton at fixed parameters from g (the load-stepping try of ``solvers.newton_try``,
    mixed iteration included): (g, iterations) or (None, iterations) on failure.  With ``run``
    (a ``parallel.DistributedRun`` of ``problem``) the try runs on the ranks' shares, its loads
    localised again for the current values of the variables; g in and out is the whole mesh's."""
    nopts = NewtonOptions(rtol=opts.rtol, dtol=opts.dtol, max_iter=opts.max_iter, limit_check=False)
    timer = SimpleNamespace(t_asm=0.0, t_sol=0.0)
    if run is not None:
        from ..parallel.newton import DistributedEquations
        run.relocalize()
        eq = DistributedEquations(run)
        trial = NewtonTry(problem, nopts, None, timer, eq)
        mip = nopts.iteration == "mip" and eq.mixed
        g_start = eq.local_frames(g)
    else:
        eq = None
        trial = NewtonTry(problem, nopts, solver, timer)
        mip = nopts.iteration == "mip" and problem.element.mixed and not problem.element.stateful
        g_start = g.copy()
    trial.first_solve = False                       # a singular tangent fails the try, as any
    try:
        stress = (eq.stress(g_start, lam) if eq is not None else problem.evaluate(g, lam, tangent=False).stress) \
            if mip else None
    except (ElementTooDistortedError, FloatingPointError):
        return None, 0
    # with the multiplier updates of a contact in mode 'al' (Uzawa, as Problem.solve): the gap
    # error within its tolerance, not the penalty solution of the multipliers last left
    aug = hooked_loads(eq if eq is not None else problem, "update_multipliers")
    out = augmented_try(trial, aug, g_start, lam, mip, stress, nopts.max_augmentations, lambda o, k: None)
    if not out.ok:
        return None, out.iterations
    return (eq.whole_frames(out.g) if eq is not None else out.g), out.iterations


def follow(problem, variables, xs, state, options=None, run=None, check=None):
    """Follow the equilibrium of ``state`` to the variables' values xs (module docstring).

    Parameters
    ----------
    problem : core_se3.Problem
        The problem.
    variables : sequence of Variable
        The variables (all those the pose's state records).
    xs : sequence of arrays
        Their new values.
    state : EquilibriumState
        The last equilibrium of the pose.
    options : EquilibriumOptions, optional
        The controls.
    run : core_se3.parallel.DistributedRun, optional
        Solve on the MPI ranks (a design under mpirun).
    check : ElementCheck, optional
        The element's coarse-mesh check of the new point (a design run's; default a new one
        that takes the problem's element at the start as checked).

    Returns
    -------
    (EquilibriumState, dict)
        The new state and stats (iterations, substeps, cutbacks, restarted, time).  A failure of
        the restart from the flat state is a ConvergenceError.

    Example
    -------
    See the module docstring.

    >>> EquilibriumOptions().max_cutbacks
    8
    """
    opts = options or EquilibriumOptions()
    t0 = time.perf_counter()
    check = check or ElementCheck(problem)
    solver = make_solver(opts.linear_solver or problem.linear_solver)
    x0 = [np.array(x, float) for x in state.x]
    x1 = [np.array(x, float) for x in xs]
    g, t, dt = state.g, 0.0, 1.0
    its = subs = cuts = 0
    restore_multipliers(problem, state)
    if all(np.array_equal(a, b) for a, b in zip(x0, x1)):
        assign_all(variables, x1)
        info = dict(iterations=0, substeps=0, cutbacks=0, restarted=False, time=0.0)
        return EquilibriumState(g, state.lam, x1, info, state.multipliers), info
    last = state
    while t < 1.0:
        t_try = min(1.0, t + dt)
        assign_all(variables, [a + t_try * (b - a) for a, b in zip(x0, x1)])
        g_new, k = _newton(problem, g, state.lam, opts, solver, run)
        its += k
        subs += 1
        if g_new is not None:
            g, t = g_new, t_try
            last = EquilibriumState(g, state.lam, x1, {}, multipliers(problem))
            if k <= 4:
                dt = min(2 * dt, 1.0)
            continue
        restore_multipliers(problem, last)          # those of the last point reached, not the failed try's
        cuts += 1
        dt /= 2
        if cuts > opts.max_cutbacks:
            try:
                st = solve_flat(problem, variables, x1, state.lam, opts, check)
            except ConvergenceError as exc:
                raise ConvergenceError(f"the design's equilibrium could not be followed to the new values, nor "
                                       f"solved again from the flat state: {exc}", exc.result) from None
            info = dict(iterations=its + st.stats["iterations"], substeps=subs, cutbacks=cuts, restarted=True,
                        time=time.perf_counter() - t0)
            return EquilibriumState(st.g, state.lam, x1, info), info
    check(problem, variables, x1, stacklevel=2)     # the accepted point's element (not every substep's)
    info = dict(iterations=its, substeps=subs, cutbacks=cuts, restarted=False, time=time.perf_counter() - t0)
    return EquilibriumState(g, state.lam, x1, info, last.multipliers), info
