"""The outputs of a contact load (``model.contact.ContactLoad``): gaps, penetration, forces and
their totals, the per-step report, the VTU fields and the check of the undeformed shell, as a
mixin so that the law and the solver hooks stay in one screenful each."""
from __future__ import annotations

import warnings

import numpy as np

from .contact_faces import face_minima
from ..errors import AccuracyWarning
from .obstacles import contact_error

__all__ = ["ContactOutputs", "field_key", "field_key_clash"]


def field_key(name):
    """An obstacle's name in its VTU fields: contact_gap_KEY, friction_traction_KEY, ...

    Example
    -------
    >>> field_key("floor a")
    'floor_a'
    """
    return "".join(ch if ch.isalnum() else "_" for ch in name)


def field_key_clash(names, name):
    """The one of ``names`` (obstacle names) whose VTU fields ``name``'s would overwrite -- the
    output adds them up under one name -- or None; ``Problem.add_obstacle`` and a scenario's
    [[obstacles]] refuse it.

    Example
    -------
    >>> field_key_clash(["floor a", "ball"], "floor_a")
    'floor a'
    """
    return next((n for n in names if n != name and field_key(n) == field_key(name)), None)


class ContactOutputs:
    """Outputs of :class:`~core_se3.model.contact.ContactLoad` (which see)."""
    def gaps(self, g, lam):
        """d_i (k,) at the contact nodes [length]."""
        return self.state(g, lam)[1]

    def penetration(self, g, lam):
        """max_i (-d_i) over the nodes and the face samples, 0 when none penetrates [length]; a
        sample held on a line contact counts the line's lower end (``d_low``: the chord of a
        roller across a plate ended 3.9e-4 inside it, 0.02 h, with the samples' 9e-10 reported)."""
        pen = float(max(0.0, -self.gaps(g, lam).min()))
        if len(self.face_el):
            s, _, _ = self.face_state(g, lam)
            pen = max(pen, float(-s["d_low"][s["ok"]].min(initial=0.0)))
        return pen

    def face_cut(self, g, lam):
        """The deepest point of the contact faces inside a curved obstacle [length], nodes
        included: max(0, -min d) over each contact face's closest point to the obstacle
        (``face_minima``); 0 on a flat obstacle (d is trilinear there: no face cuts deeper than its
        nodes).  ``penetration`` counts the nodes and the face samples only; a large obstacle
        without face samples ('auto' samples only obstacles thinner than an element) may cut a
        face between its nodes unfelt: a box's edge (half sizes 0.6 x 0.8 x 0.6, turned edge up)
        pressed 0.1 into a 2 x 1 plate (8 x 4, h 0.02) ends 0.037 (1.8 h) inside the face between
        the nodes that rest on its sides, penetration 1.4e-9."""
        if getattr(self.obstacle, "flat", False):          # the same on every rank: no collective
            return 0.0
        on = np.nonzero(np.all(self.side[self._quads] != 0, axis=1))[0] if len(self._quads) else []
        d = face_minima(self.obstacle, self.contact_points(g)[self._quads[on]], lam)["d"] if len(on) else np.zeros(0)
        return float(self.largest(max(0.0, -float(d.min(initial=0.0)))))   # every rank calls it (mpirun)

    def warn_face_cut(self, cut, pen, lam):
        """An AccuracyWarning (once per obstacle) where the faces cut deeper than h/2 beyond the
        reported penetration: the obstacle reaches past the shell's mid-surface (the contact
        points lie on its face, ``contact_points``) between nodes that do not feel it."""
        if cut - pen <= 0.5 * self.h or getattr(self, "_cut_warned", False):
            return
        self._cut_warned = True
        sampled = "its face samples cannot hold it there (an edge or corner sharper than they follow)" \
            if len(self.face_el) else "no face samples are on (faces = 'auto' samples obstacles thinner than an element)"
        warnings.warn(AccuracyWarning(
            f"obstacle {self.name!r} cuts {cut:.3g} ({cut / self.h:.2g} h) into the shell's contact faces between their "
            f"nodes at load factor {lam:.6g}, while the reported penetration (nodes and face samples) is {pen:.3g}: "
            f"{sampled}; the obstacle reaches {'through the shell' if cut >= self.h else 'past its mid-surface'} there "
            "-- set faces = true in the contact law (a scenario's [[obstacles]] key), refine "
            "the mesh where it touches, or round the obstacle's edges (contact.NAME.face_cut in the results)"),
            stacklevel=3)

    def nodal_forces(self, g, lam):
        """Lab contact forces (k, 3) on the contact nodes (friction included) and their points of
        action x (k, 3)."""
        F, x, _ = self.node_forces(g, lam)
        return F, x

    def total(self, g, lam):
        """Total lab contact force [force] and its moment about the origin [force x length]
        (nodes and face samples)."""
        F, x = self.nodal_forces(g, lam)
        if len(self.face_el):
            Ff, xf = self.face_forces(g, lam)
            F, x = np.concatenate([F, Ff]), np.concatenate([x, xf])
        return F.sum(0), np.cross(x, F).sum(0)

    def report(self, g, lam):
        """Per-step scalars: penetration [length], gap error of the last update [length], the
        number of nodes carrying force, the faces' deepest cut (``face_cut`` [length]; warned
        beyond the penetration by h/2)."""
        _, d, _, _, p, _ = self.state(g, lam)
        out = dict(penetration=self.penetration(g, lam), gap_error=self.gap_error,
                   nodes_in_contact=int(np.count_nonzero(p > 0)), face_cut=self.face_cut(g, lam))
        self.warn_face_cut(out["face_cut"], out["penetration"], lam)
        if len(self.face_el):
            out["faces_in_contact"] = int(np.count_nonzero(self.face_state(g, lam)[1] > 0))
        if self.mu > 0:                                # friction: stick/slip counts, largest slip
            # the counts and the slip of the last accepted step (``accept_state``: the anchors
            # have moved to this state since)
            x, _, n, H, p, dp = self.state(g, lam)
            t, _, stick, slip = self.friction_state(g, lam, x, n, H, p, dp)
            on = p > 0
            Ft = (self.A[:, None] * t).sum(0)
            rec = getattr(self, "step_stats", None) or dict(
                sticking=int(np.count_nonzero(on & stick)), slipping=int(np.count_nonzero(on & ~stick)),
                largest_slip=float(np.linalg.norm(slip[on & ~stick], axis=1).max(initial=0.0)))
            # the normal force of the face samples too (frictionless: their whole force)
            Fn = ((self.A * p)[:, None] * n).sum(0) + (self.face_forces(g, lam)[0].sum(0) if len(self.face_el) else 0.0)
            out.update(sticking=rec["sticking"], slipping=rec["slipping"], largest_slip=rec["largest_slip"],
                       tangential_force=float(np.linalg.norm(Ft)), normal_force=float(np.linalg.norm(Fn)))
        return out

    def output_fields(self, g, lam):
        """VTU point fields: ``contact_force`` (lab) and ``contact_pressure`` (summed over the
        obstacles), ``contact_gap_NAME`` [length] (NaN off the contact nodes)."""
        x, d, n, H, p, dp = self.state(g, lam)
        gap = np.full(self.n, np.nan)
        gap[self.nodes] = d
        F = np.zeros((self.n, 3))
        F[self.nodes] = self.node_forces(g, lam)[0]
        P = np.zeros(self.n)
        P[self.nodes] = p
        if len(self.face_el):                          # face samples shared out by N_a(xi*)
            s, pf, _ = self.face_state(g, lam)
            nq = self.nodes[self.face_q]
            np.add.at(F, nq.ravel(), (s["N"][:, :, None] * ((self.Af * pf)[:, None] * s["n"])[:, None, :]).reshape(-1, 3))
            np.add.at(P, nq.ravel(), (s["N"] * (self.Af * pf)[:, None] / self.A[self.face_q]).ravel())
        key = field_key(self.name)
        out = {f"contact_gap_{key}": gap, "contact_force": F, "contact_pressure": P}
        if self.mu > 0:                     # the friction traction (lab) and 1 stick / 0 slip
            t, _, stick, _ = self.friction_state(g, lam, x, n, H, p, dp)
            T, st = np.zeros((self.n, 3)), np.full(self.n, np.nan)
            T[self.nodes] = t
            rec = getattr(self, "step_stats", None)
            st[self.nodes] = rec["stick"] if rec else np.where(p > 0, stick.astype(float), np.nan)
            out.update({f"friction_traction_{key}": T, f"contact_stick_{key}": st})
        return out

    def check_initial(self, mesh, g, lam=0.0):
        """ContactError when the obstacle intersects the contact surface at (g, lam) by more than
        tol: at the nodes, at 3 x 3 points of every element (the bilinear surface through the
        contact points) and, on a curved obstacle, at each face's deepest point
        (``contact_faces.face_minima``), so that an obstacle between nodes is found too (a ball of
        radius 0.05 through a 1 x 1 element at (0.25, 0.25) was between the 3 x 3 points:
        accepted, it held the plate at no force from there on)."""
        where = np.full(self.n, -1)
        where[self.nodes] = np.arange(len(self.nodes))
        el = np.nonzero((where[mesh.quads] >= 0).all(1))[0]
        x = np.zeros((self.n, 3))
        x[self.nodes] = self.contact_points(g)
        t = np.array([-1.0, 0.0, 1.0])
        xi, et = (a.ravel() for a in np.meshgrid(t, t))
        N = 0.25 * np.stack([(1 - xi) * (1 - et), (1 + xi) * (1 - et), (1 + xi) * (1 + et), (1 - xi) * (1 + et)], 1)
        pts = np.einsum("qa,mai->mqi", N, x[mesh.quads[el]]).reshape(-1, 3)
        d = self.obstacle.distance(np.concatenate([x[self.nodes], pts]), lam)
        if not getattr(self.obstacle, "flat", False) and len(el):
            # and each face's deepest point: a ball smaller than the grid's spacing through a face
            d = np.concatenate([d, face_minima(self.obstacle, x[mesh.quads[el]], lam)["d"]])
        i = int(np.argmin(d))
        if d[i] < -self.tol:
            k = i - len(self.nodes)
            at = (f"node {int(self.nodes[i])}" if k < 0 else
                  f"element {int(el[k // 9] if k < 9 * len(el) else el[k - 9 * len(el)])}")
            raise contact_error(
                f"obstacle {self.name!r} already intersects the undeformed shell: its contact surface at {at} "
                f"lies {-d[i]:.4g} inside it (tolerance {self.tol:.3g}); move or shrink the obstacle, or start "
                "its motion off the shell")
