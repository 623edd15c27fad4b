"""Contact of a part far from the origin, in the part's coordinates (:class:`RelocatedContact`).

A part placed at x0 stores its positions to eps |x0|.  Load stepping holds the iterate of such a
part relative to its origin c (``solvers.origin``): exact differences, so that its strains do not
see eps |x0| / h_e.  A contact load reads positions, so it is restated in those coordinates: its
obstacle is ``Obstacle.relocated(c)`` (the placement point moved by -c, the motion conjugated)
and its friction anchors are held relative to c, and it is evaluated on the relative frames.
The gaps then carry no absolute round-off: with the stiff contact penalty k, a gap off by
eps |x0| was a force off by k eps |x0| per unit area (a strip pressed on a plane 1.15e4 of its
lengths from the origin stalled Newton at its first step).

The relocated load is a copy of the problem's (``whole``) that owns the state during the solve
and hands it back after each change (multipliers, penalty factors, tractions, anchors moved by
+c, the gap error and the step's stick/slip record), so that the problem's load reports the
state as ever.  Its own :meth:`~RelocatedContact.multipliers` (the solver's saves and restores
of a try) keep the anchors relative to c, exactly; restart points and records take the whole
load's (anchors in the problem's coordinates, ``whole.multipliers()``), and a start from one
comes in through :meth:`~RelocatedContact.from_whole`.  (Saved and restored through the whole
load's form, the anchors moved by eps |c| at every refused try: a clamped node resting on a
rough floor at d = 0 then counted as slipping by 6e-11 at 1e6 from the origin.)
"""
from __future__ import annotations

import copy

import numpy as np

from .contact import ContactLoad

__all__ = ["RelocatedContact", "relocated_contact"]

_PUBLISHED = ("gap_error", "step_stats", "_step_at", "_step_slip", "_step_stick", "_lam_update", "_stuck", "_stuck_face")


class RelocatedContact(ContactLoad):
    """The contact load ``whole`` in coordinates x' = x - c, evaluated on frames whose positions
    are relative to c (module docstring); made by :func:`relocated_contact`.

    Parameters
    ----------
    whole : ContactLoad
        The problem's contact load (it receives the state after every change).
    c : (3,) array_like
        The origin of the coordinates.
    obstacle : Obstacle
        ``whole.obstacle.relocated(c)``.
    g0 : (n, 4, 4) ndarray
        The reference frames in these coordinates (the anchors' reference state).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1, x0=1e6), Material(1e4, 0.0, 0.02))
    >>> c = p.add_obstacle("half_space", point=(0, 0, -0.05), normal=(0, 0, 1), friction=0.3)
    >>> g0 = p.mesh.g0.copy(); g0[:, 0, 3] -= 1e6
    >>> near = relocated_contact(c, np.array([1e6, 0.0, 0.0]), g0)
    >>> near.y_a0[:, 0].tolist(), bool(np.allclose(near.whole.multipliers(), c.multipliers()))
    ([0.0, 0.5, 1.0, 0.0, 0.5, 1.0], True)
    """

    def __init__(self, whole, c, obstacle, g0):         # noqa: D107 (the whole load is built already)
        self.__dict__.update(copy.copy(whole).__dict__)
        self.whole, self.shift, self.obstacle = whole, np.asarray(c, float), obstacle
        if self.mu > 0:
            self.y_a0 = self.placement(self.contact_points(g0), 0.0)
        ContactLoad.set_multipliers(self, self.from_whole(whole.multipliers()))

    def _anchors_moved(self, m, shift):
        """The multipliers ``m`` (the :meth:`multipliers` layout) with the anchors moved by
        ``shift`` (3,): between this load's coordinates and the whole load's."""
        m = np.array(m, float).ravel()
        k3 = 3 * len(self.nodes)
        if self.mu > 0 and len(m) == 2 * len(self.lam0) + 2 * k3:
            m[len(m) - k3:] = (m[len(m) - k3:].reshape(-1, 3) + shift).ravel()
        return m

    def _publish(self):
        """The state into the whole load (its reports, outputs and restart points)."""
        w = self.whole
        w.lam, w.soft = self.lam.copy(), self.soft.copy()
        if self.mu > 0:
            w.tau, w.y_a = self.tau.copy(), self.y_a + self.shift
        for key in _PUBLISHED:
            if key in self.__dict__:
                setattr(w, key, getattr(self, key))

    def from_whole(self, m, held=None):
        """The whole load's multipliers ``m`` (a restart point: anchors in the problem's
        coordinates) in this load's (anchors relative to c), for :meth:`set_multipliers`:
        ``held``, this load's own as a restart state keeps them (``NewtonState.held_multipliers``),
        when they are m's to the bit; else m's anchors moved by -c, which carry eps |c| (a rough
        floor's strip 1e4 from the origin, resumed, ended 9.3e-14 off the unbroken run)."""
        if m is None:
            return None
        if held is not None and np.shape(held) == np.shape(m) and np.array_equal(self._anchors_moved(held, self.shift),
                                                                                 np.ravel(m)):
            return np.array(held, float)
        return self._anchors_moved(m, -self.shift)

    def set_multipliers(self, lam=None):
        """:meth:`ContactLoad.set_multipliers` (this load's coordinates); the state is handed to
        the whole load."""
        super().set_multipliers(lam)
        self._publish()

    def update_multipliers(self, g, lam):
        ratio = super().update_multipliers(g, lam)
        self._publish()
        return ratio

    def accept_state(self, g, lam):
        super().accept_state(g, lam)
        self._publish()


def relocated_contact(load, c, g0):
    """The contact load ``load`` in the coordinates x' = x - c of a part far from the origin,
    evaluated on frames relative to c (:class:`RelocatedContact`; g0 the reference frames in
    them), or None: ``load`` is no ContactLoad, or its obstacle cannot be relocated
    (``Obstacle.relocated``: a user's SDF of absolute coordinates).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import UserSDF
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1, x0=1e6), Material(1e4, 0.0, 0.02))
    >>> lid = p.add_obstacle(UserSDF(lambda y: 1.0 - y[:, 2], lambda y: np.tile([0.0, 0.0, -1.0], (len(y), 1))))
    >>> relocated_contact(lid, np.array([1e6, 0.0, 0.0]), p.mesh.g0) is None
    True
    """
    if not isinstance(load, ContactLoad):
        return None
    obstacle = load.obstacle.relocated(c)
    return None if obstacle is None else RelocatedContact(load, c, obstacle, g0)
