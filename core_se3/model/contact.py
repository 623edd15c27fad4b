"""Frictionless contact of the shell with rigid obstacles (``model.obstacles``): node-to-surface,
a C^1-regularised augmented Lagrangian (penalty: the same law with the multipliers held), as a
:class:`~core_se3.model.Load` with the solver hooks of the Load protocol (``limit_increment``,
``update_multipliers``).  Derivations in docs/CONTACT.md.

Contact surface.  The shell touches with its face toward the obstacle, the mid-surface offset by
h/2 along the director: node i's contact point is

    x_i = phi_i + c_i d3_i,    c_i = s_i h / 2,    s_i = -sign(n(X_i, lam_ref) . d3_i(ref)),

s_i = +1 (the +d3 face) when, in the reference configuration, the obstacle lies on the +d3 side
of the node (``side`` overrides it).  The offset follows the current director d3, so the gap
couples to the rotation and the force F_i at x_i exerts the moment (x_i - phi_i) x F_i.

Sampling.  Gaps are sampled at the nodes with the nodal areas A_i = int N_i dA: one constraint
per node, 6x6 nodal tangent blocks, no over-constraint (Gauss-point gaps on bilinear quads give
four constraints per element for about one node: contact locking).  On a plane nodal
non-penetration is that of the interpolated surface; on a convex obstacle of radius rho a chord
may cut in by ~ l_e^2 / (8 rho) between nodes.

Law (pressure p >= 0 per unit reference area, F_i = A_i p_i n(x_i)):

    p = ramp(u0(lam_i) - k_i d_i; k_i eps),   u0 = ramp^-1,
    ramp(u; w) = 0 (u <= 0), u^2 / (2 w) (0 < u < w), u - w/2 (u >= w),

with multipliers lam_i >= 0 [force/length^2], penalty k_i = beta K_i / A_i [force/length^3] (K_i
the translational diagonal of the shell's own tangent at node i) and band eps [length].  p(0) =
lam_i exactly, so the Uzawa fixed points lam_i <- p_i(d_i) are the Signorini conditions, whatever
eps.  Generalised force and tangent, with n_b = R^T n, H_b = R^T H R, B = [I, -c hat(e3)]:

    f = B^T F_b,  F_b = A p n_b,   -df/deta = -B^T [A (p' n_b n_b^T + p H_b) B + [0, hat(F_b)]].

Example
-------
>>> from core_se3 import Problem, Material, mesh
>>> p = Problem(mesh.rectangle(1.0, 0.2, 4, 1), Material(1e4, 0.0, 0.02))
>>> p.clamp("x0"); p.add_pressure(-1.0)
>>> c = p.add_obstacle("half_space", point=(0.0, 0.0, -0.05), normal=(0.0, 0.0, 1.0), name="floor")
>>> st = p.solve(steps=2).final
>>> F = st.contact["floor"]["force"]
>>> bool(F[2] > 0), bool(c.penetration(st.g, 1.0) <= c.tol), bool(st.balance_error < 1e-8)
(True, True, True)
"""
from __future__ import annotations

import copy
import warnings

import numpy as np

from .. import lie
from ..errors import AccuracyWarning, did_you_mean
from .base import Load, LoadEvaluation
from .contact_faces import face_minima, face_wrench
from .contact_output import ContactOutputs, field_key, field_key_clash
from .friction import CoulombFriction, wrench
from .loads import element_area
from .contact_sweep import crossing_report
from .contact_law import (E3, MODES, ContactLaw, as_contact_law, contact_wrench, nodal_areas, normal_law, ramp,
                          ramp_inverse, reference_sides, shell_diagonal_stiffness)
from .obstacles import Obstacle, contact_error, make_obstacle, rigid_motion

RULED_SLOPE = 0.1
"""A face sample on a line contact (a roller's axis or a box's edge across the face,
``contact_faces._flat``) stays on the face's middle line while the gap changes by at most this
times h from there to the face's edge; the outputs' penetration is that of the line's lower end."""
SIDES = {"auto": "auto", "top": 1.0, "bottom": -1.0, "mid": 0.0}    # the contact face: auto, +d3, -d3, mid-surface

__all__ = ["SIDES", "ContactLoad", "ContactLaw", "add_obstacle", "ramp", "ramp_inverse", "normal_law", "contact_wrench",
           "nodal_areas", "shell_diagonal_stiffness", "reference_sides", "MODES"]


class ContactLoad(ContactOutputs, CoulombFriction, Load):
    """Frictionless contact of the nodes ``nodes`` (default all nodes of ``elements``, default all)
    with one rigid ``obstacle``, as a load (module docstring); made by ``Problem.add_obstacle``.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (mesh, thickness, element for the penalty scale).
    obstacle : core_se3.model.obstacles.Obstacle
        The obstacle; its ``name`` names the contact in reports and output fields.
    nodes, elements : array_like of int, optional
        Contact nodes, and the elements whose areas they carry.
    side : 'auto', +1 ('top'), -1 ('bottom'), 0 ('mid') or (k,) of the numbers
        The contact face (module docstring); 0: the mid-surface (c = 0), for a boundary edge
        pressed end-on, whose end face touches about its middle (no moment about the node).
    lam_ref : float
        The load factor of the reference placement that decides the 'auto' side.
    friction : float
        Coulomb's coefficient mu >= 0 of the contact nodes (``model.friction``; 0: frictionless,
        the face samples are frictionless in any case).
    law : ContactLaw or dict, optional
        How the contact is enforced (``model.contact_law.ContactLaw``: mode 'al' or 'penalty',
        beta or k, eps, tol, cap_depth, cold_start, soft_start, faces); default ContactLaw().

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import make_obstacle
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e4, 0.0, 0.02))
    >>> c = ContactLoad(p, make_obstacle("sphere", centre=(0.5, 0.0, 0.5), radius=0.4))
    >>> c.side.tolist(), round(float(c.gaps(p.mesh.g0, 0.0).min()), 4)     # the top face, ~0.1 away
    ([1.0, 1.0, 1.0, 1.0, 1.0, 1.0], 0.1001)
    >>> ContactLoad(p, make_obstacle("sphere", centre=(0.5, 0.0, 0.5), radius=0.4),
    ...             law=ContactLaw(mode="penalty", eps=0.01)).eps
    0.01
    """

    kind = "contact"
    scales_with_load_factor = False
    constraint_force = True
    conservative = False            # (a unilateral constraint, and friction dissipates)

    def __init__(self, problem, obstacle, nodes=None, elements=None, side="auto", lam_ref=0.0, friction=0.0,
                 law=None):
        if not isinstance(obstacle, Obstacle):
            raise contact_error(f"expected a core_se3.model.obstacles.Obstacle, got {type(obstacle).__name__}")
        self.law = law = as_contact_law(law)
        mesh = problem.mesh
        self.obstacle, self.mode, self.name = obstacle, law.mode, obstacle.name
        self.n = mesh.n_nodes
        el, h_node = self._contact_nodes(problem, nodes, elements)
        if isinstance(side, str) and side in SIDES:
            side = SIDES[side]
        if isinstance(side, str) and side == "auto":
            s = reference_sides(obstacle, mesh.g0[self.nodes], lam_ref)
        else:
            if isinstance(side, str) or np.asarray(side).dtype.kind not in "iuf":      # a bool is no side
                raise contact_error(f"side must be one of {', '.join(map(repr, SIDES))} or +1, -1, 0 (one or one "
                                    f"per contact node), got {side!r}", "side")
            s = np.broadcast_to(np.asarray(side, float), self.nodes.shape).copy()
            if not np.all(np.isin(s, (-1.0, 0.0, 1.0))):
                raise contact_error("side must be 'auto', +1, -1, 0 (the mid-surface) or one of them per contact "
                                    "node", "side")
        self.h = float(h_node[self.nodes].max())
        self.side, self.c = s, s * h_node[self.nodes] / 2
        self.beta = float(law.beta)
        if law.k is None:
            self.k = self.beta * shell_diagonal_stiffness(problem)[self.nodes] / self.A
        else:
            self.k = self._given_penalty(law.k)
        if not np.all(np.isfinite(self.k)) or np.any(self.k <= 0):
            raise contact_error("the contact penalty must be positive and finite (beta > 0)", "beta")
        self.eps, self.tol, self.cap_depth = law.lengths(self.h)
        self._held = getattr(problem, "constraint_mask", None)      # the supports, for failure_hint
        self._loads = getattr(problem, "loads", [])                   # the other obstacles, for failure_hint
        self._X = mesh.X[self.nodes]                                    # the contact nodes, for failure_hint
        self._faces(mesh, el, law.faces)
        self._start(mesh, friction)

    def _given_penalty(self, k):
        """The penalty ``k`` of the law: a number or one per contact node (k,) -> (k,); a
        ContactError naming the key and the expected shape for anything else (a bool or a
        string is no number)."""
        a = np.asarray(k)
        # NumPy reads [1e5, ..., True] as floats: a bool among the numbers is none either
        boolean = not isinstance(k, np.ndarray) and any(isinstance(e, (bool, np.bool_))
                                                         for e in np.asarray(k, dtype=object).ravel())
        if boolean or a.dtype.kind not in "iuf" or a.shape not in ((), self.nodes.shape):
            what = f"shape {a.shape}" if a.dtype.kind in "iuf" and not boolean else repr(k)[:60]
            raise contact_error(f"contact {self.name!r}: the penalty k must be a number or one per contact node, shape "
                                f"({len(self.nodes)},) in the order of the contact nodes, got {what}", "k")
        return np.broadcast_to(a.astype(float), self.nodes.shape).copy()

    def _contact_nodes(self, problem, nodes, elements):
        """The contact nodes and their areas A; returns (the contact elements, the thickest
        contact element's h at each node)."""
        mesh = problem.mesh
        per = getattr(problem.material, "per_element", None)
        h_el = per("h") if per is not None else np.full(mesh.n_elements, float(problem.material.h))
        el = np.arange(mesh.n_elements) if elements is None else np.asarray(elements, np.int64)
        h_node = np.zeros(mesh.n_nodes)                  # the thickest contact element at each node
        np.maximum.at(h_node, mesh.quads[el].ravel(), np.repeat(h_el[el], 4))
        area = nodal_areas(mesh, elements, element_area(problem, el))       # the element's own area (curved)
        self.nodes = np.nonzero(area > 0)[0] if nodes is None else np.asarray(nodes, np.int64)
        self.A = area[self.nodes]
        if len(self.nodes) == 0 or np.any(self.A <= 0):
            raise contact_error("contact nodes must belong to the contact elements (zero area weight)", "nodes")
        return el, h_node

    def _faces(self, mesh, el, faces):
        """The contact faces in contact-node positions, and the face samples (``model.contact_faces``)
        on curved obstacles: each face's area and penalty are the means of its nodes'."""
        where = np.full(mesh.n_nodes, -1)
        where[self.nodes] = np.arange(len(self.nodes))
        quads = where[mesh.quads[el]]
        on = (quads >= 0).all(1)
        self._quads = quads[on]                     # the contact faces, in contact-node positions
        self._quad_el = el[on]                      # their elements (a rank's share: parallel.localize)
        self._mesh_quads = mesh.quads
        size = np.linalg.norm(mesh.X[mesh.quads[el, 2]] - mesh.X[mesh.quads[el, 0]], axis=1).max(initial=0.0)
        flat = getattr(self.obstacle, "flat", False)
        self._thin = float(getattr(self.obstacle, "thickness", np.inf)) < size and not flat
        if isinstance(faces, str) and faces == "auto":
            faces = self._thin
        elif self._thin and not faces:
            warnings.warn(AccuracyWarning(
                f"obstacle {self.name!r} is thinner (inradius {float(self.obstacle.thickness):.3g}) than the contact "
                f"elements (diameter up to {size:.3g}) and faces = false: it can pass between the nodes unfelt; set "
                f"faces = true (or 'auto', the default) in the contact law (a scenario's [[obstacles]] key), or refine "
                f"the mesh"), stacklevel=5)
        use = bool(faces) and not flat
        self.face_el = el[on] if use else np.zeros(0, np.int64)
        self.face_q = self._quads if len(self.face_el) else np.zeros((0, 4), np.int64)
        self.Af, self.kf = self.A[self.face_q].mean(1), self.k[self.face_q].mean(1)

    def _start(self, mesh, friction):
        """Multipliers, soft-start factors and friction history at the reference state."""
        cold, self.soft_start = self.law.starts()
        kk = np.concatenate([self.k, self.kf])
        self.lam0 = (kk * self.eps / 8) * cold
        self.lam = self.lam0.copy()
        self.soft = np.full(len(kk), self.soft_start)
        if isinstance(friction, str) or np.ndim(friction) or np.asarray(friction).dtype.kind not in "iuf":
            raise contact_error(f"the friction coefficient must be a number >= 0 (Coulomb's mu), got {friction!r}",
                                "friction")
        self.mu = float(friction)
        if not (np.isfinite(self.mu) and self.mu >= 0):
            raise contact_error(f"the friction coefficient must be >= 0 and finite, got {friction}", "friction")
        if self.mu > 0 and len(self.face_el):
            warnings.warn(AccuracyWarning(
                f"obstacle {self.name!r}: friction {self.mu:g} acts at the contact nodes only, and this obstacle is "
                "felt by face samples too (faces = true, or 'auto' on an obstacle thinner than the elements), which "
                "are frictionless: where it touches a face between the nodes its friction is lost (a free strip on "
                "two rough rollers slid along their axes, unresisted); refine the mesh so that the nodes carry the "
                "contact, or set faces = false"), stacklevel=5)
        if self.mu > 0:          # the history: tangential multipliers (obstacle frame) and anchors
            self.tau = np.zeros((len(self.nodes), 3))
            self.y_a0 = self.placement(self.contact_points(mesh.g0), 0.0)
            self.y_a = self.y_a0.copy()
        self.gap_error = 0.0
        self.approximate_tangent = bool(self.obstacle.approximate_hessian)
        self._active = np.zeros(len(self.nodes), bool)
        self._normals = np.zeros((len(self.nodes), 3))
        # a node resting on the obstacle in the reference state takes the full penalty at once
        self.soft0 = self.soft.copy()
        self.soft0[:len(self.nodes)][self.gaps(mesh.g0, 0.0) <= self.tol] = 1.0
        self.soft = self.soft0.copy()
        n = self.state(mesh.g0, 0.0)[2]            # the active set of the reference state
        if self.mu > 0:
            self.check_normals(n)

    # ------------------------------------------------------------------ kinematics, law
    def contact_points(self, g):
        """x_i = phi_i + c_i d3_i (k, 3) at the contact nodes [length]."""
        return g[self.nodes, :3, 3] + self.c[:, None] * g[self.nodes, :3, 2]

    def state(self, g, lam):
        """(x, d, n, H, p, dp) at the contact nodes (and the active set for :meth:`restraint`)."""
        x = self.contact_points(g)
        d, n, H = self.obstacle.evaluate(x, lam)
        kn = len(self.nodes)
        p, dp = normal_law(d, self.lam[:kn], self.k * self.soft[:kn], self.eps)
        self._active, self._normals, self._gaps = (p > 0) | (dp < 0), n, d
        return x, d, n, H, p, dp

    def face_state(self, g, lam):
        """(samples, p, dp) of the face samples (``model.contact_faces``): the samples dict of
        :func:`~core_se3.model.contact_faces.face_minima`; p = 0 where a face has none."""
        xq = self.contact_points(g)[self.face_q]
        s = face_minima(self.obstacle, xq, lam, line=self.h * RULED_SLOPE)
        kn = len(self.nodes)
        p, dp = normal_law(s["d"], self.lam[kn:], self.kf * self.soft[kn:], self.eps)
        return s, np.where(s["ok"], p, 0.0), np.where(s["ok"], dp, 0.0)

    def face_forces(self, g, lam):
        """Lab forces (m, 3) of the face samples and their points (m, 3)."""
        s, p, _ = self.face_state(g, lam)
        return (self.Af * p)[:, None] * s["n"], s["x"]

    def placement(self, x, lam):
        """Lab points x (k, 3) in the obstacle's placement coordinates at lam."""
        T = self.obstacle.transform(lam)
        return (x - T[:3, 3]) @ T[:3, :3]

    def node_forces(self, g, lam):
        """Lab forces A (p n + t) (k, 3) on the contact nodes, their points x (k, 3), and dF/dx."""
        x, d, n, H, p, dp = self.state(g, lam)
        F = (self.A * p)[:, None] * n
        S = (self.A * dp)[:, None, None] * n[:, :, None] * n[:, None, :] + (self.A * p)[:, None, None] * H
        if self.mu > 0:
            t, dt, _, _ = self.friction_state(g, lam, x, n, H, p, dp)
            F, S = F + self.A[:, None] * t, S + self.A[:, None, None] * dt
        return F, x, S

    def evaluate(self, g, lam, tangent=True):
        if self.mu > 0:
            F, _, S = self.node_forces(g, lam)
            fb, Kb = wrench(g[self.nodes, :3, :3], self.c, F, S)
            slide = self._sliding(g, lam)        # the last evaluation in contact (failure_hint's evidence)
            self._slide = slide if slide[0] or not hasattr(self, "_slide") else self._slide
        else:
            x, d, n, H, p, dp = self.state(g, lam)
            fb, Kb = contact_wrench(g[self.nodes, :3, :3], self.c, self.A, n, H, p, dp)
        f = np.zeros((self.n, 6))
        f[self.nodes] = fb
        blocks = None
        if len(self.face_el):
            s, pf, dpf = self.face_state(g, lam)
            on = pf > 0
            if on.any():
                nq = self.nodes[self.face_q[on]]
                sub = {key: v[on] for key, v in s.items()}
                ff, Kf = face_wrench(g[nq, :3, :3], self.c[self.face_q[on]], self.Af[on], sub, pf[on], dpf[on])
                np.add.at(f, nq.ravel(), ff.reshape(-1, 6))
                blocks = (self.face_el[on], Kf)
        if not tangent:
            return LoadEvaluation(f)
        K = np.zeros((self.n, 6, 6))
        K[self.nodes] = Kb
        return LoadEvaluation(f, K, blocks)

    def restraint(self):
        """(nodes, lab normals (k, 1, 3)) of the nodes in contact at the last evaluation: a shell
        resting on an obstacle is held along the normals (for the rigid-motion check)."""
        on = self._active
        if self.mu > 0:                  # friction holds the tangential directions too
            return self.nodes[on], np.broadcast_to(np.eye(3), (int(on.sum()), 3, 3))
        return self.nodes[on], self._normals[on][:, None, :]

    # ------------------------------------------------------------------ solver hooks
    def limit_increment(self, g, eta, lam):
        """The step cap alpha in [1e-3, 1]: a node the current linearisation does not see (no force,
        no stiffness) that the full increment eta would carry deeper than max(eps/2, cap_depth)
        into the obstacle stops there, alpha = min (d0 + D) / (d0 - d1) (d0, d1 its gaps before and
        after).  Without it an iterate can land deep in a stiff contact whose unbalanced force
        throws Newton off; near convergence alpha = 1."""
        x, d0, n, H, p, dp = self.state(g, lam)
        free = (p <= 0) & (dp >= 0)
        if not free.any():
            return 1.0
        idx = self.nodes[free]
        g1 = g[idx] @ lie.exp(eta[idx])
        d1 = self.obstacle.distance(g1[:, :3, 3] + self.c[free, None] * g1[:, :3, 2], lam)
        depth = max(self.eps / 2, self.cap_depth)
        hit = d1 < -depth
        if not hit.any():
            return 1.0
        a = (d0[free][hit] + depth) / (d0[free][hit] - d1[hit])
        return float(np.clip(np.min(a), 1e-3, 1.0))

    def predict_start(self, g0, lam0, g, lam, fixed):
        """The start of a try at lam from the accepted state (g0, lam0) (the ``Load.predict_start``
        hook; g the start so far, fixed (n, 6) the supported dofs): when the obstacle moves over
        the increment, T_rel = T(lam) T(lam0)^-1, the nodes carrying force move with it -- a node
        that sticks (friction) rigidly, g <- T_rel g, the others by the normal part of its
        contact point's motion (n . (T_rel x - x)) n -- and so do the faces whose sample carries
        force (:meth:`_face_shift`), in their free dofs.  Without it the first iterate of a
        sticking node meets the whole increment as slip (the return mapping turns it into a full
        slip force, and Newton swings about the stuck state), and a node in contact starts inside
        a moving obstacle, at the penalty's stiffness.  g itself when the obstacle is at rest over
        the increment (every frictionless case of a fixed obstacle is unchanged)."""
        T0, T1 = self.obstacle.transform(lam0), self.obstacle.transform(lam)
        if np.array_equal(T0, T1):
            return g
        Trel = T1 @ lie.inv(T0[None])[0]
        shift, carried = self._face_shift(g0, lam0, lam, Trel)     # (collective on a rank's part)
        if not len(self.nodes):
            return g
        x, _, n, _, p, _ = self.state(g0, lam0)
        on = p > 0
        target = g[self.nodes].copy()
        move = np.einsum("ki,ki->k", n, x @ Trel[:3, :3].T + Trel[:3, 3] - x)
        target[:, :3, 3] += move[:, None] * n
        stick = self.sticking(lam0, n, p)
        target[stick] = Trel @ g[self.nodes[stick]]
        face = carried & ~on
        target[face, :3, 3] += shift[face]
        on |= face
        if not on.any():
            return g
        idx = self.nodes[on]
        eta = lie.log(lie.relative(g[idx], target[on]))
        eta[fixed[idx]] = 0.0
        g = g.copy()
        g[idx] = g[idx] @ lie.exp(eta)
        return g

    def _face_shift(self, g0, lam0, lam, Trel):
        """((k, 3) lab shifts of the contact nodes, (k,) the nodes shifted): each face whose sample
        x* carries force at (g0, lam0) moves its four nodes by -(d(x*, lam) - d(x*, lam0)) n(x*, lam),
        which keeps the sample's gap as the obstacle moves (exact for a plane; a node of several
        such faces takes their mean).  The nodal rule alone left a ball held by face samples
        behind: a ball of radius 0.05 pressed 0.05 into a 2 x 1 plate (elements 0.25) and slid
        along it in 20 steps started each slide step with the contact lost (first residual 0.16
        of the forces whatever the step), and its first two steps took 125 and 113 tries (now 3
        and 4).  For a translating obstacle only: a turning one's sample can jump across the face
        (a box cam's rounded edge turning under a strip: carried so, its 10 steps stopped at 0.6)."""
        shift, count = self._sum_shared(*self._face_shift_sums(g0, lam0, lam, Trel))
        carried = count > 0
        shift[carried] /= count[carried, None]
        return shift, carried

    def _face_shift_sums(self, g0, lam0, lam, Trel):
        """(the sum of the shifts of :meth:`_face_shift` over the faces of each contact node,
        their number) (k, 3), (k,)."""
        k = len(self.nodes)
        shift, count = np.zeros((k, 3)), np.zeros(k)
        if not len(self.face_el) or not np.allclose(Trel[:3, :3], np.eye(3), rtol=0.0, atol=1e-12):
            return shift, count
        s, pf, _ = self.face_state(g0, lam0)
        on = pf > 0
        if not on.any():
            return shift, count
        s1, _, _ = self.face_state(g0, lam)
        on &= s1["ok"]
        v = -np.maximum(0.0, s1["d"][on] - s["d"][on])[:, None] * s1["n"][on]
        q = self.face_q[on]
        np.add.at(shift, q.ravel(), np.repeat(v, 4, axis=0))
        np.add.at(count, q.ravel(), 1.0)
        return shift, count

    def _sum_shared(self, shift, count):
        """Per-node sums over the faces of the whole problem (here: this load's own; a rank's part
        adds the other ranks' faces of its nodes on a partition boundary)."""
        return shift, count

    def start_error(self, g, lam):
        """Refuse a try that starts with a contact point deeper than the thickness h inside the
        obstacle (a moving obstacle that swept into the shell over the increment: from there the
        node may be pushed out on the far side, tunnelling); the solver cuts the increment back."""
        d = self.gaps(g, lam)
        if not len(d):                    # no contact node here (a rank's part of the load)
            return ""
        # an Uzawa re-solve at the load factor of the last update starts from an equilibrium:
        # there a node whose multiplier carries force is pushed out by it (a soft first contact)
        if lam == getattr(self, "_lam_update", None):
            d = np.where(self.lam[:len(d)] > self.lam0[:len(d)], np.inf, d)
        i = int(np.argmin(d))
        if d[i] < -self.h:
            return (f"obstacle {self.name!r} starts the increment {-d[i]:.3g} inside the shell at node "
                    f"{int(self.node_ids[i])} (more than the thickness {self.h:.3g}): smaller increment")
        return ""

    def step_error(self, g0, lam0, g1, lam1):
        """Refuse a converged step whose contact surface passed through the obstacle between the
        accepted state (g0, lam0) and the new one (g1, lam1): the nodes' and the faces' paths,
        linear in the lab, against the obstacle's rigid motion (``model.contact_sweep``); deeper
        than min(h/2, half the obstacle's thickness) anywhere is a crossing, and the solver cuts
        the step back.  '' when the step is clear."""
        if not len(self.nodes):
            return ""
        if self.mu > 0 and (why := self.cone_excess(g1, lam1)):
            return why
        thick = float(getattr(self.obstacle, "thickness", np.inf))
        depth = max(min(self.h / 2, thick / 2), 2 * self.tol)
        return crossing_report(self.obstacle, self._quads, self.contact_points(g0), self.contact_points(g1),
                               lam0, lam1, depth, (self.node_ids, self.face_ids)) or self.face_crossing(g1, lam1)

    def lift_off(self, g0, lam0, g1, lam1):
        """(the largest lift-off [length], the node) of the try from (g0, lam0) to (g1, lam1): over
        the contact nodes that touched the obstacle at its start (gap at most h/100), how far
        each ended from it by its own motion -- its gap at the end beyond the one the obstacle's
        motion alone would have opened, d(x1, lam1) - max(d(x0, lam1), 0); (0.0, -1) if none.

        A node carried along by an advancing obstacle ends on it (0); one released by a retreating
        obstacle ends no farther than the retreat (0); one that jumps away -- a roof pushed at its
        crown that snaps through ahead of the pusher -- ends as far as its jump.  The snap check
        (``solvers.contact_probe``) probes a try whose lift-off exceeds LIFT_OFF h: a jump survives
        the halving, a continuous lift-off shrinks with the step."""
        if not len(self.nodes):
            return 0.0, -1
        x0 = self.contact_points(g0)
        touching = self.obstacle.evaluate(x0, lam0)[0] <= 0.01 * self.h
        if not touching.any():
            return 0.0, -1
        x1 = self.contact_points(g1)[touching]
        lift = self.obstacle.evaluate(x1, lam1)[0] - np.maximum(self.obstacle.evaluate(x0[touching], lam1)[0], 0.0)
        i = int(np.argmax(lift))
        return float(lift[i]), int(np.asarray(self.node_ids)[touching][i])

    def face_crossing(self, g, lam):
        """'' unless a curved obstacle reaches into a contact face between its nodes at (g, lam)
        where no constraint feels it (:meth:`unfelt_face`); steps ending so are refused (the
        sweep forgives penetration present at an end state), with the fix: face samples, or,
        where they are on but cannot hold the obstacle there (a sharp edge or corner), more
        steps or a larger rounding."""
        e, depth = self.unfelt_face(g, lam)
        if e is None:
            return ""
        el = int(self.face_ids[e])
        if not len(self.face_el):
            return (f"obstacle {self.name!r} passes through the contact face of element {el} between its nodes at "
                    f"load factor {lam:.6g} ({depth:.3g} deep, through the shell): the nodes "
                    f"alone do not feel it; set faces = true (or 'auto') in the contact law (a scenario's "
                    "[[obstacles]] key), or refine the mesh")
        r = getattr(self.obstacle, "rounding", None)
        edge = f"its edges are rounded by {r:.3g}" if r is not None else "its surface is not smooth there"
        return (f"obstacle {self.name!r} reaches {depth:.3g} into the contact face of element {el} between its nodes "
                f"at load factor {lam:.6g}, where its face sample cannot hold it ({edge}: the face sample needs the "
                "obstacle's surface to be smooth and convex where it meets the face, and inside an edge or corner "
                "deeper than its rounding it is neither); give the obstacle a larger rounding (about a tenth of its "
                "smallest half size), or take more load steps, so that it moves into a face by less than its "
                "rounding per step")

    def unfelt_face(self, g, lam):
        """(the contact face's position in ``_quads``, its depth) of the deepest face that a curved
        obstacle reaches into between the nodes at (g, lam) unfelt, or (None, 0): the face's
        deepest point lies inside it (d < -tol, below the face's nodes by more than tol) and

        * faces not sampled (``faces = false``): the obstacle's normal there points along the face's
          own normal toward the obstacle side (mean of s_a d3_a) -- the point is past the
          obstacle's medial surface, its middle beyond the face -- or the obstacle is thinner than
          the elements and reaches deeper than the thickness h (through the shell); a chord that
          merely cuts a large obstacle (nodal sampling) has the normal against the face's;
        * faces sampled: the face's sample is not kept (``contact_faces.face_minima``: the
          obstacle is not smooth and convex there -- a box's edge, rounded by r, entered deeper
          than r between two states: a cam turning by 9 degrees a step under a strip of 0.05
          elements ended its steps 0.0078 and 0.011 through the strip, the strip flat, no force,
          penetration 0)."""
        if getattr(self.obstacle, "flat", False) or not len(self._quads):
            return None, 0.0
        on = np.nonzero(np.all(self.side[self._quads] != 0, axis=1))[0]
        x = self.contact_points(g)
        s = face_minima(self.obstacle, x[self._quads[on]], lam, line=self.h * RULED_SLOPE if len(self.face_el) else None)
        d_nodes = self.obstacle.distance(x, lam)[self._quads[on]].min(1)
        if len(self.face_el):
            past = (s["d"] < np.minimum(-self.tol, d_nodes - self.tol)) & ~s["ok"]
        else:
            m = np.einsum("ma,maj->mj", self.side[self._quads[on]], g[self.nodes[self._quads[on]], :3, 2])
            inside = s["d"] < np.minimum(-self.tol, d_nodes)
            # the middle beyond the face, or a thin obstacle through the whole shell between the nodes
            past = inside & ((np.einsum("mj,mj->m", s["n"], m) > 0) | (self._thin & (s["d"] < -self.h)))
        if not past.any():
            return None, 0.0
        e = int(np.argmin(np.where(past, s["d"], np.inf)))
        return int(on[e]), -float(s["d"][e])

    def clear(self, g, lam):
        """True when the obstacle exerts no force and no stiffness on the shell at the state
        (g, lam): every contact node's and face sample's pressure and its derivative are 0 (the
        law's ramp is exactly 0 beyond its band).  The step checks of smooth problems apply to a
        try whose two ends are clear (``solvers.newton``: an obstacle the path never touches
        turned them off for the whole run; fuzz seed 12, problem 78).

        Example
        -------
        >>> from core_se3 import Problem, Material, mesh
        >>> from core_se3.model import make_obstacle
        >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e4, 0.0, 0.02))
        >>> c = ContactLoad(p, make_obstacle("sphere", centre=(0.5, 0.0, 0.5), radius=0.4))
        >>> c.clear(p.mesh.g0, 0.0)
        True
        """
        kn = len(self.nodes)                   # state()'s law, without its record of the active set
        p, dp = normal_law(self.obstacle.distance(self.contact_points(g), lam), self.lam[:kn],
                           self.k * self.soft[:kn], self.eps)
        touching = bool(np.any(p > 0) or np.any(dp != 0))
        if not touching and len(self.face_el):
            _, pf, dpf = self.face_state(g, lam)
            touching = bool(np.any(pf > 0) or np.any(dpf != 0))
        return not self.largest(float(touching))

    def active_set_changed(self, g0, lam0, g1, lam1):
        """True when a node touches (gap within 10 tol) at one of the states and not at the other:
        lift-off or touch-down over the step (the limit check re-bases its stiffness); with
        friction also when a node in contact passes from stick to slip or back (its tangent
        loses or regains the penalty along the slip)."""
        on0, on1 = self.gaps(g0, lam0) <= 10 * self.tol, self.gaps(g1, lam1) <= 10 * self.tol
        changed = np.any(on0 != on1)
        if self.mu > 0 and not changed:
            _, _, n0, _, p0, _ = self.state(g0, lam0)
            stick0 = self.sticking(lam0, n0, p0)
            x, _, n, H, p, dp = self.state(g1, lam1)
            stick1 = self.friction_state(g1, lam1, x, n, H, p, dp)[2] & (p > 0)
            changed = np.any(stick0 != stick1)
        return bool(self.largest(float(changed)))

    def update_multipliers(self, g, lam):
        """At a converged state: the gap error e (|d| on nodes carrying force, the penetration on
        the others) over ``tol``; when it exceeds 1 (mode 'al') the multipliers are updated,
        lam_i <- p_i(d_i) (Uzawa), and the solver solves the same load factor again."""
        _, d, _, _, p, _ = self.state(g, lam)
        if len(self.face_el):
            s, pf, _ = self.face_state(g, lam)
            d, p = np.concatenate([d, np.where(s["ok"], s["d"], np.inf)]), np.concatenate([p, pf])
        err = np.where(p > 0, np.abs(d), np.maximum(0.0, -d)) if self.mode == "al" else np.maximum(0.0, -d)
        if self.mu > 0:          # the tangential error |t - P w| / k [length]
            x, _, n, H, pn, dpn = self.state(g, lam)
            t, _, _, _ = self.friction_state(g, lam, x, n, H, pn, dpn)
            Q = self.obstacle.transform(lam)[:3, :3]
            w = self.tau @ Q.T
            w -= np.einsum("ki,ki->k", n, w)[:, None] * n
            kn = self.k * self.soft[:len(self.nodes)]
            err[:len(self.nodes)] = np.maximum(err[:len(self.nodes)], np.linalg.norm(t - w, axis=1) / kn)
        self.gap_error = float(self.largest(float(err.max(initial=0.0))))
        self._lam_update = lam
        if self.mode != "al":
            return 0.0
        ratio = self.gap_error / self.tol
        kn = len(self.nodes)
        i = int(np.argmin(d[:kn])) if kn else 0          # the deepest node (failure_hint)
        # (mesh node, depth, its id in messages: a rank's part names the whole mesh's, ``node_ids``)
        self._stuck = (int(self.nodes[i]), float(-d[i]), int(self.node_ids[i])) \
            if ratio > 1.0 and kn and d[i] < -self.tol else None
        j = int(np.argmin(d[kn:])) if len(d) > kn else 0
        self._stuck_face = ((int(self.face_ids[j]), self.nodes[self.face_q[j]], self.contact_points(g)[self.face_q[j]], lam,
                             np.asarray(self.node_ids)[self.face_q[j]])
                            if ratio > 1.0 and len(d) > kn and d[kn + j] < -self.tol else None)
        if ratio > 1.0:
            self.lam = self._extrapolated(p, lam)
            self.soft = np.where(p > 0, np.minimum(1.0, 10 * self.soft), self.soft_start)
            if self.mu > 0:
                self.tau = t @ Q
        return ratio

    def _extrapolated(self, p, lam, slow=0.9):
        """The multipliers after the Uzawa update to p at load factor lam: p itself, or, when the
        last two updates' steps s = p - lam_i at this load factor were parallel (cosine above
        0.999) and shrank by a ratio r in (slow, 1) with the same samples carrying force at full
        penalty, lam_i + s / (1 - r) (the sum of the geometric series; at least 0).  Two samples of
        neighbouring faces a few 1e-3 apart under one ball (the node line between them a ridge)
        are nearly redundant: the update moved force from one to the other at r = 0.982 per
        update, and a ball slid in 20 steps stopped under the line at "constraint error 1.06 x
        its tolerance after 25 multiplier updates" (9.87 x after 80).  The fixed point is Uzawa's;
        the history starts afresh after an extrapolation, a restore or a new load factor, and
        with friction or on a rank's part (its own samples' steps) none is made."""
        step, on = p - self.lam, (p > 0) & (self.soft >= 1.0)
        last = getattr(self, "_uzawa", None)
        self._uzawa = (lam, step, on)
        if (last is None or last[0] != lam or self.mu > 0 or getattr(self, "comm", None) is not None
                or not np.array_equal(last[2], on) or not on.any()):
            return p
        s0, s1 = last[1][on], step[on]
        r = float(s1 @ s0) / max(float(s0 @ s0), 1e-300)
        if not (slow < r < 1.0 and s1 @ s0 > 0.999 * np.linalg.norm(s0) * np.linalg.norm(s1)):
            return p
        self._uzawa = None
        return np.where(on, np.maximum(0.0, self.lam + step / (1.0 - r)), p)

    def failure_hint(self):
        """Why the failed try could not converge, from the contact's side: friction's 'it slides'
        (``CoulombFriction.failure_hint``), distances carrying round-off above the tolerance
        (:meth:`roundoff_hint`), a node pinched between this obstacle and another
        (:meth:`pinch`), or an obstacle pressing into a node whose translations a
        support holds (the multiplier updates ran out with that node deepest inside: no state has
        it outside; the message said only "raise max_augmentations or the tolerance"), or ''."""
        hint = super().failure_hint() or self.roundoff_hint()
        stuck = getattr(self, "_stuck", None)
        if hint or stuck is None:
            return hint or self.held_face_hint()
        if pinch := self.pinch(stuck[0]):
            return pinch
        if self._held is None or not self._held()[stuck[0], :3].all():
            return hint
        return (f"obstacle {self.name!r} presses {stuck[1]:.3g} into node {stuck[2]}, whose translations a support "
                "holds: no equilibrium has the node outside it; keep the obstacle's motion off the held nodes "
                "(or release them)")

    def held_face_hint(self):
        """'' unless the multiplier updates ran out with a face sample inside the obstacle on a face
        with an edge whose two nodes a support holds in translation, and that edge (straight, and
        fixed) reaches into the obstacle (33 points along it) at this load factor or on the
        obstacle's way to load factor 1 (33 load factors): no state has it outside (a clamped
        line across a plate in the way of a ball of radius 0.05 sliding between its nodes stopped
        with "raise NewtonOptions.max_augmentations", which cannot help).  Ahead of the edge the
        face props the sample ever more stiffly (a lever about the held edge), so the updates
        contract ever more slowly and run out before the obstacle reaches it: the line x = 1.25
        stopped that ball at 0.789 (0.07 from the line) with "raise max_augmentations" alone."""
        face = getattr(self, "_stuck_face", None)
        if face is None or self._held is None:
            return ""
        el, nodes, xq, lam, ids = face
        held = self._held()[nodes, :3].all(1)
        edges = [(a, (a + 1) % 4) for a in range(4) if held[a] and held[(a + 1) % 4]]
        t = np.linspace(0.0, 1.0, 33)[:, None]
        for lam_k in np.linspace(lam, max(lam, 1.0), 33) if edges else ():
            for a, b in edges:
                depth = -float(self.obstacle.evaluate((1 - t) * xq[a] + t * xq[b], lam_k)[0].min())
                if depth > self.tol:
                    ahead = "" if lam_k == lam else (
                        f" at load factor {lam_k:.6g}, on its way from this one ({lam:.6g}; the face next to the edge "
                        "props it ever more stiffly as it nears, and the multiplier updates stall before it)")
                    return (f"obstacle {self.name!r} presses {depth:.3g} into the edge between nodes {int(ids[a])} and "
                            f"{int(ids[b])} of element {el}, whose translations a support holds{ahead}: no equilibrium "
                            "has the edge outside it; keep the obstacle's motion off the held nodes and the edges between "
                            "them (or release them)")
        return ""

    def roundoff_hint(self):
        """'' unless the obstacle's placement point (a ball's centre) lies so far from the contact
        nodes (rho) that its distances carry a round-off of rho * 2.2e-16 above 1e-4 of ``tol``: the
        contact stiffness turns that jitter into residual noise above Newton's tolerance (a ball of
        radius 1e5 under a strip with h = 0.01 stopped at first contact, "no convergence in 30
        iterations", its tangent 1.8e-3 off central differences; a half-space converges)."""
        key = getattr(self.obstacle, "position_attribute", None)
        if key is None or getattr(self.obstacle, "flat", False) or not len(self.nodes):
            return ""
        rho = float(np.linalg.norm(self._X - np.asarray(getattr(self.obstacle, key), float), axis=1).max())
        if rho * np.finfo(float).eps <= 1e-4 * self.tol:
            return ""
        return (f"obstacle {self.name!r}: its {key} lies {rho:.3g} from the contact nodes, so its distances carry a "
                f"round-off of {rho * np.finfo(float).eps:.2g} (the contact tolerance is {self.tol:.2g}), which its "
                "stiffness turns into residual noise above Newton's tolerance; for a surface this flat over the part "
                "use a half_space (or a smaller radius)")

    def pinch(self, node):
        """'' unless mesh node ``node`` is pressed at the last evaluation by this obstacle and by
        another on its other face (normals opposed): the room between the two there is then less
        than the shell's thickness, which no state can have (the shell is not squeezed through its
        thickness; the multiplier updates ran out with "raise max_augmentations")."""
        i = np.nonzero(self.nodes == node)[0]
        if getattr(self, "whole", None) is not None:      # a rank's part (its node ids are local): not checked
            return ""
        for other in self._loads:
            j = np.nonzero(other.nodes == node)[0] if isinstance(other, ContactLoad) and other is not self else []
            if not len(i) or not len(j) or not hasattr(other, "_gaps") or not other._active[j[0]]:
                continue
            i, j = i[0], j[0]
            if self._normals[i] @ other._normals[j] < 0 and self.c[i] != other.c[j]:
                room = self._gaps[i] + other._gaps[j] + abs(self.c[i] - other.c[j])
                return (f"node {int(node)} is pinched between obstacles {self.name!r} and {other.name!r}: the room "
                        f"between them there is {room:.6g}, less than the shell's thickness {abs(self.c[i] - other.c[j]):.6g} "
                        "(a shell is not squeezed through its thickness); keep the obstacles at least h apart")
        return ""

    @property
    def node_ids(self):
        """The mesh ids of the contact nodes, in messages (``nodes``; a rank's part of the load,
        ``parallel.localize.LocalContact``, names the whole mesh's)."""
        return self.nodes

    @property
    def face_ids(self):
        """The mesh ids of the contact faces' elements, in messages (as :attr:`node_ids`)."""
        return self._quad_el

    def largest(self, value):
        """The largest of ``value`` over the processes that share this load: the value itself
        (a rank's part under mpirun, ``parallel.localize.LocalContact``, takes it over the ranks).

        Example
        -------
        >>> ContactLoad.largest(None, 2.5)
        2.5
        """
        return value

    def multipliers(self):
        """The restart point: the multipliers [force/length^2] of the nodes and the face samples
        followed by their penalty factors (``soft_start``), one array."""
        hist = [self.tau.ravel(), self.y_a.ravel()] if self.mu > 0 else []
        return np.concatenate([self.lam, self.soft] + hist)

    def set_multipliers(self, lam=None):
        """Set the multipliers (None: back to the cold start); the nodes' alone (k,) leave the
        face samples' at the cold start.  A restore starts the friction's step record afresh
        (``accept_state``: the relaxations of one accepted state add up)."""
        self._step_at = self._uzawa = None
        self.lam = self.lam0.copy()
        self.soft = self.soft0.copy()
        if self.mu > 0:
            self.tau, self.y_a = np.zeros_like(self.tau), self.y_a0.copy()
        if lam is not None:
            lam = np.array(lam, float).ravel()
            m = len(self.lam0)
            if self.mu > 0 and len(lam) == 2 * m + 6 * len(self.nodes):     # with the friction history
                k3 = 3 * len(self.nodes)
                self.tau = lam[2 * m:2 * m + k3].reshape(-1, 3).copy()
                self.y_a = lam[2 * m + k3:].reshape(-1, 3).copy()
                lam = lam[:2 * m]
            if len(lam) == 2 * m:                      # multipliers and penalty factors
                self.lam, self.soft = lam[:m].copy(), lam[m:].copy()
            elif len(lam) == len(self.nodes) or len(lam) == m:     # multipliers alone: full penalties
                self.lam[:len(lam)] = lam
                self.soft[:] = 1.0
            else:
                raise contact_error(f"contact {self.name!r}: {len(lam)} multipliers for {m} samples")


def add_obstacle(problem, obstacle, region=None, nodes=None, name=None, side="auto", friction=0.0, law=None,
                 **params):
    """Add contact with a rigid obstacle to ``problem``; returns the ContactLoad.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem.
    obstacle : str or Obstacle
        A registered kind (``model.OBSTACLES``: 'half_space', 'sphere', 'cylinder', 'box') with
        its ``params``, or an Obstacle instance (e.g. a ``UserSDF``).
    region, nodes : optional
        The contact elements (a region name or ids; default all) and nodes (a node selection;
        default all nodes of those elements).
    name : str, optional
        The contact's name in reports (default the kind).
    side, friction : optional
        The contact face and Coulomb's mu: as for :class:`ContactLoad`.
    law : ContactLaw or dict, optional
        How the contact is enforced (mode, beta, eps, tol, cap_depth, ...; ``ContactLaw``).
    **params
        The kind's parameters (e.g. centre, radius) and its ``motion``: lam -> (4, 4) rigid
        transform, or dict(translate, axis, angle, point) of
        :func:`~core_se3.model.obstacles.rigid_motion`; for a kind only.

    Returns
    -------
    ContactLoad
        ContactError for an unknown kind or key, a bad value, or an obstacle that already
        intersects the undeformed shell.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e4, 0.0, 0.02))
    >>> c = add_obstacle(p, "cylinder", point=(1.0, 0.0, -0.2), axis=(0, 1, 0), radius=0.1,
    ...                  motion=dict(translate=(0.0, 0.0, 0.1)), name="pusher", law=dict(mode="penalty"))
    >>> c.name, c.mode, round(float(c.obstacle.distance([[1.0, 0.0, 0.0]], lam=1.0)[0]), 12)
    ('pusher', 'penalty', 0.0)
    """
    motion = params.pop("motion", None)
    if isinstance(motion, dict):
        keys = ("translate", "axis", "angle", "point", "scale")
        for key in motion:
            if key not in keys:
                raise contact_error(f"unknown motion key {key!r}{did_you_mean(key, keys)}; a motion takes "
                                    f"{', '.join(keys)}", key)
        motion = rigid_motion(**motion)
    if isinstance(obstacle, str):
        obstacle = make_obstacle(obstacle, motion=motion, name=name, **params)
    elif params or motion is not None:
        raise contact_error("an Obstacle instance carries its own parameters and motion: give them to its "
                            f"constructor (got {', '.join(list(params) + ['motion'] * (motion is not None))})")
    elif name is not None and name != obstacle.name:
        obstacle = copy.copy(obstacle)           # the caller's instance (maybe another contact's) keeps its name
        obstacle.name = name
    elements = problem.elements(region)
    sel = None if nodes is None else problem.nodes(nodes)
    load = ContactLoad(problem, obstacle, sel, elements, side, 0.0, friction, law)
    load.check_initial(problem.mesh, problem.mesh.g0, 0.0)
    names = [ld.name for ld in problem.loads if isinstance(ld, ContactLoad)]
    if load.name in names:
        raise contact_error(f"there is already an obstacle named {load.name!r}: give each a name", "name")
    same = field_key_clash(names, load.name)
    if same is not None:
        raise contact_error(f"obstacles {same!r} and {load.name!r} have one VTU field name, contact_gap_"
                            f"{field_key(load.name)} (the output sums the two): name them apart in letters and "
                            "digits", "name")
    return problem.add(load)
