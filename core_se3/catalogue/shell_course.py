"""The linear shell obstacle course: patch tests and the standard linear benchmarks of shell
elements, as problems with their published reference values (``benchmarks/obstacle_course.py``
runs them; ``tests/test_shell_course.py`` checks one mesh of each).

References
----------
* MacNeal, R.H. and Harder, R.L. (1985) "A proposed standard set of problems to test finite
  element accuracy", Finite Elements in Analysis and Design 1, 3-20: the patch tests (their
  5-element patch), the Scordelis-Lo roof (0.3024), the pinched cylinder with diaphragms
  (1.8248e-5), the pinched hemisphere with an 18 deg hole (0.094) and the twisted beam (in
  plane 5.424e-3, out of plane 1.754e-3).
* Belytschko, T., Stolarski, H., Liu, W.K., Carpenter, N. and Ong, J.S.-J. (1985) "Stress
  projection for membrane and shear locking in shell finite elements", CMAME 51, 221-258: the
  same roof, cylinder and hemisphere (the "shell obstacle course"; 0.0924 for the hemisphere
  without the hole, the value tests/test_sze_p2.py uses: 1.7 % below 0.094).
* Knight, N.F. (1997) "The Raasch challenge for shell elements", AIAA J. 35, 375-381: the
  hook, 5.02.
* Cook, R.D. (1974) "Improved two-dimensional finite element", J. Struct. Div. ASCE 100, 1851:
  the tapered panel; converged deflection 23.96 at the middle of the loaded edge (e.g. Simo and
  Rifai 1990).

Each builder returns ``(problem, measure)``: ``measure(result)`` gives the displacement the
reference is for (in the load's direction).  Loads are the published ones; the answers are
linear (``Problem.solve_linear``).
"""
from __future__ import annotations

from math import pi

import numpy as np

from ..fem import Material
from ..mesh import Mesh, frames_from
from ..mesh import generators as G
from ..model import Problem
from ..solvers.linear import linear_state

__all__ = ["REFERENCES", "scordelis_lo", "pinched_cylinder", "pinched_hemisphere", "twisted_beam",
           "raasch_hook", "cook_membrane", "hat_integrals", "scenario_doc", "roof_free_edge_layer"]

REFERENCES = {
    "scordelis-lo": 0.3024, "pinched-cylinder": 1.8248e-5, "pinched-hemisphere": 0.094,
    "twisted-beam-in-plane": 5.424e-3, "twisted-beam-out-of-plane": 1.754e-3,
    "raasch-hook": 5.02, "cook-membrane": 23.96,
}


def _node(mesh, name, k):
    return int(mesh.node_set(name)[k])


def _u(result, node, direction):
    return float(np.dot(result.final.g[node, :3, 3] - result.steps[0].g[node, :3, 3], direction))


def scordelis_lo(n, h=0.25, material=None, element="default", grade=None, **kw):
    """Quarter of the Scordelis-Lo roof (R 25, L 50, 40 deg, E 4.32e8, nu 0, self-weight 90 per
    unit area), n x n; measure: the downward deflection at the middle of the free edge.
    ``grade``: the generator's (``{"x1": fraction}`` grades toward the free edge).

    Example
    -------
    >>> p, measure = scordelis_lo(4)
    >>> round(measure(p.solve_linear()) / REFERENCES["scordelis-lo"], 2)
    0.97
    """
    R, L = 25.0, 50.0
    m = G.cylinder_panel(R, L / 2, 0.0, np.radians(40.0), n, n, grade=grade)
    p = Problem(m, material or Material(4.32e8, 0.0, h), element=element, **kw)
    p.fix("x0", (0, 4, 5))                 # crown x = 0: u_x, rotations about y and z
    p.fix("y1", (1, 3, 5))                 # mid-span y = L/2: u_y, rotations about d1, d3
    p.fix("y0", (0, 2, 4))                 # diaphragm: u_x = u_z = theta_y = 0
    p.add_body_force((0.0, 0.0, -90.0))
    A = _node(m, "x1", -1)
    return p, lambda res: -_u(res, A, (0.0, 0.0, 1.0))


def scenario_doc(case, n, h, grade=None):
    """The Scordelis-Lo roof (``case`` 'scordelis-lo') or the pinched hemisphere
    ('pinched-hemisphere') of :func:`scordelis_lo` / :func:`pinched_hemisphere` as a scenario
    document (``scenario.from_dict``), n x n, thickness h; its probe ``A`` is the measured node;
    ``grade``: the generator's ``[mesh] grade`` table.

    Example
    -------
    >>> import warnings
    >>> from core_se3 import scenario
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")                  # a thin roof's load number
    ...     scn = scenario.from_dict(scenario_doc("scordelis-lo", 4, 0.25))
    >>> u = scn.problem.solve_linear().final.probes["A"]["u"]
    >>> round(-float(u[2]) / scordelis_lo(4)[1](scordelis_lo(4)[0].solve_linear()), 12)
    1.0
    """
    mesh = {"grade": dict(grade)} if grade else {}
    if case == "scordelis-lo":
        a = np.radians(40.0)
        return {"name": f"scordelis-lo-{n}", "mesh": {"generator": "cylinder_panel", "R": 25.0, "length": 25.0,
                                                      "theta0": 0.0, "theta1": float(a), "nt": n, "nl": n, **mesh},
                "material": {"E": 4.32e8, "nu": 0.0, "h": h},
                "supports": [{"type": "fix", "edge": "x0", "dofs": [0, 4, 5]},
                             {"type": "fix", "edge": "y1", "dofs": [1, 3, 5]},
                             {"type": "fix", "edge": "y0", "dofs": [0, 2, 4]}],
                "loads": [{"type": "body_force", "q": [0.0, 0.0, -90.0]}],
                "edges": {"A": {"nodes": {"near": [25.0 * np.sin(a), 25.0, 25.0 * np.cos(a)]}}},
                "probes": [{"name": "A", "edge": "A"}]}
    if case == "pinched-hemisphere":
        return {"name": f"pinched-hemisphere-{n}", "mesh": {"generator": "hemisphere_quarter", "R": 10.0,
                                                            "hole_deg": 18.0, "nt": n, "nf": n, **mesh},
                "material": {"E": 6.825e7, "nu": 0.3, "h": h},
                "edges": {"A": {"nodes": {"near": [10.0, 0.0, 0.0]}}, "B": {"nodes": {"near": [0.0, 10.0, 0.0]}}},
                "supports": [{"type": "fix", "edge": "y0", "dofs": [1, 3, 5]},
                             {"type": "fix", "edge": "y1", "dofs": [1, 3, 5]},
                             {"type": "fix", "edge": "A", "dofs": [0]}],
                "loads": [{"type": "nodal", "edge": "A", "force": [1.0, 0.0, 0.0]},
                          {"type": "nodal", "edge": "B", "force": [0.0, -1.0, 0.0]}],
                "probes": [{"name": "A", "edge": "A"}]}
    raise ValueError(f"no scenario document for {case!r}: 'scordelis-lo' or 'pinched-hemisphere'")


def roof_free_edge_layer(mesh, u):
    """Where the Scordelis-Lo roof's free-edge layer lies: along the mid-span line (y = L/2) of
    a :func:`scordelis_lo` mesh with displacements ``u`` (n, 3), the arc length s from the free
    edge at which the circumferential curvature change w'' of the normal deflection peaks, and
    the distances within which 50 % and 90 % of w''^2 lie (finite differences of the nodal w).

    A membrane-dominated cylindrical shell bends in layers along its free generators whose
    width scales like R (h/R)^(1/4) (benchmarks/results/roof_layer.md).

    Example
    -------
    >>> p, _ = scordelis_lo(32, h=25.0 / 1e4)
    >>> peak, s50, s90 = roof_free_edge_layer(p.mesh, p.solve_linear().displacements())
    >>> round(peak / (25.0 * 1e4 ** -0.25), 1)                     # about 1.5 R (h/R)^(1/4)
    1.5
    """
    X = mesh.X
    line = np.asarray(mesh.node_set("y1"))
    theta = np.arctan2(X[line, 0], X[line, 2])
    order = np.argsort(-theta)
    line, theta = line[order], theta[order]
    s = np.hypot(X[line[0], 0], X[line[0], 2]) * (theta[0] - theta)
    w = np.einsum("ni,ni->n", u[line], np.c_[np.sin(theta), np.zeros_like(theta), np.cos(theta)])
    k2 = np.gradient(np.gradient(w, s), s) ** 2
    share = np.cumsum(k2) / k2.sum()
    return float(s[np.argmax(k2)]), float(s[np.searchsorted(share, 0.5)]), float(s[np.searchsorted(share, 0.9)])


def pinched_cylinder(n, h=3.0, material=None, element="default", **kw):
    """Octant of the pinched cylinder on rigid diaphragms (R 300, L 600, E 3e6, nu 0.3, P = 1),
    n x n; measure: the inward deflection under the load."""
    R, L = 300.0, 600.0
    m = G.cylinder_panel(R, L / 2, 0.0, pi / 2, n, n)
    p = Problem(m, material or Material(3.0e6, 0.3, h), element=element, **kw)
    p.fix("x0", (0, 4, 5))
    p.fix("x1", (0, 4, 5))
    p.fix("y1", (1, 3, 5))
    p.fix("y0", (0, 2, 4))                 # diaphragm
    A = _node(m, "y1", 0)
    p.add_nodal_load([A], force=(0.0, 0.0, -0.25))
    return p, lambda res: -_u(res, A, (0.0, 0.0, 1.0))


def pinched_hemisphere(n, h=0.04, material=None, element="default", R=10.0, load_arc=None, transform=None, **kw):
    """Quarter of the hemisphere with an 18 deg hole (R 10, E 6.825e7, nu 0.3), radial loads 2
    alternating on the equator (1 on each loaded node of the quarter), n x n; measure: the
    outward displacement under the outward load.

    ``load_arc`` [length]: spread each load uniformly over this arc of the equator from its
    node (consistent nodal loads of the line load 1 / load_arc), instead of a point load.  A
    shear-deformable shell has no finite displacement under a point load: it grows like
    P ln(1/r) / (pi k G h) at a free edge (Reissner-Mindlin), so on thick shells (R/h 10) the
    point load's mesh sequence has no limit and the spread load is the well-posed problem.

    ``transform``: a function Mesh -> Mesh applied to the generated mesh (the same nodes and node
    sets; frames turned or interior nodes moved: ``benchmarks/curved_frames.py``).  The supports
    hold body-frame dofs of the symmetry edges, so a transform keeps the frames of those nodes.
    """
    m = G.hemisphere_quarter(R, 18.0, n, n)
    if transform is not None:
        m = transform(m)
    p = Problem(m, material or Material(6.825e7, 0.3, h), element=element, **kw)
    p.fix("y0", (1, 3, 5))
    p.fix("y1", (1, 3, 5))
    A, B = _node(m, "y0", -1), _node(m, "y1", -1)
    p.fix([A], (0,))                       # A on the equator: d1 = -z, the rigid z motion
    if load_arc is None:
        p.add_nodal_load([A], force=(1.0, 0.0, 0.0))
        p.add_nodal_load([B], force=(0.0, -1.0, 0.0))
    else:
        equator = np.asarray(m.node_set("x1"))
        equator = equator[np.argsort(np.arctan2(m.X[equator, 1], m.X[equator, 0]))]   # A ... B
        s = R * np.arctan2(m.X[equator, 1], m.X[equator, 0])
        w = (hat_integrals(s, load_arc) - hat_integrals(s[-1] - s[::-1], load_arc)[::-1]) / load_arc
        for k in np.flatnonzero(w):        # outward from A, inward from B
            p.add_nodal_load([equator[k]], force=tuple(w[k] * m.X[equator[k]] / R))
    return p, lambda res: _u(res, A, (1.0, 0.0, 0.0))


def hat_integrals(s, a):
    """Integrals over [0, a] of the piecewise-linear hat functions on the increasing node
    abscissae ``s`` (s[0] = 0): the consistent nodal loads of a unit line load on [0, a].

    Example
    -------
    >>> hat_integrals(np.array([0.0, 2.0, 4.0]), 3.0)
    array([1.  , 1.75, 0.25])
    """
    w = np.zeros(len(s))
    for k in range(len(s) - 1):
        L, t = s[k + 1] - s[k], min(s[k + 1], a) - s[k]
        if t <= 0:
            break
        w[k] += t - t * t / (2 * L)
        w[k + 1] += t * t / (2 * L)
    return w


def twisted_mesh(L, w, twist, nx, ny):
    """A strip of length L along x and width w, twisted by ``twist`` [rad] about x linearly."""
    s, t = np.meshgrid(np.linspace(0.0, L, nx + 1), np.linspace(-w / 2, w / 2, ny + 1))
    s, t = s.ravel(), t.ravel()
    ph = twist * s / L
    X = np.stack([s, t * np.cos(ph), t * np.sin(ph)], -1)
    dph = twist / L
    Xs = np.stack([np.ones_like(s), -t * np.sin(ph) * dph, t * np.cos(ph) * dph], -1)
    Xt = np.stack([0 * s, np.cos(ph), np.sin(ph)], -1)
    ids, quads, edges = G._structured(nx, ny)
    return Mesh(frames_from(X, Xs, np.cross(Xs, Xt)), quads, edges, shape=(nx, ny))


def twisted_beam(load, nx=12, ny=2, h=0.32, material=None, element="default", **kw):
    """MacNeal-Harder's twisted beam (L 12, w 1.1, twist 90 deg, E 29e6, nu 0.22), clamped at
    x = 0; ``load`` 'in-plane' (the tip's width direction, z) or 'out-of-plane' (y), total 1
    (scaled by (h/0.32)^3); measure: the tip's deflection along the load."""
    m = twisted_mesh(12.0, 1.1, pi / 2, nx, ny)
    p = Problem(m, material or Material(29.0e6, 0.22, h), element=element, **kw)
    p.clamp("x0")
    d = np.array([0.0, 0.0, 1.0]) if load == "in-plane" else np.array([0.0, 1.0, 0.0])
    P = (h / 0.32) ** 3
    p.add_edge_force("x1", tuple(P * d))
    tip = m.node_set("x1")
    return p, lambda res: float(np.mean([_u(res, k, d) for k in tip])) / P


def hook_mesh(nx, ny, R1=14.0, R2=46.0, width=20.0):
    """Raasch's hook: a 60 deg arc of radius R1 from the origin (tangent +x), then a 150 deg arc
    of radius R2 curving the other way; the width along z."""
    l1, l2 = R1 * pi / 3, R2 * 5 * pi / 6
    s = np.linspace(0.0, l1 + l2, nx + 1)
    a = np.minimum(s, l1) / R1                              # angle on the first arc
    b = np.maximum(s - l1, 0.0) / R2                        # angle on the second
    C2 = np.array([R1 * np.sin(pi / 3) + R2 * np.sin(pi / 3), R1 * (1 - np.cos(pi / 3)) - R2 * np.cos(pi / 3)])
    on1 = s <= l1
    P = np.where(on1[:, None], np.stack([R1 * np.sin(a), R1 * (1 - np.cos(a))], -1),
                 C2 + R2 * np.stack([np.cos(5 * pi / 6 - b), np.sin(5 * pi / 6 - b)], -1))
    T = np.where(on1[:, None], np.stack([np.cos(a), np.sin(a)], -1),
                 np.stack([np.sin(5 * pi / 6 - b), -np.cos(5 * pi / 6 - b)], -1))
    z = np.linspace(0.0, width, ny + 1)
    X = np.concatenate([np.c_[np.tile(P, (1, 1)), np.full(nx + 1, zz)] for zz in z])
    d1 = np.concatenate([np.c_[T, np.zeros(nx + 1)]] * (ny + 1))
    ez = np.tile([0.0, 0.0, 1.0], (len(X), 1))
    ids, quads, edges = G._structured(nx, ny)
    return Mesh(frames_from(X, d1, np.cross(d1, ez)), quads, edges, shape=(nx, ny))


def raasch_hook(nx=96, ny=32, h=2.0, material=None, element="default", **kw):
    """Raasch's hook (Knight 1997: E 3300, nu 0.35, width 20, thickness 2), clamped at the
    start, unit shear along the width (z) on the free end; measure: its mean z deflection."""
    m = hook_mesh(nx, ny)
    p = Problem(m, material or Material(3300.0, 0.35, h), element=element, **kw)
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 1.0))
    tip = m.node_set("x1")
    return p, lambda res: float(np.mean([_u(res, k, (0.0, 0.0, 1.0)) for k in tip]))


def cook_membrane(n, material=None, element="default", **kw):
    """Cook's tapered panel (0,0)-(48,44)-(48,60)-(0,44), E 1, nu 1/3, t 1, clamped at x = 0,
    unit shear along y on x = 48; n x n (n even); measure: the vertical deflection of the middle
    of the loaded edge, (48, 52) (plain bilinear quads converge there to 23.92 at 64 x 64; the
    top corner (48, 60) goes to 25.0)."""
    xi, eta = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    xi, eta = xi.ravel(), eta.ravel()
    y0, y1 = 44.0 * xi, 44.0 + 16.0 * xi
    X = np.stack([48.0 * xi, y0 + eta * (y1 - y0), 0 * xi], -1)
    ids, quads, edges = G._structured(n, n)
    k = len(X)
    m = Mesh(frames_from(X, np.tile([1.0, 0, 0], (k, 1)), np.tile([0, 0, 1.0], (k, 1))), quads, edges, shape=(n, n))
    p = Problem(m, material or Material(1.0, 1 / 3, 1.0), element=element, **kw)
    p.clamp("x0")
    p.fix(lambda X: X[:, 0] > 1e-9, (2, 3, 4))          # a membrane: no bending dofs
    p.add_edge_force("x1", (0.0, 1.0, 0.0))
    A = _node(m, "x1", n // 2)
    return p, lambda res: _u(res, A, (0.0, 1.0, 0.0))
