"""The snap check of load stepping with contact (``NewtonOptions.snap_check``): a large contact
step is solved again in halves; a jump that survives the halving is reported as a snap.

Contact is not smooth, so the path check and the stability check of ``solvers.step_checks``
leave the tries that touch an obstacle (its Newton tries contract irregularly at every step size,
det K jumps as nodes touch and lift off; a try clear of every obstacle at both ends is judged as
any).  What remains observable is the motion itself.  Let the *travel* of a converged
try be the largest nodal displacement over the increment in element sizes h_e (the median
reference edge length).  On a continuous path the travel of a step shrinks with the step: each
half of a step travels about half as far.  Across a discontinuity of the quasi-static path (a
stick-slip release, a lift-off that releases stored energy, a buckle under contact) the travel
does not shrink: the half that holds the jump travels as far as the whole step.

So a converged contact try that travels more than PROBE_TRAVEL = 1 element size, or lifts a node
that touched an obstacle off it by its own motion by more than LIFT_OFF = 0.5 thicknesses
(``ContactLoad.lift_off``: a jump smaller than an element -- the Sze roof (h 6.35, 8x8 quarter,
elements 32 wide) pushed at its crown by a descending ball snapped through 9.8 ahead of it, contact
lost, and the run completed without a word), is not accepted at once: it is **probed**, i.e. refused and solved again in two halves (the cut-back of a
failed try).  A half whose travel shrank (at most SHRINK = 0.75 of the probed step's) is
accepted; a half that travels as far again holds the jump and is probed in turn.  When the
halves reach the end of a probed step, their state is compared with the probed step's: one that
differs by more than AGREE = 0.1 of its travel (and 0.1 h_e) had landed elsewhere, and the run
keeps the halves' path (it is recorded as a cut-back).  A jump still found in a step of at most
1/2**SNAP_HALVINGS of the requested step (1/64) -- its travel unchanged over six halvings -- is a
**snap**: the try is accepted (it is where the quasi-static path goes on), a
:class:`SnapPoint` is kept in ``Result.critical_points`` and a warning names the load factors,
the node, the travel and what to do (smaller steps cannot follow a snap; a dynamic analysis can).

Measured (docs/STEPS.md): the frictional walker of ``catalogue.cases_friction`` at mu 0.7 moved a
node by 1.6 L (8 h_e) in one step of its set-up ramp and ended 1.68 L from the 160-step path,
silently; probed, that step had landed elsewhere, and the halves end 6e-7 L from the 160-step
path.  A tip force that jumps (tests/test_contact_snap.py) is reported as a snap.

Example
-------
>>> import numpy as np
>>> g0 = np.tile(np.eye(4), (3, 1, 1)); g1 = g0.copy(); g1[2, 0, 3] = 5.0
>>> probe = ContactProbe(h_e=1.0)
>>> probe.new_step(0.1)
>>> probe.judge(g0, g1, 0.0, 0.1)[:45]
'snap check: the contact step travelled 5 elem'
>>> probe.next_increment(0.0, 0.05)
0.05
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np

from .stability import CriticalPoint

__all__ = ["ContactProbe", "SnapPoint", "median_edge", "PROBE_TRAVEL", "LIFT_OFF", "SHRINK", "AGREE", "SNAP_HALVINGS"]

log = logging.getLogger(__name__)

PROBE_TRAVEL = 1.0     # a contact try travelling farther (in element sizes) is probed in halves
LIFT_OFF = 0.5         # ... and one in which a touching node left its obstacle by its own motion (in thicknesses)
SHRINK = 0.75          # a half travelling at most this fraction of its probed step's continues the path
AGREE = 0.1            # the halves' end state differs by more than this fraction of the travel: a jump
SNAP_HALVINGS = 6      # a jump surviving down to 1/2**6 of the requested step is a snap


def median_edge(mesh):
    """The median reference edge length of ``mesh`` (the element size h_e of the travel)."""
    x = mesh.X[mesh.edge_nodes]
    h = float(np.median(np.linalg.norm(x[:, 1] - x[:, 0], axis=1)))
    return h if h > 0 else mesh.length_scale


@dataclasses.dataclass
class SnapPoint(CriticalPoint, kind="snap"):
    """A snap of load stepping with contact: a jump of the quasi-static path that a step of
    ``min_step`` still made.  ``node``: the node that moved most, by ``travel`` (length)."""
    node: int = -1
    travel: float = 0.0
    min_step: float = 0.0

    def describe(self):
        a, b = self.lam_bracket
        return (f"snap between load factors {a:.7g} and {b:.7g}: node {self.node} moved {self.travel:.4g} in one "
                f"step of {abs(b - a):.3g} (halving the step down to 1/{2 ** SNAP_HALVINGS} of the requested one did "
                "not shrink the motion), so the quasi-static path jumps there (a stick-slip release, a lift-off "
                "or a buckle under contact). "
                "Smaller load steps cannot follow it; a dynamic analysis can. The states after it are those "
                "the jump lands on")


@dataclasses.dataclass
class _Probe:
    lo: float
    hi: float
    x_full: np.ndarray          # positions the probed try reached at hi
    travel: float               # its travel [element sizes]


class ContactProbe:
    """The snap check (module docstring): judge every converged contact try, carry the probes.

    Parameters
    ----------
    h_e : float
        The element size the travel is measured in (:func:`median_edge`).

    Attributes
    ----------
    probes : list
        The probed steps being solved in halves, innermost last.
    snaps : list of SnapPoint
        Snaps found since the last :meth:`passed`.
    probed, landed_elsewhere : int
        Steps probed, and probed steps whose halves ended elsewhere, since the last :meth:`record`.
    """

    def __init__(self, h_e):
        self.h_e = float(h_e)
        self.probes = []
        self.snaps = []
        self.probed = self.landed_elsewhere = 0
        self.min_step = 0.0

    def new_step(self, dlam_nominal):
        """A new requested step of ``dlam_nominal``: a jump in 1/2**SNAP_HALVINGS of it is a snap."""
        self.min_step = abs(dlam_nominal) / 2 ** SNAP_HALVINGS * (1 + 1e-9)

    def judge(self, g0, g1, lam, lam_try, lift=0.0):
        """'' when the converged contact try from (g0, lam) to (g1, lam_try) may be accepted,
        else why it is refused (it is probed: solved again in halves).  ``lift``: the try's
        largest lift-off in thicknesses (``ContactLoad.lift_off``); a try travelling at most
        PROBE_TRAVEL element sizes is probed too when it exceeds LIFT_OFF.  A snap found is kept
        (:meth:`passed`) with step -1 (the caller sets the stored step's index)."""
        x1 = self.positions(g1)
        d_max, node = self.largest_motion(self.positions(g0), x1)
        travel = d_max / self.h_e
        if travel <= PROBE_TRAVEL and lift <= LIFT_OFF:
            return ""
        parent = self.probes[-1] if self.probes else None
        if parent is not None and travel <= SHRINK * parent.travel:
            return ""                                        # the travel shrank with the step
        if abs(lam_try - lam) <= self.min_step:
            self.snaps.append(SnapPoint("snap", -1, 0.5 * (lam + lam_try), (lam, lam_try), (None, None),
                                        node=node, travel=d_max, min_step=abs(lam_try - lam)))
            return ""
        self.probes.append(_Probe(lam, lam_try, x1, travel))
        self.probed += 1
        why = (f"travelled {travel:.3g} element sizes" if travel > PROBE_TRAVEL else
               f"lifted a node {lift:.3g} thicknesses off its obstacle")
        return f"snap check: the contact step {why}: solved again in halves to tell a continuous path from a jump"

    def accept(self, g, lam):
        """The try reaching (g, lam) was accepted: close the probes whose end it reached,
        comparing their states with the halves'."""
        while self.probes and abs(self.probes[-1].hi - lam) <= 1e-14 * max(1.0, abs(lam)):
            p = self.probes.pop()
            diff = self.largest_motion(p.x_full, self.positions(g))[0] / self.h_e
            if diff > AGREE * max(p.travel, 1.0):
                self.landed_elsewhere += 1
                log.info("snap check: the step from %.6g to %.6g had landed %.3g element sizes away from the "
                         "path its halves followed: cut back", p.lo, p.hi, diff)

    def positions(self, g):
        """The nodal positions (n, 3) of frames g whose motion is measured (a copy)."""
        return np.array(g[:, :3, 3])

    def largest_motion(self, x0, x1):
        """(the largest |x1 - x0| over the nodes, the node: the first with it) of positions
        (n, 3); a distributed run takes it over all ranks (``parallel.newton``)."""
        d = np.linalg.norm(x1 - x0, axis=1)
        node = int(np.argmax(d))
        return float(d[node]), node

    def next_increment(self, lam, dlam):
        """``dlam`` capped so that a try does not pass the end of the innermost probe."""
        if not self.probes:
            return dlam
        rest = self.probes[-1].hi - lam
        return float(np.sign(rest) * min(abs(dlam), abs(rest)))

    def passed(self):
        """The snaps found since the last call (the list is emptied)."""
        out, self.snaps = self.snaps, []
        return out

    def record(self):
        """What was checked for the stored step (``StepResult.checks``); resets the counts."""
        rec = dict(snap_probes=self.probed, landed_elsewhere=self.landed_elsewhere)
        self.probed = self.landed_elsewhere = 0
        return rec
