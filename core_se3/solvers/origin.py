"""The origin a far part's iterate is held relative to (:func:`part_origin`): used by load
stepping (``solvers.equations``) and path following (``solvers.system.ShellSystem``) alike.

A part far from the origin stores its positions to an absolute round-off eps |x0|, so the
strains of an iterate carry eps |x0| / h_e (docs/STEPS.md, "Translation invariance").
"""
from __future__ import annotations

import numpy as np

__all__ = ["part_origin", "mesh_origin", "frames_origin"]


def part_origin(problem):
    """The translation c (3,) that load stepping subtracts from the positions of ``problem``'s
    frames (module docstring), or None: per axis the smallest reference coordinate when all of
    them lie within a factor 2 of it (then X - c is exact, Sterbenz' lemma, and a part at x0
    iterates as the same part at 0), else 0; None when a load is not ``translation_invariant``
    or no axis moves.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1, x0=1e9), Material(1.2e6, 0.0, 0.1))
    >>> p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> part_origin(p).tolist(), part_origin(Problem(mesh.rectangle(10.0, 1.0, 4, 1), p.material))
    ([1000000000.0, 0.0, 0.0], None)
    """
    if not all(getattr(ld, "translation_invariant", False) for ld in problem.loads):
        return None
    return mesh_origin(problem)


def mesh_origin(problem):
    """:func:`part_origin` of the mesh alone (whatever the loads): the translation c (3,) whose
    subtraction from its reference positions is exact, or None.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> mesh_origin(Problem(mesh.rectangle(10.0, 1.0, 4, 1, x0=1e9), Material(1.2e6, 0.0, 0.1))).tolist()
    [1000000000.0, 0.0, 0.0]
    """
    X = problem.mesh.g0[:, :3, 3]
    lo, hi = X.min(0), X.max(0)
    c = np.where((lo > 0) & (hi <= 2 * lo), lo, np.where((hi < 0) & (lo >= 2 * hi), hi, 0.0))
    return c if np.any(c != 0) else None


def frames_origin(problem, g, origin=None):
    """``origin`` (default :func:`mesh_origin`) when the positions of the frames ``g`` lie near
    it (within half of it on each axis it moves: a far part's frames in the problem's
    coordinates), else None (a part near the origin, or frames already relative to it).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1, x0=1e9), Material(1.2e6, 0.0, 0.1))
    >>> g = p.mesh.g0.copy(); g[:, 0, 3] -= 1e9
    >>> frames_origin(p, p.mesh.g0).tolist(), frames_origin(p, g)
    ([1000000000.0, 0.0, 0.0], None)
    """
    c = mesh_origin(problem) if origin is None else origin
    if c is None:
        return None
    x = np.asarray(g)[..., :3, 3]
    return c if np.all(np.abs(x - c) <= 0.5 * np.abs(c), where=(c != 0)) else None
