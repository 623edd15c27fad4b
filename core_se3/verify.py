"""Verification tools: finite-difference tangent checks and zero-energy-mode counts.

``tangent_fd_check`` compares the assembled tangent with central differences of the residual
along the exponential update g_i <- g_i exp(eps eta_i) -- the derivative the Newton solver
needs.  Other modules (magnetic loads, new elements) reuse it.
"""
from __future__ import annotations

import numpy as np

from . import se3
from .assembly import Assembler

__all__ = ["residual", "tangent", "tangent_fd_check", "zero_modes"]


def residual(problem, g, lam, asm=None):
    """Free residual r_int - f_ext at (g, lam)."""
    asm = asm or problem.assembler()
    ev = problem.element.evaluate(g, tangent=False)
    f, _, _ = problem.external(g, lam, tangent=False)
    return asm.vector(ev["r"] - f)


def tangent(problem, g, lam, asm=None):
    """Assembled sparse tangent on the free dofs at (g, lam)."""
    asm = asm or problem.assembler()
    ev = problem.element.evaluate(g, tangent=True)
    f, Kn, Ke = problem.external(g, lam, tangent=True)
    Ke_tot = ev["Ke"] if Ke is None else ev["Ke"] + Ke
    return asm.matrix(Ke_tot, ev["KE"], ev["Kn"] + Kn)


def tangent_fd_check(problem, g, lam=1.0, h=1e-6, free_all=False):
    """Max relative difference between the tangent and central FD of the residual.

    With ``free_all`` every dof is treated as free (supports ignored).  Returns
    (relative error, K dense, K_fd dense).
    """
    asm = Assembler(problem.mesh, np.ones(6 * problem.mesh.n_nodes, bool)) if free_all \
        else problem.assembler()
    K = tangent(problem, g, lam, asm).toarray()
    Kfd = np.zeros_like(K)
    for k in range(asm.nfree):
        e = np.zeros(asm.nfree)
        e[k] = h
        d = asm.scatter(e)
        Kfd[:, k] = (residual(problem, g @ se3.exp(d), lam, asm)
                     - residual(problem, g @ se3.exp(-d), lam, asm)) / (2 * h)
    err = np.abs(K - Kfd).max() / max(np.abs(Kfd).max(), 1e-300)
    return err, K, Kfd


def zero_modes(problem, g=None, lam=0.0, rel=1e-10):
    """Eigenvalues of the symmetric part of the free-free tangent, sorted by magnitude,
    and the number below rel * lambda_max."""
    g = problem.mesh.g0 if g is None else g
    asm = Assembler(problem.mesh, np.ones(6 * problem.mesh.n_nodes, bool))
    K = tangent(problem, g, lam, asm).toarray()
    ev = np.sort(np.abs(np.linalg.eigvalsh(0.5 * (K + K.T))))
    return ev, int(np.sum(ev < rel * ev[-1]))
