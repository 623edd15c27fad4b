"""The mechanics at large rotations on both backends (CORE_SE3_BACKEND=numpy and numba): the
assembled tangent of every built-in load, support and contact against central differences of
the residual along g_i <- g_i exp(eps eta_i); the residual, tangent and energy under rigid
motions of angles beyond 2 pi; six zero modes of free patches; one final state whatever the
number of load steps of conservative loads.

What the other tests leave out and this one covers: states turned past a full turn (a strip
rolled by 2 pi + 1.3 rad and then moved rigidly by 7.9 rad, so that its elements sit across the
cut of the rotations' log at pi and 2 pi), follower and dead variants of each load, the
magnetic kinds in user and rotating fields, contact and friction on the numba backend and with
the frames turned, a sliver quad and a curved patch across the log's cut.

Tolerances.  The central differences take eps = 1e-6 (``model.verify.FD_STEP``; a tenth of the
contact's smoothing band with contact): their truncation error is eps^2 |K''| ~ 1e-12 of |K| and
their round-off eps_mach |r| / eps ~ 1e-10 of |r|, so a consistent tangent agrees to about
1e-10; the bar is 1e-6 (measured 2e-11 ... 6e-10), a dropped load stiffness term is O(1).  The
element stiffness is made negligible (E = 1e-9) in the load checks, so that the load's own
stiffness is what is compared, relative to max(|K_fd|, |r|) (a follower force has none).
Invariance and step independence are exact in exact arithmetic: 1e-12 (measured 1e-16 ... 8e-15).
"""
import numpy as np
import pytest

import core_se3 as cs
from core_se3 import backend as _backend, lie
from core_se3 import mesh as M
from core_se3.assembly import Assembler
from core_se3.model import HalfSpace, Sphere, tangent_fd_check, verify
from core_se3.model.fields import DipoleField, GradientField, UniformField, UserField, rotating_direction
from core_se3.model.obstacle_kinds import Box, Cylinder
from core_se3.model.obstacles import rotation
from test_friction import _friction_state

BACKENDS = ["numpy", pytest.param("numba", marks=pytest.mark.skipif(not _backend.numba_available(),
                                                                     reason="numba is not installed"))]
G_GRAD = np.array([[0.3, 0.1, 0.0], [0.1, -0.1, 0.2], [0.0, 0.2, -0.2]])     # symmetric, traceless


def _rigid(seed, angle, shift):
    """A rigid motion: a turn by ``angle`` [rad] about a random axis, a random shift of size ``shift``."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=3)
    return lie.exp(np.r_[shift * rng.normal(size=3), angle * a / np.linalg.norm(a)])


def _rolled(m, seed=0):
    """The strip rolled about -y by 2 pi + 1.3 rad over its length (exact: g = exp(x zeta) T(y)),
    perturbed by 0.05 and moved rigidly by 7.9 rad and a shift of about 3."""
    xi = np.zeros((m.n_nodes, 6))
    xi[:, 0], xi[:, 4] = m.X[:, 0], -(2 * np.pi + 1.3) * m.X[:, 0]
    T = np.tile(np.eye(4), (m.n_nodes, 1, 1))
    T[:, 1, 3] = m.X[:, 1]
    rng = np.random.default_rng(seed)
    return _rigid(seed, 7.9, 3.0) @ lie.exp(xi) @ T @ lie.exp(0.05 * rng.normal(size=(m.n_nodes, 6)))


def _user_field():
    """B = 0.2 + G x + (x^2 - y^2, -2 x y, 0) / 2: curl- and divergence-free, with its Hessian."""
    H = np.zeros((3, 3, 3))
    H[0, 0, 0], H[0, 1, 1], H[1, 0, 1], H[1, 1, 0] = 1.0, -1.0, -1.0, -1.0

    def value(x):
        q = np.stack([0.5 * (x[..., 0] ** 2 - x[..., 1] ** 2), -x[..., 0] * x[..., 1], 0 * x[..., 0]], -1)
        return 0.2 + x @ G_GRAD.T + q

    def gradient(x):
        J = np.broadcast_to(G_GRAD, x.shape + (3,)).copy()
        J[..., 0, 0] += x[..., 0]
        J[..., 0, 1] -= x[..., 1]
        J[..., 1, 0] -= x[..., 1]
        J[..., 1, 1] -= x[..., 0]
        return J
    return UserField(value, gradient, lambda x: np.broadcast_to(H, x.shape + (3, 3)).copy())


F, MOM, BR = (0.3, -0.2, 0.9), (0.1, 0.5, -0.3), (0.2, -0.5, 0.7)
LOADS = {
    "edge force": lambda p: p.add_edge_force("x1", F),
    "edge force follower": lambda p: p.add_edge_force("x1", F, follower=True),
    "edge moment": lambda p: p.add_edge_moment("x1", F),
    "edge moment follower": lambda p: p.add_edge_moment("x1", F, follower=True),
    "nodal": lambda p: p.add_nodal_load("x1", F, MOM),
    "nodal follower": lambda p: p.add_nodal_load("x1", F, MOM, follower=True),
    "pressure": lambda p: p.add_pressure(0.7, direction=F),
    "pressure follower": lambda p: p.add_pressure(0.7, follower=True),
    "body force": lambda p: p.add_body_force(F),
    "gravity": lambda p: p.add_gravity(rho=100.0, g=(0.3, -0.2, -9.0)),
    "magnet uniform": lambda p: p.add_magnetic(BR, UniformField(F), mu0=1.0),
    "magnet rotating": lambda p: p.add_magnetic(
        BR, UniformField(F, direction=rotating_direction((0, 1, 1), (1, 0, 0), 3.3)), mu0=1.0),
    "magnet gradient": lambda p: p.add_magnetic(BR, GradientField((0.1, 0.0, 0.2), G_GRAD, (0.2, 0.1, -0.3)), mu0=1.0),
    "magnet dipole": lambda p: p.add_magnetic(BR, DipoleField(F, (0.5, 0.3, 2.5), mu0=1.0), mu0=1.0),
    "magnet user": lambda p: p.add_magnetic(BR, _user_field(), mu0=1.0),
    "lab spring": lambda p: p.add_lab_support("x1", [[[1.0, 0.2, 0.0], [0.0, 0.3, 1.0]]], 3.0),
    "lab tilt spring": lambda p: p.add_lab_tilt_support("x1", (0.2, 1.0, 0.3), 3.0),
}


def _load_error(p, g, lam=0.7):
    """max |K - K_fd| / max(|K_fd|, |r|) on the free dofs."""
    err, K, Kfd = tangent_fd_check(p, g, lam)
    return np.abs(K - Kfd).max() / max(np.abs(Kfd).max(), np.abs(p.residual(g, lam)).max())


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("load", list(LOADS))
def test_load_tangents_on_a_strip_rolled_past_a_full_turn(backend, load):
    m = M.rectangle(1.0, 0.2, 12, 1)
    p = cs.Problem(m, cs.Material(1e-9, 0.3, 0.05), backend=backend)     # the load's stiffness dominates
    p.clamp("x0")
    LOADS[load](p)
    assert _load_error(p, p.apply_prescribed(_rolled(m), 0.7)) < 1e-6


def _sliver():
    """Two quads, the second a trapezoid of top edge 0.04 (of its bottom edge's 0.5)."""
    m = M.rectangle(1.0, 0.5, 2, 1)
    g0 = m.g0.copy()
    g0[4, 0, 3] += 0.46
    return cs.mesh.Mesh(g0, m.quads, edges=dict(m.edges))


def _patches():
    """A sliver, a distorted rectangle and a cylinder panel whose frames turn through pi (the cut of log)."""
    d = M.rectangle(1.0, 0.3, 6, 2)
    g0, X = d.g0.copy(), d.X
    g0[:, 0, 3] += 0.06 * np.sin(7 * X[:, 1] + 3 * X[:, 0]) * (X[:, 0] > 0) * (X[:, 0] < 1)
    g0[:, 1, 3] += 0.04 * np.sin(5 * X[:, 0])
    return {"sliver": _sliver(), "distorted": cs.mesh.Mesh(g0, d.quads, edges=dict(d.edges)),
            "across the cut": M.cylinder_panel(1.0, 0.4, 2.2, 4.3, 8, 2)}


@pytest.mark.parametrize("backend", BACKENDS)
def test_element_and_prescribed_rotations_beyond_two_pi(backend):
    """The element on the rolled strip, the sliver, the distorted and the cut patch; an edge
    turned (rotate_edge, move_edge) by 7 and 13 rad: full tangent against differences."""
    for name, m in {"rolled": M.rectangle(1.0, 0.2, 12, 1), **_patches()}.items():
        p = cs.Problem(m, cs.Material(1.0, 0.3, 0.05), backend=backend)
        p.clamp("x0")
        g = _rolled(m) if name == "rolled" else m.g0 @ lie.exp(0.6 * np.random.default_rng(1).normal(size=(m.n_nodes, 6)))
        assert tangent_fd_check(p, p.apply_prescribed(_rigid(2, 7.9, 3.0) @ g, 0.7), 0.7)[0] < 1e-6, name
    m = M.rectangle(1.0, 0.2, 12, 1)
    for angle in (7.0, 13.0):
        for move in (False, True):
            p = cs.Problem(m, cs.Material(1.0, 0.3, 0.05), backend=backend)
            p.clamp("x0")
            if move:
                p.move_edge("x1", (0.1, 0.2, 0.3), axis=(0.3, 1.0, 0.2), angle=angle)
            else:
                p.rotate_edge("x1", (0.3, 1.0, 0.2), angle, point=(1.0, 0.0, 0.0))
            assert tangent_fd_check(p, p.apply_prescribed(_rolled(m), 0.7), 0.7)[0] < 1e-6, (angle, move)


OBSTACLES = {"half_space": lambda: HalfSpace((0, 0, -0.01), (0.1, 0, 1)),
             "sphere": lambda: Sphere((0.5, 0, 0.6), 0.6),
             "roller": lambda: Cylinder((0.5, 0, 0.6), (0, 1, 0), 0.6, motion=rotation((0, 1, 0), (0.5, 0, 0.6), 0.5)),
             "turning_box": lambda: Box((0.5, 0.3, -0.5), (0.6, 0.6, 0.5), rotation=(0.0, 0.1, 0.0),
                                        motion=rotation((0, 0, 1), (0.5, 0.3, 0.0), 0.3))}


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_contact_and_friction_tangents_with_the_frames_turned(backend, mu):
    """Every obstacle kind, frictionless and rough (nodes in stick, in slip and free), the
    frames turned by 2.5 rad about the normal: full tangent (non-symmetric with friction)."""
    for name, ob in OBSTACLES.items():
        prob, cl, g, lam = _friction_state(ob(), mu=mu, backend=backend, turn=2.5)
        x, d, n, H, p, dp = cl.state(g, lam)
        on = p > 0
        if mu:
            stick = cl.friction_state(g, lam, x, n, H, p, dp)[2]
            assert (on & stick).any() and (on & ~stick).any() and (~on).any(), name
        assert tangent_fd_check(prob, g, lam, free_all=True)[0] < 1e-6, name


def _body_frame_evaluation(p, g):
    asm = Assembler(p.mesh, np.ones(6 * p.mesh.n_nodes, bool))
    ev = p.evaluate(g, 0.7, assembler=asm)
    return ev.r, ev.K.toarray(), ev.energy


@pytest.mark.parametrize("backend", BACKENDS)
def test_rigid_motions_beyond_two_pi_change_nothing(backend):
    """g <- h g, h turned by 20 pi + 0.3 ... 22 pi + 0.3 rad and shifted by about 5 (follower
    loads), or shifted only (dead loads, weight, a magnet in a uniform field): residual,
    tangent and energy in the body frames unchanged to round-off."""
    def follower(p):
        p.add_edge_force("x1", F, follower=True), p.add_edge_moment("x1", MOM, follower=True)
        p.add_pressure(0.7, follower=True)

    def dead(p):
        p.add_edge_force("x1", F), p.add_gravity(rho=10.0), p.add_pressure(0.7, direction=(0, 0.3, 1))
        p.add_magnetic(BR, UniformField(F), mu0=1.0)
    for name, m in {"rolled": M.rectangle(1.0, 0.2, 12, 1), **_patches()}.items():
        g = _rolled(m) if name == "rolled" else m.g0 @ lie.exp(0.6 * np.random.default_rng(0).normal(size=(m.n_nodes, 6)))
        for loads, turn in ((follower, 20 * np.pi + 0.3), (dead, 0.0)):
            p = cs.Problem(m, cs.Material(1.0, 0.3, 0.05), backend=backend)
            loads(p)
            r0, K0, e0 = _body_frame_evaluation(p, g)
            for seed in range(3):
                r1, K1, e1 = _body_frame_evaluation(p, _rigid(seed, turn + seed * (turn > 0), 5.0) @ g)
                assert np.abs(r1 - r0).max() < 1e-12 * np.abs(r0).max(), (name, loads.__name__)
                assert np.abs(K1 - K0).max() < 1e-12 * np.abs(K0).max(), (name, loads.__name__)
                assert abs(e1 - e0) < 1e-12 * abs(e0), (name, loads.__name__)


@pytest.mark.parametrize("backend", BACKENDS)
def test_six_zero_modes_of_a_sliver_a_distorted_and_a_cut_patch(backend):
    """Free patches moved rigidly by 20 pi + 0.3 rad: exactly six eigenvalues of sym(K) below
    1e-10 of the largest (measured <= 2e-16), the seventh >= 1e-7 of it (measured 4.4e-7 ... 3.6e-6)."""
    for name, m in _patches().items():
        for nu in (0.0, 0.3):
            p = cs.Problem(m, cs.Material(1.0e4, nu, 0.02), backend=backend)
            ev, n_zero = verify.zero_modes(p, _rigid(1, 20 * np.pi + 0.3, 3.0) @ m.g0)
            assert n_zero == 6 and ev[6] > 1e-7 * ev[-1], (name, nu, ev[:8] / ev[-1])


def test_conservative_loads_reach_one_state_in_1_7_and_23_steps():
    """A cylinder panel under a dead edge force, its weight, a dead pressure, magnets in a uniform
    and in a gradient field and a lab spring (all conservative: one equilibrium path-independent):
    the final states of 1, 7 and 23 load steps agree to 1e-12 (measured 3e-16 of the length and
    2e-15 of the rotations; the tip moves 0.9 of the length)."""
    finals = []
    for steps in (1, 7, 23):
        m = M.cylinder_panel(1.0, 0.3, -0.6, 0.6, 10, 2)
        p = cs.Problem(m, cs.Material(1e4, 0.3, 0.02))
        p.clamp("x0")
        p.add_edge_force("x1", (0.0, 0.01, -0.02))
        p.add_gravity(rho=2.0, g=(0, 0, -9.81))
        p.add_pressure(1e-3, direction=(0, 0, -1.0))
        p.add_magnetic((0.5, 0.0, 0.1), UniformField((0.0, 0.2, 1.0)), mu0=1.0, elements=np.arange(10))
        p.add_magnetic((0.2, 0.0, 0.3), GradientField((0.1, 0.0, 0.3), G_GRAD), mu0=1.0, elements=np.arange(10, 20))
        p.add_lab_support("x1", [[[0.0, 1.0, 0.0]]], 10.0)
        finals.append(p.solve(steps=steps, rtol=1e-12, dtol=1e-12).final.g)
    u = np.abs(finals[0][:, :3, 3] - m.g0[:, :3, 3]).max()
    assert u > 0.05 * m.length_scale                                     # a large deflection
    for g in finals[1:]:
        assert np.abs(g[:, :3, 3] - finals[0][:, :3, 3]).max() < 1e-12 * m.length_scale
        assert np.abs(g[:, :3, :3] - finals[0][:, :3, :3]).max() < 1e-12
