"""Layer 6b, parallel: load-stepped Newton over MPI ranks with PETSc (docs/PARALLEL.md).

Elements are partitioned (PT-Scotch through PETSc, or coordinate bisection), every rank builds
the Problem of its elements (``local``: a sub-mesh, the unchanged element kernels, loads kept
where they act once) and assembles through PETSc COO into an MPIAIJ tangent (``system``,
``coo``); frames live with their owners and are ghost-updated after each exponential update;
norms and decisions are global (``newton``).  ``Problem.solve`` dispatches load control here
under ``mpirun -n N`` (N > 1) or with ``solver="distributed"``; importing this package imports
neither mpi4py nor petsc4py.

Example
-------
>>> from core_se3.model import SOLVERS
>>> SOLVERS["distributed"] is distributed_solve
True
"""
from ..model.problem import SOLVERS
from .comm import SerialComm, collective, is_root, world
from .localize import LocalView, localize_load, localize_support
from .local import Subdomain, local_problem, subdomain
from .newton import RUN_OPTIONS, RunSetup, distributed_newton_steps, distributed_solve
from .partition import PARTITIONERS, dual_graph, node_owners, partition_elements, rcb
from .run import DistributedRun, GlobalEvaluation

__all__ = ["distributed_solve", "RunSetup", "distributed_newton_steps", "DistributedRun", "GlobalEvaluation", "Subdomain",
           "subdomain", "local_problem", "LocalView", "localize_load", "localize_support", "partition_elements",
           "rcb", "dual_graph", "node_owners", "PARTITIONERS", "SerialComm", "world", "collective", "is_root",
           "RUN_OPTIONS"]

SOLVERS["distributed"] = distributed_solve
