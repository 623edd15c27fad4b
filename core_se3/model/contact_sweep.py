"""Continuous collision detection of the shell's contact surface against a moving rigid obstacle
over one load step (``ContactLoad.step_error``, docs/CONTACT.md "No tunnelling").

Two accepted states (g0, lam0) and (g1, lam1) say nothing of the path between them; a step that
carries a node, or the face between nodes, through an obstacle can converge on the far side, a
converged-looking wrong answer.  The check takes the motion between the states to be linear in the
lab for every point of the contact surface (x(t) = (1 - t) x0 + t x1: the bilinear faces move
bilinearly) and the obstacle's own rigid motion T(lam) with lam(t) = lam0 + t (lam1 - lam0), and
asks whether any point passes deeper than ``depth`` into the obstacle for some t in [0, 1].

In the obstacle's placement coordinates y(t) = T(lam(t))^-1 x(t) the SDF d0 is 1-Lipschitz, so on
a chord y(t) = ya + s (yb - ya) of speed v = |yb - ya| a sample d0(y(s)) = d >= -depth leaves
d0 >= -depth over the next (d + depth) / v of the chord (conservative advancement): the samples
cannot step over an inside stretch deeper than ``depth``.  The obstacle's motion is followed by
chords between sub-samples of lam (one per 0.05 rad of its rotation over the step), so that a
point resting on a rotating roller follows its arc instead of cutting the chord.

Which points: the contact nodes, and on every element whose nodes pass within the element's
diameter of the obstacle (a lower bound from the nodes' chords), a grid of face points with a
spacing of half the obstacle's thickness (``Obstacle.thickness``, its inradius: a ball's radius,
a box's smallest half size): a ball smaller than an element that passes through the face between
its nodes passes within that spacing of a grid point, deeper than ``depth`` = min(h/2,
thickness/2).  On a plane d is trilinear in the face coordinates and t, so the nodes suffice.

Example
-------
>>> import numpy as np
>>> from core_se3.model import make_obstacle
>>> ball = make_obstacle("sphere", centre=(0.0, 0.0, -2.0), radius=1.0, motion=lambda lam: np.array(
...     [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4.0 * lam], [0, 0, 0, 1.0]]))
>>> x = np.array([[0.0, 0.0, 0.0]])
>>> bool(ball.distance(x, 0.0)[0] > 0 and ball.distance(x, 1.0)[0] > 0)      # outside at both ends
True
>>> bool(swept_depth(ball, x, x, 0.0, 1.0, depth=0.05)[0][0] < -0.05)         # but the ball passed through
True
"""
from __future__ import annotations

import numpy as np

from .. import lie

__all__ = ["swept_depth", "face_grid", "crossing_report"]

MAX_SAMPLES = 20000          # conservative-advancement samples per chord before giving up


def _motion_samples(obstacle, lam0, lam1):
    """Load factors at which the obstacle's transform is sampled over the step: one chord per
    0.05 rad of its rotation (at least one chord)."""
    if obstacle.motion is None or lam1 == lam0:
        return np.array([lam0, lam1])
    T0, T1 = obstacle.transform(lam0), obstacle.transform(lam1)
    angle = float(np.linalg.norm(lie.log_so3(T1[:3, :3] @ T0[:3, :3].T)))
    m = 1 + int(np.ceil(angle / 0.05))
    mid = obstacle.transform(0.5 * (lam0 + lam1))
    if np.abs(mid[:3, :3] - T0[:3, :3]).max() > 0 and m == 1:
        m = 8                        # a rotation that returns over the step: follow it anyway
    return np.linspace(lam0, lam1, m + 1)


def _placement(obstacle, x, lam):
    """y = Q^T (x - t) of lab points x (k, 3) at lam."""
    T = obstacle.transform(lam)
    return (x - T[:3, 3]) @ T[:3, :3]


def swept_depth(obstacle, x0, x1, lam0, lam1, depth, relative=False):
    """The smallest SDF value found along each point's path (k,), and a lower bound of it:
    points x0 (k, 3) at lam0 moving linearly to x1 at lam1 in the lab (``relative``: linearly
    in the obstacle's placement coordinates, i.e. carried along by it), the obstacle moving
    rigidly; ``depth`` (scalar or (k,)).
    Sampling stops at a point once it is found deeper than ``depth`` (its value is then that
    sample, < -depth); otherwise the true minimum is >= min(found, -depth) (module docstring).

    Returns
    -------
    found : (k,) ndarray
        The smallest sampled d [length].
    lower : (k,) ndarray
        A lower bound of d along the path (the Lipschitz bound between samples) [length].
    """
    x0, x1 = np.atleast_2d(np.asarray(x0, float)), np.atleast_2d(np.asarray(x1, float))
    lams = np.array([lam0, lam1]) if relative else _motion_samples(obstacle, lam0, lam1)
    k = len(x0)
    depth = np.broadcast_to(np.asarray(depth, float), (k,))
    found, lower = np.full(k, np.inf), np.full(k, np.inf)
    ts = (lams - lam0) / (lam1 - lam0) if lam1 != lam0 else np.linspace(0.0, 1.0, len(lams))
    ya = _placement(obstacle, x0, lams[0])
    y_end = _placement(obstacle, x1, lam1)
    da = obstacle.local_distance(ya)
    found = np.minimum(found, da)
    lower = np.minimum(lower, da)
    for j in range(1, len(lams)):
        yb = y_end if relative else _placement(obstacle, x0 + ts[j] * (x1 - x0), lams[j])
        v = np.linalg.norm(yb - ya, axis=1)
        s = np.zeros(k)
        d = da.copy()
        live = (v > 0) & (found >= -depth)
        for _ in range(MAX_SAMPLES):
            if not live.any():
                break
            ds = np.maximum(d[live] + depth[live], 0.5 * depth[live]) / v[live]
            s_new = np.minimum(s[live] + ds, 1.0)
            idx = np.nonzero(live)[0]
            y = ya[idx] + s_new[:, None] * (yb[idx] - ya[idx])
            dn = obstacle.local_distance(y)
            # between two samples d >= (d_a + d_b - v ds) / 2 (a 1-Lipschitz function on the chord)
            lower[idx] = np.minimum(lower[idx], 0.5 * (d[idx] + dn - v[idx] * (s_new - s[idx])))
            found[idx] = np.minimum(found[idx], dn)
            s[idx], d[idx] = s_new, dn
            live[idx] = (s_new < 1.0) & (dn >= -depth[idx])
        else:
            found[live] = -np.inf                 # too long a path to check: refuse the step
        ya, da = yb, obstacle.local_distance(yb)
    return found, lower


def face_grid(spacing, size):
    """Bilinear weights (q, 4) of a grid of face points with at most ``spacing`` between them on
    an element of diameter ``size`` (the corners excluded: they are the nodes).

    Example
    -------
    >>> face_grid(0.5, 1.0).shape, face_grid(2.0, 1.0).shape
    ((5, 4), (0, 4))
    """
    m = int(min(64, np.ceil(size / max(spacing, 1e-300))))
    if m <= 1:
        return np.zeros((0, 4))
    t = np.linspace(-1.0, 1.0, m + 1)
    xi, et = (a.ravel() for a in np.meshgrid(t, t))
    corner = (np.abs(xi) == 1) & (np.abs(et) == 1)
    xi, et = xi[~corner], et[~corner]
    return 0.25 * np.stack([(1 - xi) * (1 - et), (1 + xi) * (1 - et), (1 + xi) * (1 + et), (1 - xi) * (1 + et)], 1)


def crossing_report(obstacle, quads, x0, x1, lam0, lam1, depth, ids):
    """Where the contact surface passes deeper than ``depth`` into the obstacle over the step:
    '' when nowhere, else a sentence naming the node or element and the depth.

    quads (m, 4): the contact elements in positions of x0/x1 (rows: contact points of the nodes
    ``ids``, lab, at the two states); ``ids`` may be a pair (the nodes' ids, the (m,) elements'
    ids) that the messages name (the elements' default: their positions in quads).
    """
    node_ids, element_ids = ids if isinstance(ids, tuple) else (ids, None)
    dn = _crossing(obstacle, x0, x1, lam0, lam1, depth)
    found, lower = dn[0], dn[1]
    i = int(np.argmin(found - dn[2]))
    if found[i] < dn[2][i]:
        what = "too long a path to check" if np.isinf(found[i]) else f"{-found[i]:.3g} deep"
        return (f"node {int(node_ids[i])} passes through obstacle {obstacle.name!r} between load factors "
                f"{lam0:.6g} and {lam1:.6g} ({what}, more than {depth:.3g} below its end states)")
    thick = float(getattr(obstacle, "thickness", np.inf))
    if not np.isfinite(thick) or not len(quads):
        return ""
    # a face point lies within the element's diameter of each node at every t (the diameter of a
    # bilinear face moving linearly is largest at an end state), so d >= lower(node) - diameter
    pairs = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [0, 2], [1, 3]])
    size = np.max([np.linalg.norm(x[quads[:, pairs[:, 0]]] - x[quads[:, pairs[:, 1]]], axis=2).max(1)
                   for x in (x0, x1)], axis=0)
    near = np.nonzero(lower[quads].min(1) < size)[0]
    for e in near:
        W = face_grid(0.5 * thick, size[e])
        if not len(W):
            continue
        f, _, thr = _crossing(obstacle, W @ x0[quads[e]], W @ x1[quads[e]], lam0, lam1, depth)
        if (f < thr).any():
            return (f"the face of element {int(e if element_ids is None else element_ids[e])} passes through obstacle {obstacle.name!r} between the "
                    f"nodes from load factor {lam0:.6g} to {lam1:.6g} ({-f.min():.3g} deep, more than "
                    f"{depth:.3g})")
    return ""


def _crossing(obstacle, x0, x1, lam0, lam1, depth):
    """(found, lower, threshold) of the points' paths: a point crossed when found < threshold =
    min(d at its two end states, 0) - depth (a face's chord that cuts a curved obstacle by the
    same amount at both states is the node sampling's, not a crossing) along the lab-linear path
    and along the path carried by the obstacle (relative-linear): a step is clear when one of
    the two is."""
    d_end = np.minimum(np.minimum(obstacle.distance(x0, lam0), obstacle.distance(x1, lam1)), 0.0)
    dep = depth - d_end
    found, lower = swept_depth(obstacle, x0, x1, lam0, lam1, dep)
    bad = found < -dep
    if bad.any():
        f2, l2 = swept_depth(obstacle, x0[bad], x1[bad], lam0, lam1, dep[bad], relative=True)
        found[bad], lower[bad] = np.maximum(found[bad], f2), np.maximum(lower[bad], l2)
    return found, lower, -dep
