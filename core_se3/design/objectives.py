"""Quantities of a state whose sensitivities a design needs: nodal and probe positions, frame
orientations (the log of the rotation relative to a target), the rotation angle about an axis,
the elastic energy and any user function of (g, lam) with its gradient.

A quantity q (size,) gives ``value(problem, g, lam)`` and its left-trivialised derivative
``jacobian(problem, g, lam)`` -> scipy.sparse (size, 6 n): row k, column 6 i + j is
d/d eps q_k(g with g_i <- g_i exp(eps e_j)) -- the derivative along the same update as the
solver's, so that it pairs with the tangent K = dr/d eta.  With ``target`` the value is the
misfit q - target (a position or angle target) and the design minimises its square.

Exact derivatives where they are one line (nodal positions: R_i on the translations; nodal
orientations: J_r^-1(log(R_t^T R_i)) on the rotations; energy: the internal forces r_int);
probes between two nodes (a point on their SE(3) geodesic) by central differences in eta of
the few local dofs, Richardson-extrapolated (truncation O(d^4) ~ 1e-16 at d = 1e-4: no
equilibrium is re-solved, the frames of two nodes are perturbed).

Example
-------
>>> import numpy as np
>>> from core_se3 import Problem, Material, mesh
>>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
>>> q = NodePosition(p, [2], target=[2.0, -0.5, 0.5])
>>> q.value(p, p.mesh.g0, 1.0).tolist(), q.jacobian(p, p.mesh.g0, 1.0).shape
([0.0, 0.0, -0.5], (3, 36))
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .. import lie
from ..errors import DesignError, did_you_mean
from ..model import Probe
from ..solvers.origin import frames_origin

__all__ = ["Quantity", "NodePosition", "ProbePosition", "Orientation", "RotationAngle", "AngleInDegrees", "Energy",
           "UserQuantity", "local_jacobian", "probe_frames", "target_array", "twist_angle"]


def local_jacobian(fn, g, nodes, ell, step=1e-4, local=None, origin=None):
    """Left-trivialised derivative of fn(g) -> (k,) over the dofs of ``nodes`` by central
    differences in eta (translations step * ell, rotations step), Richardson-extrapolated.
    ``local``: the same function of the frames of ``nodes`` alone, batched,
    (M, len(nodes), 4, 4) -> (M, k): all 24 len(nodes) perturbed evaluations in one call (no
    copy of g per perturbation).  ``origin`` (3,): ``local`` is given the frames with their
    positions relative to it (an exact subtraction for a far part's ``solvers.origin.frames_origin``;
    ``local`` a function whose differences a common translation does not change: a position, an
    orientation), so that the differences are those of the part's size, not of its distance from
    the origin (a probe of a part at x0 = 1e9 was 8.4e-4 off).

    Returns: scipy.sparse (k, 6 n).

    Example
    -------
    >>> import numpy as np
    >>> g = np.broadcast_to(np.eye(4), (2, 4, 4)).copy()
    >>> J = local_jacobian(lambda g: g[1, :3, 3], g, [1], ell=1.0)
    >>> np.round(J.toarray()[:, 6:9], 12).tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    >>> J2 = local_jacobian(None, g, [1], ell=1.0, local=lambda F: F[:, 0, :3, 3])
    >>> bool(np.abs((J - J2).toarray()).max() < 1e-12)
    True
    """
    n = g.shape[0]
    nodes = list(nodes)
    h = step * np.where(np.arange(6) < 3, ell, 1.0)                    # per dof
    # perturbation m = ((node i, dof j) pair, d in (h, 2h), sign +-): eta = sign d e_j
    pairs = [(a, j) for a in range(len(nodes)) for j in range(6)]
    E = np.zeros((len(pairs), 2, 2, 6))
    for p, (a, j) in enumerate(pairs):
        E[p, 0, :, j] = h[j] * np.array([1.0, -1.0])
        E[p, 1, :, j] = 2 * h[j] * np.array([1.0, -1.0])
    if local is not None:
        gn = np.array(g[nodes], float)
        if origin is not None:
            gn[:, :3, 3] -= origin                                      # relative to the part (docstring)
        F = np.broadcast_to(gn, (len(pairs), 2, 2) + gn.shape).copy()
        X = lie.exp(E.reshape(-1, 6)).reshape(len(pairs), 2, 2, 4, 4)
        for a in range(len(nodes)):                                     # the pairs 6a .. 6a + 5
            F[6 * a:6 * a + 6, :, :, a] = gn[a] @ X[6 * a:6 * a + 6]
        vals = np.asarray(local(F.reshape((-1,) + F.shape[3:]))).reshape(len(pairs), 2, 2, -1)
    else:
        vals = []
        for p, (a, j) in enumerate(pairs):
            out = []
            for e in E[p].reshape(4, 6):
                gp = g.copy()
                gp[nodes[a]] = g[nodes[a]] @ lie.exp(e)
                out.append(np.asarray(fn(gp)))
            vals.append(out)
        vals = np.asarray(vals).reshape(len(pairs), 2, 2, -1)
    d = np.array([h[j] for _, j in pairs])[:, None]
    D1 = (vals[:, 0, 0] - vals[:, 0, 1]) / (2 * d)
    D2 = (vals[:, 1, 0] - vals[:, 1, 1]) / (4 * d)
    V = ((4 * D1 - D2) / 3).T                                            # (k, ncols)
    cols = [6 * nodes[a] + j for a, j in pairs]
    k = V.shape[0]
    return sp.csr_matrix((V.ravel(), (np.repeat(np.arange(k), len(cols)), np.tile(cols, k))), shape=(k, 6 * n))


def probe_frames(probe, ga, gb):
    """Frames (M, 4, 4) of a probe at stacks of its two nodes' frames ga, gb (M, 4, 4) (the
    batched ``Probe.state``: g_a exp((1 - wa) log(g_a^-1 g_b))).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> from core_se3.model import Probe
    >>> m = mesh.rectangle(2.0, 1.0, 2, 1)
    >>> pr = Probe.edge_midpoint("tip", m.node_set("x1"))
    >>> bool(np.allclose(probe_frames(pr, m.g0[[pr.node_a]], m.g0[[pr.node_b]])[0, :3, 3], pr.state(m.g0)[0]))
    True
    """
    if probe.node_a == probe.node_b or probe.wa == 1.0:
        return np.array(ga, float)
    ga, gb = probe.ends(ga, gb)
    return probe.unturn(ga @ lie.exp((1.0 - probe.wa) * lie.log(lie.relative(ga, gb))))


def _probe_local(probe, fn):
    """(nodes, local) of :func:`local_jacobian` for fn(probe frames (M, 4, 4)) -> (M, k)."""
    nodes = sorted({probe.node_a, probe.node_b})
    ia, ib = nodes.index(probe.node_a), nodes.index(probe.node_b)
    return nodes, lambda F: fn(probe_frames(probe, F[:, ia], F[:, ib]))


def _probe_jacobian(problem, probe, g, fn):
    """:func:`local_jacobian` of fn(probe frames) -> (M, k), translation invariant: fn's
    differences do not change with a common translation; the frames of a far part are taken
    relative to its origin (``solvers.origin.frames_origin``)."""
    nodes, local = _probe_local(probe, fn)
    return local_jacobian(None, g, nodes, problem.length_scale, local=local, origin=frames_origin(problem, g[nodes]))


def target_array(value, shape, what):
    """``value`` as a finite float array broadcast to ``shape``; DesignError naming ``what``
    otherwise (a wrong length or a NaN was a bare NumPy error, or a NaN objective, later).

    Example
    -------
    >>> target_array(0.5, (3,), "t").tolist()
    [0.5, 0.5, 0.5]
    """
    try:
        a = np.broadcast_to(np.asarray(value, float), shape).copy()
    except (TypeError, ValueError):
        raise DesignError(f"{what}: expected {' x '.join(map(str, shape)) or 'a'} number(s), got "
                          f"{np.shape(value) if not isinstance(value, str) else repr(value)}") from None
    if not np.all(np.isfinite(a)):
        raise DesignError(f"{what}: the values must be finite, got {a.ravel().tolist()[:6]}")
    return a


def _nodes(problem, nodes, what):
    n = problem.mesh.n_nodes
    if isinstance(nodes, str):
        try:
            return np.asarray(problem.mesh.node_set(nodes), np.int64)
        except Exception as exc:                     # MeshError with the closest name
            raise DesignError(f"{what}: {exc}") from None
    raw = np.atleast_1d(np.asarray(nodes))
    try:
        ids = raw.astype(np.int64)
    except (TypeError, ValueError):
        ids = None
    if ids is None or raw.dtype == bool or not np.array_equal(ids, raw):       # (1.5 was read as node 1)
        raise DesignError(f"{what}: node ids must be whole numbers, got {raw.ravel()[:5].tolist()}")
    bad = ids[(ids < 0) | (ids >= n)]
    if ids.size == 0 or bad.size:
        raise DesignError(f"node ids {bad[:5].tolist() if bad.size else []} do not exist (the mesh has {n} nodes: "
                          f"0 .. {n - 1})")
    return ids


def _probe(problem, probe, what):
    if isinstance(probe, Probe):
        return probe
    if probe not in problem.probes:
        raise DesignError(f"{what}: no probe {probe!r}{did_you_mean(probe, problem.probes)}; the problem's probes: "
                          f"{', '.join(sorted(problem.probes)) or 'none'}")
    return problem.probes[probe]


class Quantity:
    """Base class (module docstring): ``value`` (size,) and ``jacobian`` (size, 6 n) sparse;
    ``explicit(problem, g, lam, variable)`` (size, variable.size): the partial derivative at
    fixed g (zero unless the quantity depends on parameters directly, e.g. the energy on E).
    ``translation_invariant``: True when ``jacobian`` and ``explicit`` do not change with a
    translation of all frames (the value may move with it, as a position does): a control
    session evaluates them on its frames relative to a far part's origin (exact there), the
    value on the problem's (``control.session``); False (the default, and a ``UserQuantity``'s):
    all at the problem's frames.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> q = NodePosition(p, "x1")
    >>> isinstance(q, Quantity), q.size
    (True, 6)
    """

    name = "quantity"
    size = 1
    translation_invariant = False

    def value(self, problem, g, lam):
        raise NotImplementedError

    def jacobian(self, problem, g, lam):
        raise NotImplementedError

    def explicit(self, problem, g, lam, variable):
        return np.zeros((self.size, variable.size))


class NodePosition(Quantity):
    """Positions of nodes (3 per node, lab) [length], minus ``target`` (k, 3) if given.

    Parameters: problem; nodes (ids or a node-set name); target (optional); name.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> NodePosition(p, [5]).value(p, p.mesh.g0, 1.0).tolist()
    [2.0, 0.5, 0.0]
    """

    translation_invariant = True          # positions move with a translation, their derivatives do not

    def __init__(self, problem, nodes, target=None, name="position"):
        self.nodes = _nodes(problem, nodes, f"target {name!r}")
        self.name, self.size = name, 3 * len(self.nodes)
        self.target = None if target is None else target_array(target, (len(self.nodes), 3), f"target {name!r}")

    def value(self, problem, g, lam):
        x = g[self.nodes, :3, 3]
        return (x if self.target is None else x - self.target).ravel()

    def jacobian(self, problem, g, lam):
        k = len(self.nodes)
        R = g[self.nodes, :3, :3]                                    # dx = R eta_v
        rows = np.repeat(np.arange(3 * k), 3)
        cols = (6 * self.nodes[:, None, None] + np.arange(3)[None, None, :]).repeat(3, 1).reshape(-1)
        return sp.csr_matrix((R.reshape(-1), (rows, cols)), shape=(3 * k, 6 * problem.mesh.n_nodes))


class ProbePosition(Quantity):
    """Position of a probe (a point on the geodesic between two nodes) [length], minus ``target``.

    Parameters: problem; probe (a name of ``problem.probes`` or a Probe); target (3,); name.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01)); p.add_probe("tip", "x1")
    >>> ProbePosition(p, "tip").value(p, p.mesh.g0, 1.0).tolist()
    [2.0, 0.0, 0.0]
    """

    translation_invariant = True          # positions move with a translation, their derivatives do not

    def __init__(self, problem, probe, target=None, name=None):
        self.probe = _probe(problem, probe, f"target {name or probe!r}")
        self.name, self.size = name or self.probe.name, 3
        self.target = None if target is None else target_array(target, (3,), f"target {self.name!r}")

    def value(self, problem, g, lam):
        x = self.probe.state(g)[0]
        return x if self.target is None else x - self.target

    def jacobian(self, problem, g, lam):
        return _probe_jacobian(problem, self.probe, g, lambda G: G[:, :3, 3])


class Orientation(Quantity):
    """The rotation vector log(R_t^T R) [rad] of a node's or a probe's frame R relative to the
    target rotation R_t (3, 3) (default the reference frame): zero when the frame is on target.

    Parameters: problem; node (an id) or probe (a name); target (3, 3) rotation; name.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh, lie
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> g = p.mesh.g0 @ lie.exp(np.array([0, 0, 0, 0, 0.3, 0]))
    >>> Orientation(p, node=2).value(p, g, 1.0).round(12).tolist()
    [0.0, 0.3, 0.0]
    """

    translation_invariant = True

    def __init__(self, problem, node=None, probe=None, target=None, name="orientation"):
        if (node is None) == (probe is None):
            raise DesignError(f"target {name!r}: give one of node or probe")
        self.name, self.size = name, 3
        self.node = None if node is None else int(_nodes(problem, [node], f"target {name!r}")[0])
        self.probe = None if probe is None else _probe(problem, probe, f"target {name!r}")
        R0 = problem.mesh.g0[self.node, :3, :3] if node is not None else self.probe.state(problem.mesh.g0)[1]
        self.target = R0 if target is None else np.asarray(target, float)
        if self.target.shape != (3, 3) or np.abs(self.target.T @ self.target - np.eye(3)).max() > 1e-9:
            raise DesignError(f"target {name!r}: the target orientation must be a rotation matrix")

    def _R(self, g):
        return g[self.node, :3, :3] if self.node is not None else self.probe.state(g)[1]

    def value(self, problem, g, lam):
        return lie.log_so3(self.target.T @ self._R(g))

    def jacobian(self, problem, g, lam):
        n = problem.mesh.n_nodes
        if self.node is None:
            return _probe_jacobian(problem, self.probe, g, lambda G: lie.log_so3(self.target.T @ G[:, :3, :3]))
        J = lie.dexp_inv_so3(self.value(problem, g, lam))            # log(Q exp(e w)) = q + J_r^-1(q) e w
        rows, cols = np.repeat(np.arange(3), 3), np.tile(6 * self.node + 3 + np.arange(3), 3)
        return sp.csr_matrix((J.ravel(), (rows, cols)), shape=(3, 6 * n))


def twist_angle(R, axis):
    """The twist of rotations R (k, 3, 3) about the unit lab ``axis`` a: R = S T with T the turn
    by theta about a and S a swing about an axis normal to a (the swing-twist decomposition),
    theta = 2 atan2(a . v, w) for R's unit quaternion (w, v), in (-pi, pi].  A function of R
    alone, smooth except where the swing is a half turn (w = a . v = 0: a turned upside down),
    and theta = a . log(R) when R turns about a.  Also the gradient G (k, 3): d theta = G . omega
    for R <- exp(omega^) R, G = (w (w a + v x a) + (a . v) v) / (w^2 + (a . v)^2).

    Example
    -------
    >>> import numpy as np
    >>> th, G = twist_angle(lie.exp_so3(np.array([[0.0, 1.7, 0.0]])), np.array([0.0, 1.0, 0.0]))
    >>> round(float(th[0]), 12), np.round(G, 12).tolist()
    (1.7, [[0.0, 1.0, 0.0]])
    """
    psi = lie.log_so3(R)
    half = 0.5 * np.linalg.norm(psi, axis=-1)
    w = np.cos(half)
    v = 0.5 * np.sinc(half / np.pi)[:, None] * psi                 # sin(|psi|/2) psi/|psi|
    c = v @ axis
    den = w ** 2 + c ** 2
    if np.any(den < 1e-20):
        raise DesignError(f"the angle about the axis {axis.round(6).tolist()} is undefined: the frame is turned "
                          "upside down about a normal to it (a swing of a half turn); measure it about another axis")
    G = (w[:, None] * (w[:, None] * axis + np.cross(v, axis)) + c[:, None] * v) / den[:, None]
    return 2.0 * np.arctan2(c, w), G


class RotationAngle(Quantity):
    """The angle [rad] by which a probe (or node) has turned about the lab ``axis`` from its
    reference frame, continuous through any number of turns: the twist theta of R R_0^T about
    the axis (:func:`twist_angle`: R R_0^T = S T, T the turn by theta about the axis, S a swing
    about a normal to it; theta = axis . log(R R_0^T) for a turn about the axis), counted on the
    branch theta + 2 pi k nearest to a reference that follows the states it is evaluated at (it
    starts at ``reference``, default 0: the reference configuration, and becomes the value
    whenever that is more than a quarter turn from it), so that a shell turned gradually past pi
    is counted past pi; with ``target`` [rad] the misfit theta - target.  The reference picks
    only the branch: the value is a function of the state.  (Before, theta = reference +
    axis . log(exp(-reference axis) R R_0^T), which changes with the reference off the axis:
    the same state read 1.7 rad and, once the reference had followed it, 1.711 rad (a swing of
    0.3 rad) or 2.5 and 2.555 (0.6 rad), so a design's angle misfit changed with the history of
    its evaluations.)  Evaluate one RotationAngle along one path (a design's pose): a state
    turned by more than half a turn from the last reference is counted a turn short or over.

    Parameters: problem; probe (a name) or node (an id); axis (3,); target, reference [rad]; name.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh, lie
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> g = lie.exp(np.array([0, 0, 0, 0, -4.0, 0])) @ p.mesh.g0            # 4 rad about -y
    >>> round(float(RotationAngle(p, node=2, axis=(0, -1, 0), reference=3.0).value(p, g, 1.0)[0]), 12)
    4.0
    """

    translation_invariant = True

    def __init__(self, problem, probe=None, node=None, axis=(0.0, -1.0, 0.0), target=None, reference=None,
                 name="angle"):
        self.frame = Orientation(problem, node=node, probe=probe, name=name)
        a = np.asarray(axis, float)
        if a.shape != (3,) or not np.linalg.norm(a) > 0:
            raise DesignError(f"target {name!r}: the axis must be a non-zero 3-vector")
        self.axis = a / np.linalg.norm(a)
        self.target = None if target is None else float(target_array(target, (), f"target {name!r}"))
        self.reference = float(target_array(reference if reference is not None else 0.0, (), f"reference {name!r}"))
        self.R0 = self.frame.target
        self.name, self.size = name, 1

    def _angles(self, R):
        """(theta on the branch nearest to the reference (k,), its lab gradient (k, 3)) of frames R (k, 3, 3)."""
        th, G = twist_angle(R @ self.R0.T, self.axis)
        return th + 2 * np.pi * np.round((self.reference - th) / (2 * np.pi)), G

    def value(self, problem, g, lam):
        th = float(self._angles(self.frame._R(g)[None])[0][0])
        if abs(th - self.reference) > 0.5 * np.pi:
            # re-centred when the state has turned a quarter turn from the reference: the next
            # states are counted on the branch nearest to here
            self.reference = th
        return np.array([th - (self.target if self.target is not None else 0.0)])

    def jacobian(self, problem, g, lam):
        # R <- R exp(eta^) turns R R_0^T by the lab rotation R eta: d theta = (R^T G) . eta
        if self.frame.node is None:
            return _probe_jacobian(problem, self.frame.probe, g,
                                   lambda F: self._angles(F[:, :3, :3])[0][:, None])
        R = self.frame._R(g)
        row = R.T @ self._angles(R[None])[1][0]
        n = problem.mesh.n_nodes
        return sp.csr_matrix((row, (np.zeros(3, int), 6 * self.frame.node + 3 + np.arange(3))), shape=(1, 6 * n))


class AngleInDegrees(Quantity):
    """A :class:`RotationAngle` with its value, misfit and target in degrees (a scenario's angle
    target: an angle goes in and comes out of a scenario in degrees, and its default scale is
    1 rad = 57.3 deg, the Python API's, so that the objective is the same).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh, lie
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> g = lie.exp(np.array([0, 0, 0, 0, -0.5, 0])) @ p.mesh.g0            # 0.5 rad about -y
    >>> round(float(AngleInDegrees(p, node=2, target=30.0).value(p, g, 1.0)[0]), 6)   # 28.6479 - 30
    -1.35211
    """
    DEGREE = 180.0 / np.pi

    translation_invariant = True

    def __init__(self, problem, target=None, **kw):
        self.angle = RotationAngle(problem, target=None if target is None else np.radians(target), **kw)
        self.target, self.name, self.size = target, self.angle.name, 1

    def value(self, problem, g, lam):
        return self.DEGREE * self.angle.value(problem, g, lam)

    def jacobian(self, problem, g, lam):
        return self.DEGREE * self.angle.jacobian(problem, g, lam)

    def explicit(self, problem, g, lam, variable):
        return self.DEGREE * self.angle.explicit(problem, g, lam, variable)


class Energy(Quantity):
    """The elastic energy [force x length]; its left-trivialised gradient is the internal force
    r_int (the element's residual is dPi/d eta), its partial derivative by E or h that of the
    variable (``MaterialVariable.partials``: exact for the polynomial dependence).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1.0e3, 0.0, 0.01))
    >>> g = p.mesh.g0.copy(); g[:, 0, 3] *= 1.01                       # strain 0.01
    >>> round(float(Energy().value(p, g, 1.0)[0]), 12)                  # 1/2 E h eps^2 x area 1
    0.0005
    """

    name, size = "energy", 1

    translation_invariant = True

    def value(self, problem, g, lam):
        return np.array([problem.element.evaluate(g, tangent=False).energy])

    def jacobian(self, problem, g, lam):
        r = problem.element.evaluate(g, tangent=False).r
        return sp.csr_matrix(r.reshape(1, -1))

    def explicit(self, problem, g, lam, variable):
        if not hasattr(variable, "partials"):           # only a material variable changes the energy
            return np.zeros((1, variable.size))
        return variable.partials(lambda: np.array([problem.element.evaluate(g, tangent=False).energy]))


class UserQuantity(Quantity):
    """Any function of the state: fn(g, lam) -> (size,) and grad(g, lam) -> (size, n, 6), its
    left-trivialised derivative (d/d eps fn(g_i exp(eps e_j)) at [k, i, j]).

    Parameters: fn, grad, size, name.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 1, 1), Material(1.0e3, 0.0, 0.01))
    >>> def grad(g, lam):
    ...     out = np.zeros((1, len(g), 6)); out[0, :, :3] = g[:, 2, :3]; return out   # d z_i = (R eta_v)_z
    >>> q = UserQuantity(lambda g, lam: [g[:, 2, 3].sum()], grad)
    >>> q.value(p, p.mesh.g0, 1.0).tolist(), q.jacobian(p, p.mesh.g0, 1.0).nnz
    ([0.0], 4)
    """

    def __init__(self, fn, grad, size=1, name="user"):
        if not callable(fn) or not callable(grad):
            raise DesignError(f"quantity {name!r}: needs callables fn(g, lam) and grad(g, lam)")
        self.fn, self.grad, self.size, self.name = fn, grad, int(size), name

    def value(self, problem, g, lam):
        v = np.atleast_1d(np.asarray(self.fn(g, lam), float))
        if v.shape != (self.size,):
            raise DesignError(f"quantity {self.name!r}: fn returned shape {v.shape}, expected ({self.size},)")
        return v

    def jacobian(self, problem, g, lam):
        G = np.asarray(self.grad(g, lam), float)
        if G.shape != (self.size, problem.mesh.n_nodes, 6):
            raise DesignError(f"quantity {self.name!r}: grad returned shape {G.shape}, expected "
                              f"{(self.size, problem.mesh.n_nodes, 6)}")
        return sp.csr_matrix(G.reshape(self.size, -1))
