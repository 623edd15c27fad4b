"""The provenance of scenario runs and catalogue results (``results.provenance``): what a serial
'auto' linear solver resolves to, and the record of a run from its context (ranks, distributed
linear solver, partition, peak memory of every rank).

Example
-------
>>> from core_se3 import Problem, Material, mesh
>>> p = Problem(mesh.rectangle(4.0, 4.0, 4, 4), Material(1e3, 0.0, 0.01)); p.clamp("x0")
>>> problem_provenance(p)["linear_solver"]
{'setting': 'auto', 'used': 'banded'}
"""
from __future__ import annotations

import numpy as np

from ..results.provenance import peak_memory, provenance

__all__ = ["linear_solver_used", "problem_provenance", "run_provenance", "ranks_memory"]


def linear_solver_used(problem, setting=None):
    """The factorisation a serial solve of ``problem`` uses: the setting itself, or for 'auto' the
    one its tangent's pattern gets (``solvers.linalg.AutoSolver.choice``: banded, superlu or
    mumps; the choice depends on the pattern only).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(4.0, 4.0, 4, 4), Material(1e3, 0.0, 0.01)); p.clamp("x0")
    >>> linear_solver_used(p), linear_solver_used(p, "superlu")
    ('banded', 'superlu')
    """
    setting = setting or problem.linear_solver
    if setting != "auto":
        return setting
    from ..solvers.direct import CsrArrays
    from ..solvers.linalg import AutoSolver
    asm = problem.assembler()
    return AutoSolver().choice(CsrArrays(np.zeros(asm.nnz), asm.indices, asm.indptr, (asm.nfree, asm.nfree)))


def problem_provenance(problem, result=None):
    """The provenance of a solve of ``problem`` (its Result's ``parallel`` record when it ran
    distributed)."""
    par = getattr(result, "parallel", None)
    return provenance(problem, result, linear_used=None if par else linear_solver_used(problem))


def ranks_memory(ctx):
    """Peak memory of every rank [bytes] (collective in a distributed run)."""
    run = getattr(ctx, "run", None)
    return run.memory()[1] if run is not None else [peak_memory()]


def run_provenance(scn, ctx):
    """The provenance of a scenario run in its context (``scenario.context``)."""
    prob = scn.problem
    run = getattr(ctx, "run", None)
    if run is None:
        return provenance(prob, ranks=ctx.ranks, linear_used=linear_solver_used(prob))
    part = dict(method=scn.solver.get("partition", "auto"),
                elements_per_rank=np.bincount(np.asarray(run.part, np.int64).ravel()).tolist())
    return provenance(prob, ranks=ctx.ranks, linear=run.system.linear, partition=part, memory=ranks_memory(ctx))
