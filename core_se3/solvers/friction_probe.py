"""The friction check of load stepping (``NewtonOptions.friction_check``): an error control of
the slip history by step doubling.

Coulomb friction is path dependent, and load stepping integrates the slip history of each contact
node by one backward-Euler step per try (the return mapping of ``model.friction``): the anchor
and the traction of the start of the step, the slip over it, the traction at its end.  That is
exact for a node that sticks over the whole step, and for one that slips along one direction at
both ends (rate-independent slip: its end state does not depend on the path in between).  It is
not for a node that starts or stops slipping, touches or lifts off, or whose slip direction turns
within the step: ``friction-pushed-cantilever`` in one step of its slide (the end sticks, then
slips at s*) ended 7.3e-5 of its path's scale from the 36-step state, converged and silent.

So a converged try over which some node changed its status (off contact, sticking, slipping) or
slipped along a turning traction (more than SLIP_TURN) is **probed**: refused, and solved again from
the same start in two halves (the friction history moved on at the midpoint), the cut-back of a
failed try.  When the halves reach the probed step's end, the distance of their state from the
probed try's, e = max(max_n |x_n - x_n'| / U, max_n |R_n - R_n'|_F) (U: the largest nodal
displacement of the path so far, the step table's measure), estimates the error of the halves
(a first-order scheme: error(h) ~ c h, so error(h/2) ~ error(h) - error(h/2) = e).  The halves are
accepted when e <= friction_tol.  (A bound friction_tol |dlam| / (load range), so that the
errors would add up to friction_tol over the run, cannot be met: e has a floor of about 5e-9 of
the path's scale set by the solver's and the contact's tolerances, which the bound of a step of
1/256 undercuts -- ``friction-gripper-hold`` in 1 step then refined 82 steps to no avail.)  Otherwise the
run goes back to the probed step's start (state, friction history, multipliers) and solves it in
halves that are probed in turn.  A probe whose halves are already at most 1/2**FRICTION_HALVINGS
of the requested step (1/256) and still miss the bound is accepted, recorded
(``friction_unresolved``) and a warning names the load factors, the node and the estimated error.

Measured (docs/STEPS.md "The friction check"): friction-pushed-cantilever in 1 step of its slide
now ends within 1e-7 of its 36-step state (7.3e-5 before).

Example
-------
>>> import numpy as np
>>> probe = FrictionProbe([], np.zeros((2, 3)), tol=1e-7)
>>> probe.new_step(1.0); probe.record()
{'friction_probes': 0, 'friction_refinements': 0, 'friction_error': 0.0, 'friction_unresolved': 0, 'friction_relaxations': 0, 'friction_excess': 0.0}
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np

__all__ = ["FrictionProbe", "FRICTION_HALVINGS", "SLIP_TURN", "RELAXATIONS"]

log = logging.getLogger(__name__)

FRICTION_HALVINGS = 8    # a probe is not refined below 1/2**8 of the requested step
SLIP_TURN = 1e-6         # a slipping node whose traction turned by more than this [rad] over a try is probed
RELAXATIONS = 3          # an accepted state is solved again at its load factor at most 3 times (the hardening)


@dataclasses.dataclass
class _Probe:
    lo: float
    hi: float
    g_full: np.ndarray          # the frames the probed try reached at hi
    start: tuple                # the state to go back to (solvers.newton's snapshot)
    node: int                   # a node whose status changed over the probed try


def _distance(g, ref, scale):
    """max(max_n |x_n - x_n^ref| / scale, max_n |R_n - R_n^ref|_F) and the node where it is largest."""
    dx = np.linalg.norm(g[:, :3, 3] - ref[:, :3, 3], axis=1) / scale
    dR = np.sqrt(((g[:, :3, :3] - ref[:, :3, :3]) ** 2).sum((1, 2)))
    d = np.maximum(dx, dR)
    i = int(np.argmax(d))
    return float(d[i]), i


class FrictionProbe:
    """The friction check (module docstring): judge every converged try of a frictional run,
    carry the probes and the refined regions.

    Parameters
    ----------
    loads : list
        The frictional loads (``slip_status``, ``nodes``; ``mu > 0``).
    X0 : (n, 3) ndarray
        The reference positions (the displacement scale U of the distance).
    tol : float, optional
        ``friction_tol``: the bound on the hardening's excess (of mu p) and on the halves'
        estimated error (of U).
    halving : bool, optional
        ``friction_halving``: probe the tries that changed a node's status (else only relax).
    """

    def __init__(self, loads, X0, tol=1e-7, halving=True):
        self.loads, self.X0 = loads, np.asarray(X0, float)
        self.halving = halving
        self.tol = float(tol)
        self.U = 0.0
        self.probes, self.caps = [], []
        self.status = None
        self.back = None
        self.min_step = 0.0
        self.probed = self.refined = self.unresolved = self.relaxed = 0
        self.worst = self.excess_max = 0.0

    def excess(self):
        """(the largest hardening excess (|t| - mu p) / (mu p) of a slipping node at the state
        just accepted, the node) over the frictional loads (``step_stats``)."""
        stats = [getattr(ld, "step_stats", None) or {} for ld in self.loads]
        best = max(stats, key=lambda st: st.get("excess", 0.0))
        return best.get("excess", 0.0), best.get("excess_node", -1)

    def note_excess(self):
        """Keep the excess of the accepted state (after its relaxations) for :meth:`record`."""
        self.excess_max = max(self.excess_max, self.excess()[0])

    def new_step(self, dlam_nominal):
        """A new requested step of ``dlam_nominal``: probes end at 1/2**FRICTION_HALVINGS of it."""
        self.min_step = abs(dlam_nominal) / 2 ** FRICTION_HALVINGS * (1 + 1e-9)

    def _inside(self, lam):
        p = self.probes[-1] if self.probes else None
        return p is not None and min(p.lo, p.hi) - 1e-14 <= lam < max(p.lo, p.hi) - 1e-14 * max(1.0, abs(p.hi))

    def begin(self, g, lam):
        """Before a try from the accepted state (g, lam): the nodes' status there."""
        self.status = None if self._inside(lam) or not self.halving else [ld.slip_status(g, lam, True) for ld in self.loads]

    def _changed(self, g1, lam1):
        """The first node (mesh index) whose friction the try to (g1, lam1) may not have
        integrated exactly (module docstring), or -1."""
        for ld, (s0, e0) in zip(self.loads, self.status or []):
            s1, e1 = ld.slip_status(g1, lam1, False)
            turned = (np.linalg.norm(np.cross(e0, e1), axis=1) > SLIP_TURN) | (np.einsum("ki,ki->k", e0, e1) < 0)
            hit = np.flatnonzero((s0 != s1) | ((s0 == 2) & (s1 == 2) & turned))
            if len(hit):
                return int(ld.nodes[hit[0]])
        return -1

    def judge(self, g1, lam, lam_try, start):
        """'' when the converged try from lam to (g1, lam_try) may be accepted, else why it is
        refused: a try that changed a node's friction status is probed (solved again in
        halves); the halves that end a probe too far from its try send the run back to
        ``start`` (the snapshot of the probed step's start, :meth:`take_back`)."""
        U = max(self.U, float(np.linalg.norm(g1[:, :3, 3] - self.X0, axis=1).max()))
        p = self.probes[-1] if self.probes else None
        if p is not None and abs(lam_try - p.hi) <= 1e-14 * max(1.0, abs(p.hi)):
            return self._close(self.probes.pop(), g1, U)
        if self._inside(lam) or abs(lam_try - lam) <= self.min_step or self.status is None:
            return ""
        node = self._changed(g1, lam_try)
        if node < 0:
            return ""
        self.probes.append(_Probe(lam, lam_try, g1.copy(), start, node))
        self.probed += 1
        return (f"friction check: node {node} changed its stick/slip status (or its slip direction) over the step: "
                "solved again in halves to estimate the error of the slip history")

    def _close(self, p, g1, U):
        """The halves reached the probed step's end: accept them, or go back (module docstring)."""
        h = abs(p.hi - p.lo)
        err, i = _distance(g1, p.g_full, max(U, 1e-300))
        allowed = self.tol
        if err <= allowed:
            self.worst = max(self.worst, err)
            return ""
        if h / 2 <= self.min_step:
            self.unresolved += 1
            self.worst = max(self.worst, err)
            log.warning("friction check: the slip history between load factors %.7g and %.7g (node %d) is integrated "
                        "to an estimated %.3g of the path's scale, more than friction_tol = %.3g, "
                        "even in steps of 1/%d of the requested one; the states after it may depend on the steps. "
                        "Take smaller load steps there, or raise [solver] friction_tol",
                        p.lo, p.hi, i, err, allowed, 2 ** FRICTION_HALVINGS)
            return ""
        self.back = p
        self.refined += 1
        self.caps.append((p.hi, h / 2))
        return (f"friction check: the halves of the step from {p.lo:.7g} to {p.hi:.7g} differ from it by {err:.3g} "
                f"of the path's scale at node {i} (allowed {allowed:.3g}): solved again from {p.lo:.7g} in steps of "
                f"{h / 2:.3g}")

    def take_back(self):
        """The snapshot to go back to after a refused probe (None: go on from here)."""
        p, self.back = self.back, None
        return None if p is None else p.start

    def accept(self, g):
        """A try reaching the frames ``g`` was accepted (the path's scale U grows)."""
        self.U = max(self.U, float(np.linalg.norm(g[:, :3, 3] - self.X0, axis=1).max()))

    def next_increment(self, lam, dlam):
        """``dlam`` capped so that a try does not pass the end of the open probe, nor exceed
        the step of a region being refined."""
        while self.caps and (self.caps[-1][0] - lam) * np.sign(dlam) <= 1e-14 * max(1.0, abs(lam)):
            self.caps.pop()
        out = abs(dlam)
        if self.caps:
            out = min(out, self.caps[-1][1])
        if self.probes:
            out = min(out, abs(self.probes[-1].hi - lam))
        return float(np.sign(dlam) * out)

    def record(self):
        """What was checked for the stored step (``StepResult.checks``); resets the counts."""
        rec = dict(friction_probes=self.probed, friction_refinements=self.refined, friction_error=self.worst,
                   friction_unresolved=self.unresolved, friction_relaxations=self.relaxed,
                   friction_excess=self.excess_max)
        self.probed = self.refined = self.unresolved = self.relaxed = 0
        self.worst = self.excess_max = 0.0
        return rec
