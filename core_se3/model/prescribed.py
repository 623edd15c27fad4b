"""Prescribed supports: nodes whose body-frame dofs are held at their reference values or moved
with the load factor (:class:`Prescribed`, made by ``Problem.clamp``, ``fix``, ``rotate_edge``,
``move_edge`` and ``prescribe``), the node selections they and the loads take, and the checks that
two supports do not contradict each other.

A prescribed motion sets the frames of its nodes before each Newton try
(:func:`apply_prescribed`); the held dofs leave the system (``Problem.constraint_mask``).
"""
from __future__ import annotations

import numpy as np

from .. import lie
from ..errors import SupportError, warn_angle

__all__ = ["Prescribed", "checked_target", "apply_prescribed", "prescribed_rotation", "fixed_dofs", "rigid_rotation", "rigid_motion",
           "select_nodes", "check_conflict", "support_kind", "DOF_NAMES", "held_dof_drift",
           "DRIFT_TOL"]

DOF_NAMES = ("translation along d1", "translation along d2", "translation along d3", "rotation about d1",
             "rotation about d2", "rotation about d3")


class Prescribed:
    """Nodes whose body-frame dofs ``fixed`` (6 booleans) are held: at their reference values,
    or on ``target(lam) -> (k, 4, 4)`` frames (a prescribed motion).

    Made by ``Problem.clamp``, ``fix``, ``rotate_edge`` and ``prescribe``; the held dofs leave the
    system (``Problem.constraint_mask``), the solvers set the frames of a target before each try.

    Parameters
    ----------
    nodes : array_like of int
        The held nodes (k,).
    fixed : (6,) array_like of bool
        The held body-frame dofs: translations along d1, d2, d3, then rotations.
    target : callable, optional
        lam -> (k, 4, 4) frames of the nodes (None: the reference frames).
    linear : callable, optional
        lam -> (k, 6) body-frame increments (v, w) of the target linearised about the reference
        (a rigid motion's: ``rigid_motion``), which linear analysis prescribes; None: linear
        analysis takes the target's own (v, w) = (R0^T (x_t - X), log(R0^T R_t)).

    Attributes
    ----------
    name : str or None
        The key of its reaction in ``StepResult.support_reactions`` (None: ``supports[i]``, its
        index in ``Problem.supports``; scenario files set the entry's ``supports[i]``).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.fix("x0", [0, 1, 2])                                  # a hinge: translations held
    >>> s = p.supports[0]
    >>> s.nodes.tolist(), s.fixed.tolist(), s.target is None
    ([0, 3], [True, True, True, False, False, False], True)
    """

    def __init__(self, nodes, fixed, target=None, linear=None):
        self.nodes = np.asarray(nodes, np.int64)
        self.fixed = np.asarray(fixed, bool)
        self.target = None if target is None else checked_target(target, len(self.nodes))
        self.linear = linear
        self.name = None


def checked_target(target, k):
    """``target`` (lam -> frames) returning its (k, 4, 4) frames checked: the shape, finite, a
    rotation part orthonormal with determinant +1 (to 1e-9) and the last row (0, 0, 0, 1); a
    SupportError naming the load factor otherwise.  Unchecked, a target of shape (4, 4) failed as
    a bare IndexError, one for another number of nodes as a NumPy broadcast error, and NaN or a
    non-rotation (a stretched frame) as 12 cut-backs of 'non-finite residual' or 'edge turns'.

    Example
    -------
    >>> import numpy as np
    >>> checked_target(lambda lam: np.eye(4), 2)(0.5)
    Traceback (most recent call last):
    ...
    core_se3.errors.SupportError: a prescribed target must return (2, 4, 4) frames (one per node), got shape (4, 4) at load factor 0.5
    """
    def frames(lam):
        G = np.asarray(target(lam), float)
        if G.shape != (k, 4, 4):
            raise SupportError(f"a prescribed target must return ({k}, 4, 4) frames (one per node), got shape "
                               f"{G.shape} at load factor {lam:g}")
        R = G[:, :3, :3]
        bad = (~np.isfinite(G).all((1, 2)) | (np.abs(np.swapaxes(R, 1, 2) @ R - np.eye(3)).max((1, 2)) > 1e-9)
               | (np.linalg.det(np.where(np.isfinite(R), R, 0.0)) < 0) | (np.abs(G[:, 3] - [0.0, 0.0, 0.0, 1.0]).max(1) > 1e-12))
        if np.any(bad):
            i = int(np.argmax(bad))
            raise SupportError(f"a prescribed target at load factor {lam:g} is not a frame (a finite rigid motion: "
                               f"rotation R with R^T R = I, det R = 1, last row 0 0 0 1) at its node {i}: "
                               f"{np.round(G[i], 6).tolist()}")
        return G
    frames.unchecked = target
    return frames


def support_kind(s):
    """'a clamp', 'a fix' or 'a prescribed motion': what a :class:`Prescribed` does, for messages.

    Example
    -------
    >>> support_kind(Prescribed([0], [True] * 6)), support_kind(Prescribed([0], [True] * 6, lambda lam: None))
    ('a clamp', 'a prescribed motion')
    """
    if s.target is not None:
        return "a prescribed motion"
    return "a clamp" if s.fixed.all() else "a fix"


def check_conflict(supports, new):
    """SupportError if the support ``new`` holds a dof that an earlier one of ``supports`` holds
    too while either of them moves it (a prescribed motion): the frames of a node are set by one
    target only (:func:`apply_prescribed`), so the later support would silently win.  Two
    supports that both hold a dof at its reference value agree and pass.  The error's ``other``
    is the index of the earlier support.

    Example
    -------
    >>> clamp = Prescribed([0, 3], [True] * 6)
    >>> turn = Prescribed([3, 4], [True] * 6, target=lambda lam: None)
    >>> check_conflict([clamp], turn)                     # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.SupportError: support 1 (a prescribed motion) and support 0 (a clamp) both hold node 3 ...
    """
    for j, s in enumerate(supports):
        if s.target is None and new.target is None:
            continue
        both = np.intersect1d(s.nodes, new.nodes)
        dofs = np.nonzero(s.fixed & new.fixed)[0]
        if len(both) and len(dofs):
            nodes = f"node {int(both[0])}" if len(both) == 1 else f"nodes {both[:6].tolist()}" + \
                ("..." if len(both) > 6 else "")
            what = ", ".join(DOF_NAMES[d] for d in dofs) if len(dofs) < 6 else "every dof"
            err = SupportError(
                f"support {len(supports)} ({support_kind(new)}) and support {j} ({support_kind(s)}) both hold "
                f"{nodes} ({what}) and one of the two moves them: only one support can set a node's frame "
                "(the later one would silently win); remove one of them or select other nodes")
            err.other = j
            raise err


def select_nodes(mesh, where):
    """Node ids of a selection: a node-set or region name, a predicate of the reference positions
    ``pred(X) -> mask``, or ids (each listed once: a repeated id would apply a nodal load once per
    repeat).  SupportError for an empty selection, ids that do not exist or a repeated id.

    Example
    -------
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(1.0, 1.0, 2, 1)
    >>> select_nodes(m, "x1").tolist(), select_nodes(m, [4]).tolist()
    ([2, 5], [4])
    >>> select_nodes(m, [4, 4, 4])
    Traceback (most recent call last):
    ...
    core_se3.errors.SupportError: node selection [4, 4, 4] lists node 4 3 times: list every node once (a nodal load would be applied 3 times)
    """
    if isinstance(where, str) or callable(where):
        nodes = mesh.node_set(where)
    else:
        nodes = _node_ids(mesh, where)
    if len(nodes) == 0:
        raise SupportError(f"node selection {where!r} is empty")
    if nodes.min() < 0 or nodes.max() >= mesh.n_nodes:
        raise SupportError(f"node selection {where!r} refers to nodes that do not exist")
    ids, counts = np.unique(nodes, return_counts=True)
    if not isinstance(where, str) and counts.max() > 1:
        k = int(np.argmax(counts))
        raise SupportError(f"node selection {np.asarray(where).tolist() if not callable(where) else where!r} lists "
                           f"node {int(ids[k])} {int(counts[k])} times: list every node once (a nodal load would be "
                           f"applied {int(counts[k])} times)")
    return nodes


def _node_ids(mesh, where):
    """Ids of a list of node ids or of a boolean mask over the nodes; a SupportError for ids that
    are not whole numbers (2.7 was read as node 2) or a mask of the wrong length (a mask was read
    as the ids 0 and 1)."""
    raw = np.atleast_1d(np.asarray(where))
    if raw.dtype == bool:
        if raw.shape != (mesh.n_nodes,):
            raise SupportError(f"a boolean node selection needs one entry per node ({mesh.n_nodes}), got shape "
                               f"{raw.shape}")
        return np.nonzero(raw)[0]
    try:
        nodes = raw.astype(np.int64).ravel()
        whole = raw.ndim == 1 and np.array_equal(nodes, raw)
    except (TypeError, ValueError):
        whole = False
    if not whole:
        raise SupportError(f"node ids must be whole numbers in a flat list, got {raw.ravel()[:5].tolist()}"
                           f"{' ...' if raw.size > 5 else ''} (a point by its coordinates: Problem.node_at)")
    return nodes


def fixed_dofs(dofs):
    """The (6,) mask of the body-frame dofs ``dofs`` (0-2 translations along d1..d3, 3-5
    rotations about them), or a SupportError (a negative index would silently fix another dof; a
    dof listed twice, [0, 0], fixed one where two were likely meant).

    Example
    -------
    >>> fixed_dofs([0, 5]).astype(int).tolist()
    [1, 0, 0, 0, 0, 1]
    """
    dofs = list(dofs)
    if not dofs or any(isinstance(d, bool) or not isinstance(d, (int, np.integer)) or not 0 <= d <= 5 for d in dofs):
        raise SupportError(f"dofs must be one or more of 0, 1, 2 (translations along d1, d2, d3) and 3, 4, 5 "
                           f"(rotations about them), got {dofs!r}")
    repeated = sorted({int(d) for d in dofs if dofs.count(d) > 1})
    if repeated:      # [0, 0] fixed one dof where [0, 1] was likely meant: said, not merged silently
        raise SupportError(f"dofs lists {repeated} more than once ({dofs!r}): each dof once -- 0, 1, 2 "
                           f"(translations along d1, d2, d3), 3, 4, 5 (rotations about them); was another meant?")
    fixed = np.zeros(6, bool)
    fixed[dofs] = True
    return fixed


def rigid_rotation(axis, angle, point):
    """(unit axis (3,), angle [rad], point (3,)) of a prescribed rigid rotation, checked finite
    (the axis non-zero), or a SupportError.

    Example
    -------
    >>> a, t, x = rigid_rotation((0, 0, 2.0), 1.5, (1.0, 0, 0))
    >>> a.tolist(), t, x.tolist()
    ([0.0, 0.0, 1.0], 1.5, [1.0, 0.0, 0.0])
    """
    axis = np.asarray(axis, float)
    if axis.shape != (3,) or not np.all(np.isfinite(axis)) or np.linalg.norm(axis) == 0:
        raise SupportError(f"rotation axis must be a non-zero finite 3-vector, got {axis!r}")
    try:
        ok = not isinstance(angle, bool) and np.isfinite(float(angle))
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise SupportError(f"rotation angle must be a finite number [rad], got {angle!r}")
    point = np.asarray(point, float)
    if point.shape != (3,) or not np.all(np.isfinite(point)):
        raise SupportError(f"rotation point must be a finite 3-vector, got {point!r}")
    return axis / np.linalg.norm(axis), float(angle), point


def _free_dofs(g0, axis, free):
    """The (6,) held-dof mask of nodes (frames g0) moved rigidly with the lab directions ``free``
    (0 = x, 1 = y, 2 = z) left free: each must be a body axis of every node and, with a rotation,
    parallel to its axis.  (The free dof is a body axis, which turns with the nodes: a direction
    perpendicular to the axis was accepted, and an end turned by 0.8 rad about y with x free slid
    along its turned d1, 0.42 in the held z.)"""
    fixed = np.ones(6, bool)
    for d in free:
        lab = np.zeros(3)
        lab[d] = 1.0
        body = np.swapaxes(g0[:, :3, :3], 1, 2) @ lab
        k = np.argmax(np.abs(body), axis=1)
        if not np.all(k == k[0]) or np.abs(body[np.arange(len(k)), k]).min() < 1 - 1e-12:
            raise SupportError(f"the free direction {'xyz'[d]} must coincide with a body axis (d1, d2 or d3) of "
                               "every moved node")
        if axis is not None and abs(abs(axis @ lab) - 1) > 1e-12:
            raise SupportError(f"the free direction {'xyz'[d]} must be parallel to the rotation axis "
                               f"{np.round(axis, 6).tolist()}: the free dof is a body axis, which turns with the "
                               f"nodes, so the nodes would slide along the turned axis, not along {'xyz'[d]}")
        fixed[k[0]] = False
    return fixed


def rigid_motion(mesh, nodes, translate=(0.0, 0.0, 0.0), axis=None, angle=0.0, point=None, free=(), scale=None):
    """The :class:`Prescribed` support of nodes moved rigidly with the load factor: at lam, with
    s = scale(lam) (default lam), x -> p + Q(s angle, axis) (x - p) + s translate (Q the rotation
    about ``axis`` through the point p, default the nodes' centroid) and frames turned by Q.

    Parameters: mesh; nodes (k,) ids; translate (3,) [length at s = 1]; axis (3,) or None (no
    rotation), angle [rad at s = 1], point (3,); free: lab directions (0, 1, 2) the nodes may still
    translate along (each a body axis of every node); scale: lam -> s.

    Example
    -------
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(1.0, 1.0, 2, 1)
    >>> s = rigid_motion(m, [2, 5], translate=(0.0, 0.0, 0.5))
    >>> s.target(0.5)[:, :3, 3].tolist()                         # lifted by 0.25 at lam = 0.5
    [[1.0, -0.5, 0.25], [1.0, 0.5, 0.25]]

    Its ``linear(lam)`` is the motion linearised about the reference, the body-frame increments
    (R0^T (s t + s angle axis x (X - p)), R0^T s angle axis): a quarter turn about z through the
    origin moves (1, 0.5) by (-0.5, 1) pi/2 in linear analysis (its chord would be (-1.5, 0.5)).

    >>> import numpy as np
    >>> q = rigid_motion(m, [5], axis=(0, 0, 1), angle=np.pi / 2, point=(0, 0, 0))
    >>> (q.linear(1.0)[0] / (np.pi / 2)).round(12).tolist()
    [-0.5, 1.0, 0.0, 0.0, 0.0, 1.0]
    """
    nodes = np.asarray(nodes, np.int64)
    g0 = mesh.g0[nodes]
    t = np.asarray(translate, float)
    if t.shape != (3,) or not np.all(np.isfinite(t)):
        raise SupportError(f"a translation must be a finite 3-vector, got {np.asarray(translate).tolist()}")
    point = g0[:, :3, 3].mean(0) if point is None else point
    axis, angle, point = rigid_rotation(axis, angle, point) if axis is not None else (None, 0.0, np.zeros(3))
    warn_angle(angle, "a prescribed rotation's angle (rotate_edge, move_edge)")
    fixed = _free_dofs(g0, axis if angle != 0 else None, free)
    if scale is not None and not callable(scale):
        raise SupportError(f"a rigid motion's scale must be a function of the load factor (lam -> s; default s = "
                           f"lam), got {scale!r}")
    scale = scale or (lambda lam: lam)

    def target(lam):
        s = scale(lam)
        h = np.eye(4)
        if axis is not None:
            h[:3, :3] = lie.exp_so3(angle * s * axis)
            h[:3, 3] = point - h[:3, :3] @ point
        h[:3, 3] += s * t
        return h @ g0

    def linear(lam):
        # the velocity field of the motion at s = 0 times s: the infinitesimal rigid motion
        # u = s t + omega x (X - p), omega = s angle axis, whose linear strains vanish; the
        # target's chord (Q - I)(X - p) is not linear in the angle and, with rotation omega,
        # strains the element by O(angle^2) (a rotated cantilever end pulled in by 4.5 % of L at 0.3 rad)
        s = scale(lam)
        omega = s * angle * axis if axis is not None else np.zeros(3)
        u = s * t + np.cross(omega, g0[:, :3, 3] - point)
        RT = np.swapaxes(g0[:, :3, :3], 1, 2)
        return np.concatenate([RT @ u[:, :, None], RT @ np.broadcast_to(omega, u.shape)[:, :, None]], 1)[:, :, 0]
    return Prescribed(nodes, fixed, target, linear)


def apply_prescribed(supports, g, lam):
    """Set the frames of the prescribed nodes of ``supports`` to their targets at lam (in
    place); returns g.  A target that holds the three translations only (rotations free) sets
    the positions and keeps the nodes' current rotations."""
    for s in supports:
        if s.target is not None:
            if s.fixed[:3].all() and not s.fixed[3:].any():
                g[s.nodes, :3, 3] = s.target(lam)[:, :3, 3]
            else:
                g[s.nodes] = s.target(lam)
    return g


def prescribed_rotation(supports, lam0, lam1, samples=16):
    """Largest rotation angle [rad] that the prescribed motions of ``supports`` turn any node
    through between load factors lam0 and lam1 (the path length of its rotation, sampled at
    ``samples`` sub-steps): a step whose prescribed rotation nears pi is ambiguous for the
    exponential update (a turn of 2 pi lands on the same frame).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.clamp("x0"); p.rotate_edge("x1", (1.0, 0.0, 0.0), np.pi)
    >>> round(prescribed_rotation(p.supports, 0.0, 0.5), 12)               # half of pi
    1.570796326795
    """
    worst = 0.0
    for s in supports:
        if s.target is None:
            continue
        prev = s.target(lam0)
        total = np.zeros(len(s.nodes))
        for t in np.linspace(lam0, lam1, samples + 1)[1:]:
            cur = s.target(t)
            total += lie.rotation_angle(np.swapaxes(prev[:, :3, :3], 1, 2) @ cur[:, :3, :3])
            prev = cur
        worst = max(worst, float(total.max()))
    return worst


DRIFT_TOL = 1e-8        # a held dof that drifted further is reported (SupportWarning): [rad], [of max |u|]


def held_dof_drift(supports, g0, g):
    """The largest drift of a dof that a support holds incrementally but not exactly, and where:
    ``(drift, support index, node, dof)``, or None when every support holds exactly.

    ``Problem.fix`` holds the body-frame components of each Newton increment g <- g exp(eta).
    That holds the component exactly when the node can only turn about the held axis (all three
    rotations held, or the other two): then d_k keeps its reference direction; and a pin (the
    three translations held) keeps its position whatever it turns.  Otherwise the
    held components drift, at second order in the rotations (errors.SupportWarning):

    * a held rotation k (exactly one of three held): the component psi_k of the total rotation
      vector psi = log(R0^T R) [rad] (increments about the two free axes do not commute);
    * a held translation k: the displacement along the reference axis, (x - x0) . R0 e_k, over
      the largest nodal displacement of the state (the increments follow the turning d_k).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import lie
    >>> s = Prescribed([0], [False] * 4 + [True, False])        # rotation about d2 held
    >>> g0 = np.eye(4)[None]
    >>> g = g0 @ lie.exp(np.array([[0, 0, 0, 0.1, 0, 0]])) @ lie.exp(np.array([[0, 0, 0, 0, 0, 0.1]]))
    >>> d, k, node, dof = held_dof_drift([s], g0, g)            # about d1 then d3: psi_2 = -0.005
    >>> round(d, 6), k, node, dof
    (0.005, 0, 0, 4)
    """
    u_max = max(float(np.abs(g[:, :3, 3] - g0[:, :3, 3]).max()), 1e-300)
    worst = None
    for k, s in enumerate(supports):
        rot_held = np.flatnonzero(s.fixed[3:])
        if s.target is not None or len(rot_held) == 3:
            continue
        R0 = g0[s.nodes, :3, :3]
        psi = lie.log_so3(np.swapaxes(R0, 1, 2) @ g[s.nodes, :3, :3])
        u = np.einsum("nji,nj->ni", R0, g[s.nodes, :3, 3] - g0[s.nodes, :3, 3])   # R0^T (x - x0)
        for dof in np.flatnonzero(s.fixed):
            axis = dof % 3
            if dof < 3 and (s.fixed[:3].all() or len(rot_held) == 2 and axis not in rot_held):
                continue                            # a pin, or turns about d_axis only: exact
            if dof >= 3 and len(rot_held) != 1:
                continue
            drift = np.abs(psi[:, axis]) if dof >= 3 else np.abs(u[:, axis]) / u_max
            i = int(np.argmax(drift))
            if worst is None or drift[i] > worst[0]:
                worst = (float(drift[i]), k, int(s.nodes[i]), int(dof))
    return worst
