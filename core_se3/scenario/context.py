"""Where a scenario run computes and who writes: serially (one process does both), or over MPI
ranks (``mpirun -n N core-se3 run FILE.toml``, N > 1): every rank takes part in the
distributed Newton iteration (``core_se3.parallel``), rank 0 alone writes the VTU files (the
element's cell fields gathered from the ranks), the checkpoint (with the element partition, so
that a resumed run with the same number of ranks repeats the same computations), the results
JSON, the plots and the log lines.
"""
from __future__ import annotations

import numpy as np

from ..backend import launched_rank, launched_ranks
from ..solvers import newton_steps
from ..solvers.newton import end_check

__all__ = ["RunContext", "run_context", "on_root"]


class RunContext:
    """The serial run: this process computes and writes (under an MPI launcher, e.g. an
    arc-length run that every rank computes alike, rank 0 alone writes).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> ctx = RunContext(p)
    >>> ctx.root, ctx.ranks
    (True, 1)
    """

    def __init__(self, problem):
        self.problem = problem
        self.root = launched_rank() == 0
        self.ranks = launched_ranks()      # under mpirun every rank solves the whole problem
        if self.root:
            # the coarse-mesh warning, as Problem.solve gives it (the runner drives the solvers
            # itself, not through Problem.solve; the distributed context warns in its set-up)
            problem.check_element(stacklevel=5)

    def barrier(self):
        return None

    def initial_forces(self, g):
        ev = self.problem.evaluate(g, 0.0, tangent=False)
        return ev.r_int, ev.f_ext

    def steps(self, targets, options, start, recorder, result):
        return newton_steps(self.problem, targets, options, start=start, recorder=recorder, result=result)

    def end_check(self, options, result):
        """``solvers.end_check`` on ``result`` (its steps: the load-control path from the run's
        start): a ConvergenceError naming the step when negative eigenvalues rose unseen."""
        end_check(self.problem, options, result)

    def cell_fields(self, g, increments=None):
        """The element's cell fields at g (``increments``: a linear analysis', see
        ``fem.Element.cell_fields``)."""
        if increments is None:
            return self.problem.element.cell_fields(g)
        return self.problem.element.cell_fields(g, increments=increments)

    def checkpoint_arrays(self):
        return None

    def close(self):
        return None


class DistributedContext(RunContext):
    """A run over the MPI ranks (module docstring); ``state`` a resumed checkpoint or None.

    Example
    -------
    >>> DistributedContext.__mro__[1].__name__
    'RunContext'
    """

    def __init__(self, problem, solver, state=None):
        from ..parallel import DistributedRun, world
        self.problem = problem
        comm = world()
        part = solver.get("partition", "auto")
        if state is not None and "partition" in state.get("arrays", {}) \
                and state["extra"].get("ranks") == comm.size:
            part = np.asarray(state["arrays"]["partition"]).astype(np.int64)
        self.run = DistributedRun(problem, comm, solver.get("linear", "mumps"), solver.get("petsc") or None, part)
        self.comm = comm
        self.root = comm.rank == 0
        self.ranks = comm.size

    def barrier(self):
        self.comm.Barrier()

    def initial_forces(self, g):
        run = self.run
        ev = run.evaluate(run.local_frames(g), 0.0, tangent=False)
        return run.gather(ev.r_int), run.gather(ev.f_ext)

    def steps(self, targets, options, start, recorder, result):
        from ..parallel import distributed_newton_steps
        return distributed_newton_steps(self.run, targets, options, start=start, recorder=recorder, result=result)

    def end_check(self, options, result):
        """The end check with the counts taken on the ranks (``DistributedRun.negative_count``)."""
        end_check(self.problem, options, result, self.run.negative_count)

    def cell_fields(self, g, increments=None):
        """The element's cell fields of the whole mesh on rank 0 (None elsewhere), each rank
        computing its elements' (load control only: ``increments``, a linear analysis', is None)."""
        run = self.run
        mine = run.local.element.cell_fields(run.local_frames(g))
        parts = self.comm.gather((run.sub.elements, mine), root=0)
        if not self.root:
            return None
        m = self.problem.mesh.n_elements
        out = {}
        for ids, fields in parts:
            for k, v in fields.items():
                v = np.asarray(v)
                if k not in out:
                    out[k] = np.zeros((m,) + v.shape[1:])
                out[k][ids] = v
        return out

    def checkpoint_arrays(self):
        return {"partition": self.run.part.astype(float)}

    def close(self):
        self.run.close()


def run_context(problem, solver, arc=False, state=None):
    """The :class:`DistributedContext` of a load-controlled run under an MPI launcher with more
    than one rank, else the serial :class:`RunContext` (arc length runs serially on every rank).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> type(run_context(Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01)), {})).__name__
    'RunContext'
    """
    if arc or launched_ranks() == 1:
        return RunContext(problem)
    return DistributedContext(problem, solver, state)




def on_root(fn):
    """Call ``fn()`` on rank 0 only of an MPI launch (the one process of a serial run) and raise its
    error on every rank, so that all ranks stop alike (e.g. an output directory that holds another
    run, or one that cannot be made: an OSError, which rank 0 alone meets).  Returns fn's value
    (picklable: every rank gets rank 0's).

    Example
    -------
    >>> on_root(lambda: 42)
    42
    """
    if launched_ranks() == 1:
        return fn()
    from ..parallel import world
    comm = world()
    out, caught = None, None
    if comm.rank == 0:
        try:
            out = fn()
        except Exception as exc:           # any: the other ranks wait for rank 0's word (no hang)
            caught = exc
    err, out = comm.bcast((None if caught is None else (type(caught), str(caught)), out), root=0)
    if caught is not None:
        raise caught
    if err is not None:
        raise _rebuilt(*err)
    return out


def _rebuilt(cls, message):
    """The exception ``cls(message)`` of another rank (a CoreSE3Error with the message for a type
    that takes other arguments)."""
    from ..errors import CoreSE3Error
    try:
        return cls(message)
    except Exception:
        return CoreSE3Error(message)
