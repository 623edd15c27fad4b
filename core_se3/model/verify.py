"""Verification tools: finite-difference tangent checks and zero-energy-mode counts.

``tangent_fd_check`` compares the assembled tangent with central differences of the residual
along the exponential update g_i <- g_i exp(eps eta_i) -- the derivative the Newton solver
needs.  Tests of elements, loads and supports reuse it.
"""
from __future__ import annotations

import numpy as np

from .. import lie
from ..assembly import Assembler

__all__ = ["tangent_fd_check", "zero_modes", "fd_step"]

FD_STEP = 1e-6


def _all_free(problem):
    """An assembler with every dof free (supports ignored)."""
    return Assembler(problem.mesh, np.ones(6 * problem.mesh.n_nodes, bool))


def fd_step(problem, h=FD_STEP):
    """The step of :func:`tangent_fd_check`: ``h``, or a tenth of the narrowest smoothing band of
    the problem's constraint loads (a contact's ``eps`` [length], 1e-6 h by default), whichever
    is smaller.  Across the band the contact force law has the kinks of its C^1 ramp: a central
    difference whose step spans one sees a jump of the stiffness, not the derivative (a correct
    contact tangent measured 0.16 at the step 1e-6 with the band 1e-8, 4.7e-9 at 1e-9).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 0.1, 2, 1), Material(1e4, 0.0, 0.01))
    >>> fd_step(p), fd_step(p.add_obstacle("half_space", point=(0, 0, -0.01), normal=(0, 0, 1)) and p)
    (1e-06, 1e-09)
    """
    bands = [float(ld.eps) for ld in problem.loads
             if getattr(ld, "constraint_force", False) and getattr(ld, "eps", None)]
    return min([h] + [0.1 * b for b in bands])


def tangent_fd_check(problem, g, lam=1.0, h=None, free_all=False):
    """Max relative difference between the tangent and central FD of the residual.

    With ``free_all`` every dof is treated as free (supports ignored).  Returns
    (relative error, K dense, K_fd dense).

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (element, loads and supports).
    g : (n, 4, 4) array
        The state at which to compare (set prescribed frames first: ``apply_prescribed``).
    lam : float, optional
        Load factor.
    h : float, optional
        Step of the central differences along g_i <- g_i exp(+-h e_k); default :func:`fd_step`
        (1e-6, smaller in a problem with contact: below its smoothing band).
    free_all : bool, optional
        Compare on all 6n dofs instead of the free ones.

    Returns
    -------
    err : float
        max |K - K_fd| / max |K_fd|: about h^2 for a consistent tangent.
    K, K_fd : ndarray
        The dense tangent and its finite-difference approximation.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh, lie
    >>> p = Problem(mesh.rectangle(1.0, 0.5, 2, 1), Material(1e3, 0.3, 0.05))
    >>> p.clamp("x0")
    >>> g = p.mesh.g0 @ lie.exp(0.1 * np.random.default_rng(0).standard_normal((6, 6)))
    >>> bool(tangent_fd_check(p, p.apply_prescribed(g, 0.0))[0] < 1e-6)
    True
    """
    h = fd_step(problem) if h is None else h
    asm = _all_free(problem) if free_all else problem.assembler()
    K = problem.tangent(g, lam, asm).toarray()
    Kfd = np.zeros_like(K)
    for k in range(asm.nfree):
        e = np.zeros(asm.nfree)
        e[k] = h
        d = asm.scatter(e)
        Kfd[:, k] = (problem.residual(g @ lie.exp(d), lam, asm)
                     - problem.residual(g @ lie.exp(-d), lam, asm)) / (2 * h)
    err = np.abs(K - Kfd).max() / max(np.abs(Kfd).max(), 1e-300)
    return err, K, Kfd


def zero_modes(problem, g=None, lam=0.0, rel=1e-10):
    """Eigenvalues of the symmetric part of the free-free tangent, sorted by magnitude,
    and the number below rel * lambda_max.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (supports ignored: every dof free).
    g : (n, 4, 4) array, optional
        The state (default the reference frames); ``lam``: the load factor.
    rel : float, optional
        Threshold of a zero eigenvalue relative to the largest.

    Returns
    -------
    ev : ndarray
        |eigenvalues| of sym(K), ascending.
    count : int
        The number of zero-energy modes: 6 (the rigid motions) for a sound free element.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> zero_modes(Problem(mesh.rectangle(1.0, 1.0, 1, 1), Material(1e3, 0.3, 0.05)))[1]
    6
    """
    g = problem.mesh.g0 if g is None else g
    K = problem.tangent(g, lam, _all_free(problem)).toarray()
    ev = np.sort(np.abs(np.linalg.eigvalsh(0.5 * (K + K.T))))
    return ev, int(np.sum(ev < rel * ev[-1]))
