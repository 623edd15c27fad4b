"""Quasi-static Coulomb friction of the contact nodes (``model.contact``, issue 31): an augmented
Lagrangian on the tangential slip of each node over the step, with a return mapping onto the
Coulomb cone and its consistent (non-symmetric) tangent.  Derivations in docs/CONTACT.md
"Friction".

Kinematics.  Node i's contact point x (lab) and its anchor y_a, the point of the obstacle it
stuck to at the last accepted state (placement coordinates, moved with the obstacle:
x_a = T(lam) y_a).  With the obstacle's normal n(x), P = I - n n^T and the multiplier w = Q tau
(the tangential traction carried from the last state, stored in the obstacle's frame):

    v = x - x_a,   s = P v (the slip over the step),   t* = P w - k s (trial traction),
    t = t*                                 if |t*| < mu p   (stick),
    t = ((1 - d) mu p + d rho |t*|) t* / |t*|  otherwise     (slip: the return onto the cone),

p the normal pressure of the node (``contact_law.normal_law``), k the penalty [force/length^3].
The Uzawa update tau <- Q^T t has as fixed points exactly Coulomb's law with maximal
dissipation: s = 0 and |t| <= mu p, or |t| = mu p and s = -alpha t (alpha >= 0), up to the
hardening d = 1e-8 (|t| = mu p + d k |s| / (1 - d): 1e-8 of the penalty per unit slip over the
step; a converged state where it exceeds 1e-3 mu p is refused).  The hardening acts with the slope
rho = -p'/k of the normal law (0 off contact, 1 beyond its C^1 band): a node off the obstacle
carries no force from it.

Tangent (at fixed lam; H = grad n, e = t*/|t*|):

    dt*/dx = -(n.w) H - n (H w)^T - k [P - (n.v) H - n (H v)^T],
    dt/dx  = dt*/dx (stick),
    dt/dx  = (1 - d) [mu e (p' n)^T + (mu p / |t*|) (I - e e^T) dt*/dx] + d rho dt*/dx + d t* (drho/dx)^T (slip),

and the node's force A (p n + t) enters :func:`wrench` with S = A (p' n n^T + p H + dt/dx).

Example
-------
>>> import numpy as np
>>> n, H = np.array([[0.0, 0.0, 1.0]]), np.zeros((1, 3, 3))
>>> v = np.array([[0.1, 0.0, 0.0]])                      # 0.1 of slip along x
>>> t, dt, stick, s = coulomb_law(n, H, np.array([1.0]), np.array([-5.0]), v, np.zeros((1, 3)), 2.0, 0.5)
>>> t[0].tolist(), bool(stick[0])                        # k s = 0.2 < mu p = 0.5: it sticks
([-0.2, 0.0, 0.0], True)
>>> t, dt, stick, s = coulomb_law(n, H, np.array([1.0]), np.array([-5.0]), 3 * v, np.zeros((1, 3)), 2.0, 0.5)
>>> t[0].round(6).tolist(), bool(stick[0])               # 0.6 > 0.5: it slips, |t| = mu p
([-0.5, 0.0, 0.0], False)
"""
from __future__ import annotations

import numpy as np

from .. import lie
from .contact_law import E3
from .obstacles import contact_error

__all__ = ["coulomb_law", "wrench", "CoulombFriction", "STICK_MARGIN", "HARDENING", "CONE_EXCESS", "NORMAL_TOL"]

STICK_MARGIN = 1e-10        # |t*| >= (1 - STICK_MARGIN) mu p: on the cone (slip)
# the cone hardens by HARDENING of the trial traction beyond it (|t| = mu p + HARDENING (|t*| - mu p)):
# the slip keeps HARDENING k of stiffness along itself, so that a body whose contact nodes all
# slip has no zero pivot and the split of a sliding between feet that slip alike (indeterminate
# in rigid-plastic friction) is the one the residual selects, the symmetric one; a converged
# state whose traction exceeds the cone by more than CONE_EXCESS of it is refused (the loads
# exceed the friction: no static equilibrium)
HARDENING = 1e-8
CONE_EXCESS = 1e-3
NORMAL_TOL = 1e-3           # friction refuses an obstacle normal |grad d| farther than this from 1


def coulomb_law(n, H, p, dp, v, w, k, mu):
    """Tangential traction t (k, 3) [force/length^2], dt/dx (k, 3, 3), the stick mask (k,) and the
    slip s (k, 3) [length] of the module docstring: n (k, 3) normals, H (k, 3, 3) SDF Hessians,
    p, dp (k,) normal pressure and dp/dd, v (k, 3) position from the anchor, w (k, 3) the
    multiplier in the lab, k penalties (broadcast), mu the friction coefficient."""
    kk = np.broadcast_to(np.asarray(k, float), p.shape)[:, None, None]
    nv, nw = np.einsum("ki,ki->k", n, v), np.einsum("ki,ki->k", n, w)
    P = np.eye(3) - n[:, :, None] * n[:, None, :]
    s = np.einsum("kij,kj->ki", P, v)
    tt = np.einsum("kij,kj->ki", P, w) - kk[:, :, 0] * s
    Hv, Hw = np.einsum("kij,kj->ki", H, v), np.einsum("kij,kj->ki", H, w)
    dPv = P - nv[:, None, None] * H - n[:, :, None] * Hv[:, None, :]
    T = -nw[:, None, None] * H - n[:, :, None] * Hw[:, None, :] - kk * dPv
    norm = np.linalg.norm(tt, axis=1)
    cap = mu * p
    # a node off contact (cap 0) never sticks (no tangential stiffness), and one whose trial
    # traction lies on the cone to round-off (it slipped over the last step) starts on the slip
    # side: its tangent is the slip tangent, which the increment then follows
    stick = norm < cap * (1 - STICK_MARGIN)
    e = tt / np.where(norm > 0, norm, 1.0)[:, None]
    ratio = np.where(norm > 0, cap / np.where(norm > 0, norm, 1.0), 0.0)
    # the hardening acts with the slope rho = -p'/k of the normal law (0 off contact, 1 beyond
    # its C^1 band, continuous): a node off the obstacle carries no force from it at all, and
    # in the band d rho / d gap = -k rho^2 / (2 p) (p = rho^2 k eps / 2 there)
    rho = np.clip(-dp / kk[:, 0, 0], 0.0, 1.0)
    band = (rho > 0) & (rho < 1)
    drho = np.where(band, -kk[:, 0, 0] * rho ** 2 / (2 * np.where(band, p, 1.0)), 0.0)
    d = HARDENING * rho
    t = np.where(stick[:, None], tt, ((1 - HARDENING) * ratio + d)[:, None] * tt)
    slip_dt = ((1 - HARDENING) * (mu * e[:, :, None] * (dp[:, None] * n)[:, None, :]
                                  + ratio[:, None, None] * (np.eye(3) - e[:, :, None] * e[:, None, :]) @ T)
               + d[:, None, None] * T + HARDENING * tt[:, :, None] * (drho[:, None] * n)[:, None, :])
    dt = np.where(stick[:, None, None], T, slip_dt)
    return t, dt, stick, s


def wrench(R, c, F, S):
    """Generalised nodal forces f (k, 6) and -df/deta (k, 6, 6) of lab forces F (k, 3) acting at
    x = phi + c d3 whose derivative is dF/dx = S (k, 3, 3) (R (k, 3, 3) frames, c (k,) offsets):
    f = B^T R^T F, -df/deta = -B^T [R^T S R B + [0, hat(R^T F)]], B = [I, -c hat(e3)]
    (``contact_law.contact_wrench`` with S = A (p' n n^T + p H)).

    Example
    -------
    >>> import numpy as np
    >>> f, K = wrench(np.eye(3)[None], np.array([-0.5]), np.array([[6.0, 0, 0]]), np.zeros((1, 3, 3)))
    >>> f[0].tolist()
    [6.0, 0.0, 0.0, 0.0, -3.0, 0.0]
    """
    Rt = np.swapaxes(R, 1, 2)
    Fb = np.einsum("kij,kj->ki", Rt, F)
    k = len(c)
    B = np.zeros((k, 3, 6))
    B[:, :, :3] = np.eye(3)
    B[:, :, 3:] = -c[:, None, None] * lie.hat3(E3)
    Bt = np.swapaxes(B, 1, 2)
    dF = (Rt @ S @ R) @ B
    dF[:, :, 3:] += lie.hat3(Fb)
    return np.einsum("kij,kj->ki", Bt, Fb), -Bt @ dF


class CoulombFriction:
    """The friction side of :class:`~core_se3.model.contact.ContactLoad` (a mixin: its state
    ``mu``, ``tau``, ``y_a`` and the hooks of a path-dependent load; module docstring)."""

    @property
    def path_dependent(self):
        """True with friction: the state depends on the path, not on (g, lam) alone (a sweep
        does not warm-start it from another point's final state)."""
        return self.mu > 0

    def friction_state(self, g, lam, x, n, H, p, dp):
        """(t, dt/dx, stick, slip) of the nodes (:func:`coulomb_law`), the multiplier and the
        anchors moved with the obstacle to lam."""
        self.check_normals(n)
        T = self.obstacle.transform(lam)
        v = x - (self.y_a @ T[:3, :3].T + T[:3, 3])
        return coulomb_law(n, H, p, dp, v, self.tau @ T[:3, :3].T, self.k * self.soft[:len(self.nodes)], self.mu)

    def check_normals(self, n):
        """ContactError unless the obstacle's normals n (k, 3) at the contact nodes have unit length
        to NORMAL_TOL: Coulomb's law needs the tangent plane I - n n^T to be a projector (a user's
        SDF with |grad d| = 1.1 failed a plate holding on an incline with "tangent is singular")."""
        bad = np.abs(np.einsum("ki,ki->k", n, n) - 1.0) > 2 * NORMAL_TOL
        if bad.any():
            i = int(np.argmax(bad))
            raise contact_error(
                f"obstacle {self.name!r}: friction needs the unit normal of a signed distance, but |grad d| = "
                f"{np.linalg.norm(n[i]):.6g} at node {int(self.nodes[i])} (more than {NORMAL_TOL:g} from 1; the "
                "tangent plane I - n n^T is then no projector): give a signed distance d with |grad d| = 1 "
                "(a UserSDF: divide d and grad by |grad|) or use friction = 0", "grad")

    def sticking(self, lam, n, p):
        """The nodes that carry force and whose stored traction lies inside the cone,
        |P w| < mu p (1 - STICK_MARGIN), at an accepted state at lam (n, p: its normals and
        pressures): the nodes that stuck over the last step."""
        if self.mu <= 0:
            return np.zeros(len(p), bool)
        w = self.tau @ self.obstacle.transform(lam)[:3, :3].T
        w -= np.einsum("ki,ki->k", n, w)[:, None] * n
        return np.linalg.norm(w, axis=1) < self.mu * p * (1 - STICK_MARGIN)

    def hardening_excess(self, t, p, stick):
        """The hardening's share of the slipping nodes' friction force, A (|t| - mu p) (k,), over the
        largest nodal friction capacity A mu p on this obstacle: what the hardening carries beyond
        Coulomb, on the scale of the friction the obstacle can give.  On a node's own mu p it
        diverged on a node that barely touches (a clamped node resting on a moving rough floor:
        p at the cold start, 2.6e-6, so 2 d |s| / (mu rho eps) = 80 |s| of its cone) and refused
        every step of a physical slide, however small."""
        on = (p > 0) & ~stick
        cap = float(self.largest(float((self.A * self.mu * p).max(initial=0.0))))
        over = self.A * (np.linalg.norm(t, axis=1) - self.mu * p)
        return np.where(on, over, 0.0) / (cap if cap > 0 else 1.0)

    def cone_excess(self, g, lam):
        """Why the converged state (g, lam) is refused: a slipping node whose hardening force exceeds
        CONE_EXCESS of the largest nodal friction capacity (:meth:`hardening_excess`: the hardening
        has carried a load the friction cannot -- no static equilibrium), or ''."""
        x, _, n, H, p, dp = self.state(g, lam)
        t, _, stick, _ = self.friction_state(g, lam, x, n, H, p, dp)
        over = self.hardening_excess(t, p, stick)
        i = int(np.argmax(over)) if len(over) else 0
        if len(over) and self.largest(float(over[i] - CONE_EXCESS)) > 0:
            return (f"obstacle {self.name!r}: the friction at node {int(self.nodes[i])} exceeds mu p by "
                    f"{over[i]:.2g} of the largest nodal friction (more than {CONE_EXCESS:g}): the loads exceed "
                    "what Coulomb friction can hold there")
        return ""

    def _sliding(self, g, lam):
        """(nodes in contact, of them slipping) at (g, lam): the failure hint's evidence."""
        x, _, n, H, p, dp = self.state(g, lam)
        _, _, stick, _ = self.friction_state(g, lam, x, n, H, p, dp)
        on = p > 0
        return int(on.sum()), int((on & ~stick).sum())

    def failure_hint(self):
        """'no static equilibrium: it slides' when every node in contact slipped at the last
        evaluation in contact (of the failed tries; an iterate flung off every obstacle says
        nothing), on this obstacle and on every other rough one of the problem (a grasp: two
        rollers slipping while the third sticks hold the part): friction cannot hold the loads.
        (A strip pulled out of three rough rollers by twice what they hold failed with "edge
        [39, 40] turns by 3.109 rad ... refine the mesh or the load step": the last iterate had
        left them all.)"""
        on, slip = getattr(self, "_slide", (0, 0))
        if not (self.mu > 0 and on):
            return ""
        rough = [self] + [ld for ld in getattr(self, "_loads", ()) if ld is not self and getattr(ld, "mu", 0.0) > 0
                          and getattr(ld, "_slide", (0, 0))[0]]
        on, slip = (sum(ld._slide[k] for ld in rough) for k in (0, 1))
        if slip == on:
            names = ", ".join(repr(ld.name) for ld in rough)
            return (f"no static equilibrium: it slides -- all {on} contact nodes on obstacle{'s' * (len(rough) > 1)} "
                    f"{names} slip (Coulomb friction {self.mu:g} cannot hold the loads); raise the friction, add a "
                    "support, or prescribe the sliding motion")
        return ""

    def slip_status(self, g, lam, start):
        """(status, unit traction direction) of the nodes at (g, lam): 0 off contact, 1 sticking,
        2 slipping; ``start``: (g, lam) is the accepted state the history stands at (its stored
        traction, and how the nodes moved over the step to it), else a converged try from there
        (its traction t).  The friction check (``solvers.friction_probe``) compares the two ends
        of a step."""
        x, _, n, H, p, dp = self.state(g, lam)
        if start:
            t = self.tau @ self.obstacle.transform(lam)[:3, :3].T
            t = t - np.einsum("ki,ki->k", n, t)[:, None] * n
            stick = self.sticking(lam, n, p)
        else:
            t, _, stick, _ = self.friction_state(g, lam, x, n, H, p, dp)
        status = np.where(p > 0, np.where(stick, 1, 2), 0)
        norm = np.linalg.norm(t, axis=1)
        return status, t / np.where(norm > 0, norm, 1.0)[:, None]

    def close_step(self):
        """The state just accepted is a stored step (load stepping records it): the slip of the
        next step counts from here (:meth:`step_slip`)."""
        if self.mu > 0:
            self._y_rec = self.y_a.copy()

    def step_slip(self, x, n, lam, slip):
        """The slip (k, 3) of the nodes at x (normals n) over the stored step that ends at lam:
        their tangential motion relative to the obstacle since the last stored step
        (:meth:`close_step`: the points of the obstacle they were at then, carried with it to
        lam), through every sub-step the solver split the step into; ``slip`` (that of the last
        accepted state alone) without a stored step to count from.  The step's ``largest_slip``
        was its last sub-step's: the pushed cantilever sliding in 9 steps reported 1.52e-3 for
        the wall's 6.08e-3 a step (each step split in 4), in 1 step 1.71e-3 for 2.7e-2."""
        y = getattr(self, "_y_rec", None)
        if y is None or len(y) != len(x):
            return slip
        T = self.obstacle.transform(lam)
        v = x - (y @ T[:3, :3].T + T[:3, 3])
        return v - np.einsum("ki,ki->k", n, v)[:, None] * n

    def accept_state(self, g, lam):
        """An accepted state (``Load.accept_state``): the friction history moves on -- the
        multipliers become the nodes' tractions there (obstacle frame) and the anchors their
        current points on the obstacle.  The friction check solves an accepted state again at its
        lam (``solvers.newton``: relaxations): those add their slip to the step's and a node that
        slipped in any of them slipped over the step (the record was the last relaxation's alone:
        a clamped node on a floor sliding 0.1 under it reported a largest slip of 5e-8)."""
        if self.mu > 0:
            x, _, n, H, p, dp = self.state(g, lam)
            t, _, stick, slip = self.friction_state(g, lam, x, n, H, p, dp)
            if getattr(self, "_step_at", None) == lam:      # a relaxation of the state just accepted
                slip, stick = slip + self._step_slip, stick & self._step_stick
            self._step_at, self._step_slip, self._step_stick = lam, slip, stick
            on = p > 0                   # the step's stick/slip record, before the anchors move
            # the hardening's share of the slipping nodes' friction (of the largest nodal friction)
            excess = self.hardening_excess(t, p, stick)
            slid = np.linalg.norm(self.step_slip(x, n, lam, slip), axis=1)
            self.step_stats = dict(sticking=int(np.count_nonzero(on & stick)),
                                   slipping=int(np.count_nonzero(on & ~stick)),
                                   largest_slip=float(slid[on & (~stick | (slid > self.tol))].max(initial=0.0)),
                                   stick=np.where(on, stick.astype(float), np.nan),
                                   excess=float(self.largest(float(excess.max(initial=0.0)))),
                                   excess_node=int(self.nodes[int(np.argmax(excess))]) if len(excess) else -1)
            self.tau = t @ self.obstacle.transform(lam)[:3, :3]
            self.y_a = self.placement(x, lam)
