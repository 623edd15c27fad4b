"""Layer 6, solvers: sparse linear algebra, unit-scaled convergence tests, the option dataclasses,
load-stepped Newton and path following (arc length, displacement control), each a generator of
converged steps with a wrapper that returns a Result, and the stability analysis.

Importing this package registers the solvers that ``Problem.solve(control=...)`` uses:
'load' (:func:`newton_solve`), 'arclength' (:func:`arc_length`), 'displacement'
(:func:`displacement_control`) and 'linear' (:func:`linear_solve`: one solve at the reference state).

Example
-------
>>> from core_se3 import Problem, Material, mesh
>>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
>>> p.clamp("x0"); p.add_edge_moment("x1", (0, -0.1, 0)); p.add_probe("tip")
>>> [len(p.solve(steps=2).steps), len(p.solve(control="arclength", dlam0=0.5).steps)]
[3, 3]
"""
from ..model.solving import LINEAR_SOLVERS, SOLVERS
from .arclength import ArcState, PathEvent, PathInfo, path_follow, path_steps
from .shell_paths import PathStep, arc_length, arc_length_steps, displacement_control
from .convergence import increment_norm, relative_residual, scaled_norm
from .equations import NewtonEquations
from .linear import linear_solve, linear_state
from .direct import have_petsc
from .linalg import AUTO_MUMPS_MIN, Factorization, available_solvers, checked_solve, make_solver
from .newton import (MAX_PRESCRIBED_TURN, NewtonState, NewtonStep, newton_solve, newton_steps,
                     requested_load_factors)
from .options import ArcLengthOptions, NewtonOptions
from .stability import CriticalPoint, PathPoint, inertia, limit_point_hint, smallest_mode
from .system import AlgebraicSystem, ShellSystem

__all__ = ["newton_solve", "newton_steps", "NewtonState", "NewtonStep", "requested_load_factors",
           "MAX_PRESCRIBED_TURN", "NewtonOptions", "ArcLengthOptions", "arc_length",
           "arc_length_steps", "displacement_control", "path_follow", "path_steps", "ArcState",
           "PathEvent", "PathInfo", "PathStep", "CriticalPoint", "PathPoint", "inertia",
           "smallest_mode", "limit_point_hint", "ShellSystem", "AlgebraicSystem", "make_solver",
           "available_solvers", "checked_solve", "Factorization", "AUTO_MUMPS_MIN", "scaled_norm",
           "relative_residual", "increment_norm", "NewtonEquations", "linear_solve", "linear_state"]


def _arclength(problem, steps=None, lam_end=1.0, **kw):
    """Problem.solve(control='arclength'): the first load-factor step dlam0 defaults to
    lam_end / steps when steps are given (as in scenario files)."""
    if steps is not None and "dlam0" not in kw:
        kw["dlam0"] = lam_end / steps
    return arc_length(problem, lam_end=lam_end, **kw)


SOLVERS.update(load=newton_solve, arclength=_arclength, displacement=displacement_control, linear=linear_solve)
LINEAR_SOLVERS.update(auto=lambda: None, banded=lambda: None, superlu=lambda: None,
                      mumps=lambda: None if have_petsc() else "needs petsc4py (Debian: python3-petsc4py), not "
                                                              "installed here")
