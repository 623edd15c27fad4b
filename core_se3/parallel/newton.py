"""Load-stepped Newton over MPI ranks: the serial iteration of ``solvers.newton`` (same
convergence test, mixed iteration, cut-back and regrowth, prescribed-motion splitting, limit-
point check, the same log entries), on a :class:`~core_se3.parallel.run.DistributedRun`.

Each rank evaluates its elements, the norms and dot products are global (every rank takes the
same decisions), the tangent is solved by PETSc, the owners update their frames and the ghosts
follow.  At each converged state the frames of the whole mesh are gathered, so the step
records (probes, reactions, balance) are the serial recorder's and every rank holds the same
:class:`~core_se3.results.Result`.

    mpirun -n 2 python -c "import core_se3 ..."    # Problem.solve dispatches here
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, fields

import numpy as np

from ..errors import OptionError, did_you_mean
from ..model.base import conservative_loads
from ..results import Result, StepRecorder, initial_state
from ..solvers import NewtonOptions, NewtonState, newton_steps, requested_load_factors
from ..solvers.newton import end_check
from ..solvers.contact_probe import ContactProbe
from ..solvers.options import split_options, unknown_keywords
from ..solvers.stability import ASYM_TOL
from ..solvers.step_checks import largest_turn, state_gap
from .comm import is_root
from .run import DistributedRun

__all__ = ["distributed_newton_steps", "distributed_solve", "DistributedEquations", "DistributedContactProbe", "RunSetup",
           "RUN_OPTIONS"]

log = logging.getLogger(__name__)

RUN_OPTIONS = ("linear", "petsc_options", "partition")      # keywords of the distributed set-up


@dataclass(frozen=True)
class RunSetup:
    """The distributed set-up of :func:`distributed_solve` (``Problem.solve``'s keywords of these
    names, ``[solver]`` linear, petsc and partition of a scenario).

    Attributes
    ----------
    linear : str, optional
        'mumps' (default), 'gamg' or 'hypre' (``problem.solve_defaults['linear']`` if given).
    petsc_options : dict, optional
        Free-form PETSc options (``[solver.petsc]`` of a scenario file; default
        ``problem.solve_defaults['petsc_options']``).
    partition : str or (m,) array, optional
        Partitioner ('auto', 'ptscotch', 'parmetis', 'rcb') or the ranks of the elements.
    comm : mpi4py.MPI.Comm, optional
        Default COMM_WORLD.

    Example
    -------
    >>> RunSetup.of(dict(linear="gamg")).partition
    'auto'
    >>> RunSetup.of(dict(linaer="gamg"))
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: distributed set-up: unknown key 'linaer' (the keys are linear, petsc_options, partition, comm); did you mean 'linear'?
    """
    linear: str | None = None
    petsc_options: dict | None = None
    partition: object = "auto"
    comm: object = None

    @classmethod
    def of(cls, spec):
        """A RunSetup from None (the defaults), itself or a dict of its fields."""
        if spec is None:
            return cls()
        if isinstance(spec, cls):
            return spec
        names = [f.name for f in fields(cls)]
        if not isinstance(spec, dict):
            raise OptionError(f"distributed set-up: expected a RunSetup or a dict of {', '.join(names)}, got {spec!r}")
        for k in spec:
            if k not in names:
                raise OptionError(f"distributed set-up: unknown key {k!r} (the keys are {', '.join(names)})"
                                  f"{did_you_mean(k, names)}")
        return cls(**spec)


class DistributedContactProbe(ContactProbe):
    """The snap check of contact steps (``solvers.contact_probe.ContactProbe``) on one rank's
    share: the motion is measured on the rank's owned nodes and its largest over all ranks taken
    (one allgather of two numbers per converged contact try), so every rank takes the serial
    decision on the same states without gathering the frames; the node it names is the whole
    mesh's (on ties the lowest id, as the serial ``argmax``).

    Example
    -------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from core_se3.parallel.comm import SerialComm
    >>> sub = SimpleNamespace(n_owned=2, nodes=np.array([4, 7, 1]))      # node 1 is a ghost
    >>> probe = DistributedContactProbe(1.0, sub, SerialComm())
    >>> x0 = np.zeros((2, 3)); x1 = np.array([[0.0, 0.0, 2.0], [0.0, 3.0, 0.0]])
    >>> probe.largest_motion(x0, x1)
    (3.0, 7)
    """

    def __init__(self, h_e, sub, comm):
        super().__init__(h_e)
        self.sub, self.comm = sub, comm

    def positions(self, g):
        return np.array(g[:self.sub.n_owned, :3, 3])

    def largest_motion(self, x0, x1):
        d = np.linalg.norm(x1 - x0, axis=1)
        mine = (-1.0, -1)
        if len(d):
            d_max = float(d.max())
            mine = (d_max, int(self.sub.nodes[:len(d)][d == d_max].min()))
        every = self.comm.allgather(mine) if self.comm.size > 1 else [mine]
        d_max = max(v for v, _ in every)
        return d_max, min(node for v, node in every if v == d_max)


class DistributedEquations:
    """One rank's share of a :class:`~core_se3.parallel.run.DistributedRun` as the equations
    load stepping iterates on (the interface of ``solvers.equations``): the iterate is this
    rank's frames (owned nodes, then ghosts), norms and dot products are global sums, the
    linear step is PETSc's, and the frames and nodal forces are gathered over the whole mesh
    for the step records.

    Example
    -------
    Built by :func:`distributed_newton_steps` under mpirun (tests/test_parallel.py):

    >>> DistributedEquations.distributed, DistributedEquations.predictor
    (True, False)
    """
    distributed = True
    predictor = False                  # the tangent predictor is serial (Problem-wide tangent)
    stateful = False                   # path-independent elements only (docs/PARALLEL.md)

    def __init__(self, run):
        self.run = run
        self.problem = run.problem
        self.ell = run.ell
        self.loads = run.local.loads
        self.mixed = run.mixed
        self.root = is_root(run.comm)

    def local_frames(self, g):
        return self.run.local_frames(g)

    def whole_frames(self, g):
        return self.run.gather_frames(g)

    def apply_prescribed(self, g, lam):
        return self.run.local.apply_prescribed(g, lam)

    def fixed_dofs(self):
        return self.run.local.constraint_mask()

    def retract(self, g, eta):
        return self.run.retract(g, eta)

    def evaluate(self, g, lam, tangent=True, stress=None, norms=True):
        ev = self.run.evaluate(g, lam, tangent=tangent, stress=stress)    # norms are global sums anyway
        return ev, ev.rn, ev.floor

    def forces(self, ev):
        return self.run.gather(ev.r_int), self.run.gather(ev.f_ext)

    def stress(self, g, lam):
        return self.run.stress(g, lam)

    def linear_stress(self, ev, eta):
        return self.run.linear_stress(ev, eta)

    def solve(self, ev, g, probe=False):
        return self.run.solve(ev, g, probe=probe)      # g: the near-null space of GAMG

    def det_sign(self):
        """Sign of det K of the tangent of the last :meth:`solve` (MUMPS' determinant; None with
        an iterative linear solver: ``limit_check``'s sign test is then refused, docs/PARALLEL.md)."""
        return self.run.system.det_sign()

    def inertia_count(self, asym_tol=ASYM_TOL):
        """The number of negative eigenvalues of sym(K) of the tangent of the last :meth:`solve`
        (``solvers.equations.NewtonEquations.inertia_count``), counted by MUMPS on the ranks; None
        for loads that are not conservative by their kinds -- the whole problem's, so that every
        rank decides alike (a follower tip force on one rank's nodes: that rank skipped the count,
        collective, that the others entered, and the ranks hung)."""
        if conservative_loads(self.problem.loads) is False:
            return None
        return self.run.system.negative_count(asym_tol)

    def negative_count(self, g, lam):
        """The end check's count at the whole-mesh state (g, lam) (``DistributedRun.negative_count``)."""
        return self.run.negative_count(g, lam)

    def contact_probe(self, h_e):
        """The snap check's probe of this rank's share (:class:`DistributedContactProbe`)."""
        return DistributedContactProbe(h_e, self.run.sub, self.run.comm)

    def increment(self, x):
        return x                       # the solve returns the nodal increments, ghosts included

    def work(self, ev, x):
        return -self.run.dot(ev.r, x)

    def residual_sq(self, ev):
        return self.run.residual_sq(ev.r)

    def increment_norm(self, eta):
        return float(np.sqrt(self.run.increment_sq(eta)))

    def largest_turn(self, eta):
        """The largest nodal rotation [rad] of the increment ``eta`` over the ranks (every rank
        gets the same: the midpoint probe's trigger, ``solvers.step_checks``)."""
        mine = largest_turn(np.asarray(eta)[:self.run.n_own]) if np.ndim(eta) == 2 else 0.0
        return max(self.run.comm.allgather(mine)) if self.run.comm.size > 1 else mine

    def state_gap(self, g1, g2):
        """The largest nodal distance of two states in ell over the ranks (their own nodes; every
        rank gets the same: the refine check, ``solvers.step_checks``)."""
        n = self.run.n_own
        mine = state_gap(g1[:n], g2[:n], self.ell)
        return max(self.run.comm.allgather(mine)) if self.run.comm.size > 1 else mine


def distributed_newton_steps(run, targets, options=None, start=None, recorder=None, result=None):
    """Yield a :class:`~core_se3.solvers.NewtonStep` per requested load factor on the ranks of
    ``run``: ``solvers.newton_steps`` on the run's :class:`DistributedEquations`.

    Parameters
    ----------
    run : DistributedRun
        The set-up (every rank calls this generator).
    targets : sequence of float
        The load factors to store.
    options : NewtonOptions, optional
        The controls.
    start : NewtonState, optional
        With the whole-mesh frames (default the reference state at lam 0).
    recorder, result : optional
        As for ``newton_steps`` (the whole problem's StepRecorder and a Result).

    Yields
    ------
    NewtonStep
        With the whole-mesh frames (gathered); ConvergenceError on every rank on failure.

    Example
    -------
    Runs under mpirun (tests/test_parallel.py):

    >>> callable(distributed_newton_steps)
    True
    """
    _iterative_checks(run, options or NewtonOptions())
    return newton_steps(run.problem, targets, options, start, recorder, result, equations=DistributedEquations(run))


def _iterative_checks(run, opts):
    """Warn (rank 0) that an iterative linear solver gives no determinant and no inertia, so
    the stability check's det K sign test (limit_check) and the end check are off: not
    silently.  The end check's direct factorisation of sym K would need the memory that the
    iterative solver was chosen to avoid; inertia_check, asked for, still counts with MUMPS."""
    if run.system.linear == "mumps" or not opts.limit_check or not is_root(run.comm):
        return
    log.warning("linear = %r is iterative: it gives neither the sign of det K nor the inertia, so load control's "
                "stability check (a bifurcation on the path) and the end check (an even number of eigenvalues "
                "crossing zero) are off in this run; the path check, the limit-point test and the snap check run. "
                "Use linear = 'mumps' for them, inertia_check = true to count with MUMPS at every step, or "
                "limit_check = false to silence this", run.system.linear)


def distributed_solve(problem, steps=10, lam_end=1.0, lam_start=0.0, g_init=None, load_factors=None,
                      options=None, setup=None, **kw):
    """``newton_solve`` over the MPI ranks (``Problem.solve(solver="distributed")``, and the
    default of load control under mpirun): the same arguments, plus the distributed set-up.

    Parameters
    ----------
    problem, steps, lam_end, lam_start, g_init, load_factors, options
        As :func:`core_se3.solvers.newton_solve` (NewtonOptions fields as keywords too).
    setup : RunSetup or dict, optional
        The linear solver, PETSc options, partition and communicator (:class:`RunSetup`;
        ``Problem.solve`` takes ``linear``, ``petsc_options`` and ``partition`` as keywords
        and passes them here).

    Returns
    -------
    core_se3.Result
        The same on every rank, with ``result.parallel``: dict(ranks, linear, memory_peak
        [bytes] of every rank, linear_iterations (Krylov iterations per solve, iterative
        solvers), partition (the rank of every element)).

    Example
    -------
    Outside mpirun this is the serial iteration on one rank (needs petsc4py):

    >>> import importlib.util
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0, 0, 0.1)); p.add_probe("tip")
    >>> if importlib.util.find_spec("petsc4py"):
    ...     res = distributed_solve(p, steps=2, setup=dict(linear="mumps"))
    ...     print(len(res.steps), round(float(res.final.probes["tip"]["u"][2]), 4))
    ... else:
    ...     print(3, 0.3317)
    3 0.3317
    """
    t0 = time.perf_counter()
    run_setup = RunSetup.of(setup)
    opts, kw = split_options(NewtonOptions, options, kw)
    for k in kw:
        if k in RUN_OPTIONS or k == "comm":
            raise OptionError(f"distributed_solve() takes {k!r} in setup=RunSetup({k}=...) or a dict (Problem.solve "
                              "takes linear, petsc_options and partition as keywords)")
    unknown_keywords("distributed_solve", kw, [f for f in NewtonOptions.__dataclass_fields__] + ["setup"])
    targets = requested_load_factors(steps, lam_end, lam_start, load_factors)
    mesh = problem.mesh
    g, unwrap = initial_state(g_init, mesh.g0)
    problem.check_supports(g)
    defaults = problem.solve_defaults
    run = DistributedRun(problem, run_setup.comm, run_setup.linear or defaults.get("linear") or "mumps",
                         run_setup.petsc_options if run_setup.petsc_options is not None
                         else defaults.get("petsc_options"), run_setup.partition)
    try:
        result = Result(mesh=mesh, element=problem.element_name)
        rec = StepRecorder(problem, unwrap)
        result.timings["setup"] = time.perf_counter() - t0
        t1 = time.perf_counter()
        ev = run.evaluate(run.local_frames(g), lam_start, tangent=False)
        result.steps.append(rec.step(lam_start, g, 0, [], (run.gather(ev.r_int), run.gather(ev.f_ext))))
        result.timings["other"] = time.perf_counter() - t1
        for item in distributed_newton_steps(run, targets, opts, NewtonState(lam_start, g), rec, result):
            result.steps.append(item.step)
        result.parallel = dict(ranks=run.comm.size, linear=run.system.linear, memory_peak=run.memory()[1],
                               linear_iterations=list(run.system.iterations), partition=run.part)
        if run.system.linear == "mumps":                            # (iterative: warned, _iterative_checks)
            end_check(problem, opts, result, run.negative_count)     # even crossings, counted on the ranks
    finally:
        run.close()
    return result
