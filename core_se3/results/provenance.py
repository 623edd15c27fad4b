"""How a result was computed, recorded in every result document (``provenance``): the package
version, Python and NumPy, the backend (the setting, and what evaluated the steps), the MPI
ranks, the linear solver (the setting and what it resolved to: 'auto' picks by the tangent's
pattern), the element partition of a distributed run, and the peak resident memory of every
rank.  A number is only comparable with another of the same provenance.

Example
-------
>>> from core_se3 import Problem, Material, mesh
>>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
>>> p.clamp("x0")
>>> d = provenance(p, linear_used="banded")
>>> d["package"], d["ranks"], d["linear_solver"]["setting"], d["linear_solver"]["used"]
('core_se3', 1, 'auto', 'banded')
"""
from __future__ import annotations

import platform

import numpy as np

__all__ = ["provenance", "peak_memory"]


def peak_memory():
    """Peak resident memory of this process [bytes] (``getrusage``; None where unavailable).

    Example
    -------
    >>> peak_memory() > 1e6
    True
    """
    try:
        import resource
        import sys
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        return float(rss if sys.platform == "darwin" else rss * 1024)     # Linux: KiB
    except (ImportError, OSError):              # pragma: no cover - not POSIX
        return None


def provenance(problem=None, result=None, ranks=None, linear=None, partition=None, memory=None, backends=None,
               linear_used=None):
    """The provenance record of a result (module docstring).

    Parameters
    ----------
    problem : core_se3.Problem, optional
        What was solved (its backend setting and linear solver).
    result : core_se3.Result, optional
        Its ``parallel`` record (a distributed solve: ranks, linear solver, partition, memory of
        every rank) and the backends of its steps.
    ranks, linear, partition, memory : optional
        What the caller knows instead (a scenario run's context): the number of ranks, the
        distributed linear solver, the element partition (m,) or its summary, the peak memory of
        every rank [bytes].
    backends : list of str, optional
        The backend of every step.
    linear_used : str, optional
        What a serial 'auto' linear solver resolved to (``scenario.provenance.linear_solver_used``).

    Returns
    -------
    dict
        package, version, python, numpy, backend {setting, used}, ranks, linear_solver
        {setting, used}, partition (None serially), peak_memory [bytes] per rank (rank 0's alone
        when every rank solved the whole problem) and solve: how it ran, 'distributed' (over the
        ranks: a ``result.parallel`` record or a ``partition``), 'serial' (one process) or 'serial
        on every rank' (under mpirun, a control that runs serially: every rank solves the whole
        problem, rank 0 writes).
    """
    import sys
    from ..backend import launched_ranks
    version = getattr(sys.modules.get("core_se3"), "__version__", None)     # the package's, imported first
    par = getattr(result, "parallel", None) or {}
    ranks = ranks or par.get("ranks") or launched_ranks()
    mem = memory if memory is not None else par.get("memory_peak") or [peak_memory()]
    if backends is None and result is not None:
        backends = [getattr(s, "backend", "") for s in result.steps]
    used = sorted({b for b in backends or [] if b})
    setting = getattr(problem, "linear_solver", None)
    linear = linear or par.get("linear")
    lin_used = linear or linear_used
    part = partition if partition is not None else par.get("partition")
    solve = "distributed" if par or part is not None else ("serial" if int(ranks) == 1 else "serial on every rank")
    return dict(package="core_se3", version=version, python=platform.python_version(), numpy=np.__version__,
                backend=dict(setting=getattr(problem, "backend_setting", None), used=used),
                ranks=int(ranks), linear_solver=dict(setting=setting if linear is None else linear, used=lin_used),
                partition=_partition(part), peak_memory=[None if m is None else float(m) for m in np.ravel(mem)],
                solve=solve)


def _partition(part):
    """A partition's summary: elements per rank (and the method when given as a dict)."""
    if part is None or isinstance(part, (dict, str)):
        return part
    part = np.asarray(part).astype(np.int64).ravel()
    return dict(elements_per_rank=np.bincount(part).tolist())
