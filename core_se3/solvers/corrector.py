"""The corrector of path following (``solvers.arclength``): Newton on the bordered system

    K du - q dlam = -r,        c_u . du + c_lam dlam = -c

from a predicted (state, lam), with its constraints: the arc length (``crisfield``: cylindrical,
the root that keeps the increment closest to its previous direction; ``riks``: the normal plane)
and a linear constraint (load control dlam = lam* - lam, or a controlled displacement).  A
corrector that does not converge raises :class:`StepFailed` (the step is retried shorter).
"""
from __future__ import annotations

import time

import numpy as np

from .linalg import Factorization

__all__ = ["StepFailed", "ArcLengthConstraint", "LinearConstraint", "correct"]


class StepFailed(Exception):
    """A corrector that did not converge (the step is rejected and retried shorter)."""


class ArcLengthConstraint:
    """The arc-length constraint of one step (``method`` 'crisfield' or 'riks', length ds,
    load weight psi_u [length], dof weights w): ``start(du, dlam)`` with the predictor,
    ``dlam_for(...)`` the load increment of each correction, ``accept`` accumulates it."""

    def __init__(self, method, ds, psi_u, w):
        self.method, self.ds, self.c2, self.w = method, ds, psi_u ** 2, w

    def start(self, du, dlam):
        self.du, self.dlam = du.copy(), dlam
        self.du0, self.dlam0 = du.copy(), dlam                  # predictor (normal of Riks)

    def dlam_for(self, sysm, state, a, b):
        w = self.w
        if self.method == "riks":
            den = np.sum(w * self.du * b) + self.c2 * self.dlam
            if den == 0:
                raise StepFailed("Riks constraint is tangent to the path")
            return -np.sum(w * self.du * a) / den
        ua = self.du + a
        A = np.sum(w * b * b) + self.c2
        B = 2 * (np.sum(w * ua * b) + self.c2 * self.dlam)
        Cc = np.sum(w * ua * ua) + self.c2 * self.dlam ** 2 - self.ds ** 2
        disc = B * B - 4 * A * Cc
        if disc < 0:
            # complex roots: take the point of the correction line closest to the sphere
            # (minimum of the quadratic); the next iterations return to the constraint
            self.complex_roots = getattr(self, "complex_roots", 0) + 1
            if self.complex_roots > 3:
                raise StepFailed("arc-length constraint has no real root (complex roots)")
            return -B / (2 * A)
        roots = ((-B + np.sqrt(disc)) / (2 * A), (-B - np.sqrt(disc)) / (2 * A))
        # choose the root whose increment makes the smallest angle with the previous one
        score = [np.sum(w * self.du * (ua + x * b)) + self.c2 * self.dlam * (self.dlam + x)
                 for x in roots]
        return roots[int(np.argmax(score))]

    def accept(self, x, dl):
        self.du += x
        self.dlam += dl


class LinearConstraint:
    """A linear constraint of the bordered corrector: c(state, lam) = value(state) + c_lam lam - target, linearised by row . du + c_lam dlam."""

    def __init__(self, value, row, c_lam, target):
        self.value, self.row, self.c_lam, self.target = value, row, c_lam, target
        self.lam = None
        self.du = self.dlam = None

    def start(self, du, dlam):
        """Accumulate the step's increment (``du``, ``dlam``) from the predictor (du, dlam) on, as
        the arc-length constraint does (displacement control's critical points are refined
        along it, ``solvers.critical``)."""
        self.du, self.dlam = du.copy(), dlam

    def dlam_for(self, sysm, state, a, b):
        c = (self.value(state) if self.value else 0.0) + self.c_lam * self.lam - self.target
        ru = self.row(state) if self.row else None
        num = c + (ru @ a if ru is not None else 0.0)
        den = (ru @ b if ru is not None else 0.0) + self.c_lam
        if den == 0 or not np.isfinite(den):
            raise StepFailed("the controlled displacement does not respond to the load (c_u . b = 0)")
        return -num / den

    def accept(self, x, dl):
        if self.du is not None:
            self.du += x
            self.dlam += dl


def correct(sysm, state, lam, con, opts, timers, incs=None):
    """Newton on the bordered system from the predicted (state, lam); returns the converged
    (state, lam, iterations, residual history, evaluation at the solution).  ``incs``: a list
    that gets the relative size (``sysm.increment_norm``) of every correction, for the path
    check of ``solvers.step_checks.path_measures`` (displacement control)."""
    hist = []
    dn = np.inf
    for it in range(opts.max_iter + 1):
        ta = time.perf_counter()
        ev = sysm.evaluate(state, lam, tangent=True)
        timers[0] += time.perf_counter() - ta
        rn = ev["rn"]
        hist.append(rn)
        if it > 0 and rn <= max(opts.rtol, ev["floor"]) and dn <= opts.dtol:
            return state, lam, it, hist, ev
        if it == opts.max_iter:
            raise StepFailed(f"no convergence in {opts.max_iter} iterations (residual {rn:.2e})")
        if it > 3 and rn > opts.divergence * max(hist[0], 1e-300):
            raise StepFailed(f"diverging (residual {rn:.2e})")
        ts = time.perf_counter()
        sysm.factorizations += 1
        with Factorization(ev["K"], sysm.solver) as fac:
            a = fac.solve(-ev["r"])
            b = fac.solve(ev["q"])
        timers[1] += time.perf_counter() - ts
        if isinstance(con, LinearConstraint):
            con.lam = lam
        dl = con.dlam_for(sysm, state, a, b)
        x = a + dl * b
        dn = sysm.increment_norm(x)
        if incs is not None:
            incs.append(dn)
        state = sysm.update(state, x)
        lam = lam + dl
        con.accept(x, dl)
