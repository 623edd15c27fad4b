"""Lie-group numerics of the element at extreme states: parts far from the origin and turned.

The element's edge twists are psi = log(g_a^-1 g_b).  Forming g_a^-1 g_b as inv(g_a) @ g_b adds
-R_a^T p_a and R_a^T p_b, two vectors of the size of the positions, and loses eps |p| on an edge
of length ~1: for a strip 1e6 lengths from the origin, turned, the NumPy backend's residual
differed from the compiled kernels' (which form R_a^T (p_b - p_a)) by 3e-8 of itself, and a
small-load solve's displacement carried 5 to 15 ulp(|p|) of error (2e-6 of the displacement at
1e6, 8e-5 at 1e8), far above the solver's tolerance 1e-10.  ``lie.relative`` differences the
positions first; both backends now agree to round-off and the displacement is that of the part
at the origin to the ulp of its stored positions.
"""
import warnings

import numpy as np
import pytest

from core_se3 import Material, Problem, backend, lie, mesh
from core_se3.fem.element_default import edge_twists
from core_se3.mesh.core import Mesh


def _moved(m, Q):
    """The mesh m carried by the rigid motion Q (4, 4)."""
    return Mesh(g0=Q @ m.g0, quads=m.quads, edges=m.edges, shape=m.shape)


def _rigid(axis, angle, t):
    Q = np.eye(4)
    n = np.asarray(axis, float)
    Q[:3, :3] = lie.exp_so3(angle * n / np.linalg.norm(n))
    Q[:3, 3] = t
    return Q


def test_relative_differences_positions_first():
    """lie.relative(g_a, g_b) = g_a^-1 g_b with the translation R_a^T (p_b - p_a) exact to the
    edge's round-off, also 1e7 from the origin (inv(g_a) @ g_b: 7e-10 off on unit edges)."""
    rng = np.random.default_rng(0)
    ga = lie.exp(rng.normal(size=(50, 6)))
    ga[:, :3, 3] += rng.normal(size=(50, 3)) * 1e7
    gb = ga @ lie.exp(rng.normal(size=(50, 6)) * 0.3)
    L = np.longdouble
    exact = np.einsum("eji,ej->ei", ga[:, :3, :3].astype(L), gb[:, :3, 3].astype(L) - ga[:, :3, 3].astype(L))
    h = lie.relative(ga, gb)
    edge = np.linalg.norm(gb[:, :3, 3] - ga[:, :3, 3], axis=1)
    assert np.all(np.abs(h[:, :3, 3] - exact).max(1) <= 8 * np.finfo(float).eps * edge)
    assert np.abs(h[:, :3, :3] - lie.inv(ga)[:, :3, :3] @ gb[:, :3, :3]).max() == 0.0
    assert np.array_equal(h[:, 3], np.broadcast_to([0.0, 0.0, 0.0, 1.0], (50, 4)))
    # broadcasting: one frame against many
    assert np.array_equal(lie.relative(ga[0], gb), lie.relative(np.broadcast_to(ga[0], ga.shape), gb))


def test_edge_twists_of_a_far_turned_part_to_edge_round_off():
    """The element's edge twists of a deformed strip 3.7e6 from the origin, turned by 2 rad: their
    translations equal R_a^T (p_b - p_a) of the stored frames (long double) to a few eps of the
    edge length 1.25 (before: 6.9e-10, eps |p| -- 2.8e6 eps of the edge)."""
    Q = _rigid([1.2, -0.8, 1.5], 2.19, (3e6, -1e6, 2e6))
    m = _moved(mesh.rectangle(10.0, 1.0, 8, 2), Q)
    g = m.g0 @ lie.exp(np.random.default_rng(1).normal(size=(m.n_nodes, 6)) * 0.01)
    psi = edge_twists(g, m.edge_nodes)
    En, L = m.edge_nodes, np.longdouble
    ga, gb = g[En[:, 0]].astype(L), g[En[:, 1]].astype(L)
    p = np.einsum("eji,ej->ei", ga[:, :3, :3], gb[:, :3, 3] - ga[:, :3, 3])
    # psi's translation is J_l^-1(w) p: apply J_l(w) (round-off ~eps |p|) to compare with p
    Jl = np.swapaxes(lie.dexp_so3(psi[:, 3:]), 1, 2)
    p_psi = np.einsum("eij,ej->ei", Jl, psi[:, :3])
    assert np.abs(p_psi - p).max() <= 10 * np.finfo(float).eps * 1.25


@pytest.mark.skipif(not backend.numba_available(), reason="compares with the compiled kernels")
def test_backends_agree_on_a_far_turned_part():
    """Residual, tangent and energy of NumPy and numba at a deformed state of a strip 3.7e6 from
    the origin, turned: equal to round-off (before: 3.2e-8 of the residual, 4e-10 of K)."""
    Q = _rigid([1.2, -0.8, 1.5], 2.19, (3e6, -1e6, 2e6))
    m = _moved(mesh.rectangle(10.0, 1.0, 8, 2), Q)
    g = m.g0 @ lie.exp(np.random.default_rng(0).normal(size=(m.n_nodes, 6)) * 0.01)
    ev = [Problem(m, Material(1.2e6, 0.3, 0.1), backend=b).evaluate(g, 0.0, True) for b in ("numpy", "numba")]
    r0 = np.abs(ev[0].r_int).max()
    assert np.abs(ev[0].r_int - ev[1].r_int).max() <= 1e-13 * r0
    K0 = ev[0].K.toarray()
    assert np.abs(K0 - ev[1].K.toarray()).max() <= 1e-13 * np.abs(K0).max()
    assert abs(ev[0].energy - ev[1].energy) <= 1e-13 * ev[0].energy


def _cantilever_u(Q, backend_name):
    """Displacements (in the part's frame) of a small-load one-step cantilever carried by Q."""
    m = _moved(mesh.rectangle(10.0, 1.0, 8, 2), Q)
    p = Problem(m, Material(1.2e6, 0.3, 0.1), backend=backend_name)
    p.clamp("x0")
    p.add_edge_force("x1", tuple(Q[:3, :3] @ [0.0, 0.0, 4e-4]))      # tip deflection 1.3e-3
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        g = p.solve(steps=1).final.g
    return np.einsum("ji,nj->ni", Q[:3, :3], g[:, :3, 3] - m.g0[:, :3, 3])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_far_turned_part_solves_to_the_ulp_of_its_positions(seed):
    """A cantilever 1e5 ... 1e8 from the origin, turned, under a small load: its displacements
    equal those at the origin to 2 ulp of its positions (a displacement is a difference of two
    stored positions: 1 ulp).  Before: 4.8 ... 14 ulp (2e-6 of the tip deflection at 1e6)."""
    rng = np.random.default_rng(seed)
    t = rng.normal(size=3) * 10 ** rng.uniform(5, 8)
    Q = _rigid(rng.normal(size=3), rng.uniform(0.5, 3.1), t)
    u0 = _cantilever_u(np.eye(4), "numpy")
    u = _cantilever_u(Q, "numpy")
    assert np.abs(u - u0).max() <= 2 * np.spacing(np.abs(t).max())


# ------------------------------------------------ checks at extreme states (no bug found) ------

def _deformed(rng, m, rot=0.3, trans=0.02):
    return m.g0 @ lie.exp(np.concatenate([trans * rng.normal(size=(m.n_nodes, 3)),
                                          rot * rng.normal(size=(m.n_nodes, 3))], 1))


def _rolled(m, k, twist=0.0):
    """Each node of the flat strip m carried along the helix exp(x (e1, (twist, k, 0)))."""
    X = m.X
    xi = np.zeros((m.n_nodes, 6))
    xi[:, 0], xi[:, 3], xi[:, 4] = X[:, 0], twist * X[:, 0], k * X[:, 0]
    off = np.zeros((m.n_nodes, 6))
    off[:, 1] = X[:, 1]
    return lie.exp(xi) @ lie.exp(off)


@pytest.mark.parametrize("backend_name", ["numpy", "numba"])
def test_objectivity_with_half_turns_and_far_translations(backend_name):
    """g <- Q g with Q turning by pi - 1e-9, pi and 4 pi + 1e-3 and translating by 0 or 1e6 (the
    element edges 0.25): residual, tangent and energy unchanged to the round-off of the moved
    positions, ulp(|t|) <= 2 eps |t| on each edge vector (observed: 5e-11 .. 1.6e-10 of the force
    scale at 1e6, where 4 eps |t| / edge is 3.6e-9; 1e-16 at t = 0)."""
    if backend_name == "numba" and not backend.numba_available():
        pytest.skip("needs numba")
    rng = np.random.default_rng(2)
    m = mesh.rectangle(1.0, 0.25, 4, 2)
    g = _deformed(rng, m)
    p = Problem(m, Material(1e4, 0.3, 0.01), backend=backend_name)
    ev = p.evaluate(g, 0.0, True)
    K = ev.K.toarray()
    for angle in (np.pi - 1e-9, np.pi, 4 * np.pi + 1e-3):
        for t in (0.0, 1e6):
            n = rng.normal(size=3)
            n /= np.linalg.norm(n)
            Q = np.eye(4)
            Q[:3, :3], Q[:3, 3] = lie.exp_so3(angle * n), t * n
            ev2 = p.evaluate(Q @ g, 0.0, True)
            d = 4 * np.finfo(float).eps * (t + 1.0) / 0.25        # relative strain round-off
            assert np.abs(ev2.r_int - ev.r_int).max() <= d * ev.force_scale
            assert np.abs(ev2.K.toarray() - K).max() <= d * np.abs(K).max()
            # the energy's relative change is ~2 |dz| / |z - z0|, the strains z - z0 here ~0.2
            assert abs(ev2.energy - ev.energy) <= 10 * d * ev.energy


@pytest.mark.parametrize("edge_turn", [0.5, 0.9, 0.96])
def test_edges_turning_near_pi_give_the_exact_bending_strain(edge_turn):
    """A flat strip rolled up so that each element edge turns by edge_turn * pi (3.84 turns at
    0.96): the strain twists are the exact curvature (natural coordinates: k dx / 2), with its
    sign -- the log takes the short way -- to 1e-14 (observed <= 9e-16), in either sense."""
    nx, L = 8, 1.0
    m = mesh.rectangle(L, 0.2, nx, 2)
    p = Problem(m, Material(1e3, 0.3, 0.01), backend="numpy")
    for sense in (1.0, -1.0):
        k = sense * edge_turn * np.pi * nx / L
        dz = p.element.strains(_rolled(m, k)) - p.element.strains(m.g0)
        expect = np.zeros(12)
        expect[4] = 0.5 * k * L / nx
        assert np.abs(dz - expect).max() <= 1e-14 * abs(expect[4])


@pytest.mark.parametrize("backend_name", ["numpy", "numba"])
def test_a_strip_rolled_twice_round_sees_rigid_motions_as_strain_free(backend_name):
    """Reference: a strip rolled two full turns (32 elements, 0.39 rad per edge); current: that
    roll turned rigidly by 2 pi + 1e-3, 6 pi - 1e-6 and pi about its axis and moved: residual
    <= 1e-14 of the force scale, energy round-off (observed 5e-14 |r|, 2e-28 energy)."""
    if backend_name == "numba" and not backend.numba_available():
        pytest.skip("needs numba")
    m1 = mesh.rectangle(1.0, 0.2, 32, 2)
    g0 = _rolled(m1, 4 * np.pi)
    m = Mesh(g0=g0, quads=m1.quads, edges=m1.edges, shape=m1.shape)
    p = Problem(m, Material(1e3, 0.3, 0.01), backend=backend_name)
    for angle in (2 * np.pi + 1e-3, 6 * np.pi - 1e-6, np.pi):
        Q = _rigid([0.0, 1.0, 0.0], angle, (5.0, 6.0, 7.0))
        ev = p.evaluate(Q @ g0, 0.0, False)
        assert np.abs(ev.r_int).max() <= 1e-14 * ev.force_scale
        assert ev.energy <= 1e-24 * ev.force_scale


def _fd_tangent_error(p, g, h=1e-6):
    """The largest relative column error |K e_j - (r(g exp(h e_j)) - r(g exp(-h e_j))) / 2h|
    / |K e_j| over the dofs."""
    K = p.evaluate(g, 0.0, True).K.toarray()
    n = p.mesh.n_nodes
    worst = 0.0
    for j in range(6 * n):
        e = np.zeros((n, 6))
        e.ravel()[j] = h
        col = (p.evaluate(g @ lie.exp(e), 0.0, False).r_int - p.evaluate(g @ lie.exp(-e), 0.0, False).r_int)
        worst = max(worst, np.linalg.norm(col.ravel() / (2 * h) - K[:, j]) / np.linalg.norm(K[:, j]))
    return worst


@pytest.mark.parametrize("state", ["folded", "turned_pi"])
@pytest.mark.parametrize("h_over_L", [1e-5, 1.0])
def test_tangent_at_extreme_states_matches_finite_differences(state, h_over_L):
    """The consistent tangent by central differences (h = 1e-6) on a strip whose edges turn by
    0.95 pi (nearly folded), or deformed and turned by pi - 1e-9 as a whole, very thin (h/L =
    1e-5) and thick (h/L = 1): column errors ~1e-9 (observed 4e-10 .. 2.5e-9, the differences'
    round-off eps |r| / h and truncation h^2), so 1e-6 as tests/test_element.py's FD_TOL."""
    rng = np.random.default_rng(5)
    m = mesh.rectangle(1.0, 0.25, 4, 1)
    if state == "folded":
        g = _rolled(m, 0.95 * np.pi * 4 / 1.02, twist=0.2 * 0.95 * np.pi * 4 / 1.02) @ lie.exp(
            0.003 * rng.normal(size=(m.n_nodes, 6)))
    else:
        g = _rigid(rng.normal(size=3), np.pi - 1e-9, 0.0) @ _deformed(rng, m, rot=0.05, trans=0.05)
    p = Problem(m, Material(1e3, 0.3, h_over_L), backend="numpy")
    assert _fd_tangent_error(p, g) <= 1e-6


@pytest.mark.parametrize("scale", [1e-3, 1e-8, 1e2])
def test_units_and_size_scale_out(scale):
    """The same cantilever (PL^2/EI = 10 at the end of 5 steps) in mm-N-MPa and with every length
    times ``scale`` (1e-3: m-N-Pa, E x 1e6; 1e-8: L = 1e-6; 1e2: L = 1e4, forces x scale^2):
    displacements scale exactly (<= 1e-13 relative, observed <= 1e-15) and every step takes the
    same Newton iterations -- the convergence test is scale-free (solvers.convergence)."""
    def run(s, E_factor, F_factor):
        p = Problem(mesh.rectangle(100.0 * s, 10.0 * s, 10, 2), Material(2.1e5 * E_factor, 0.3, 1.0 * s),
                    backend="numpy")
        p.clamp("x0")
        p.add_edge_force("x1", (0.0, 0.0, 175.0 * F_factor))
        res = p.solve(steps=5)
        return res.final.g[:, :3, 3] - p.mesh.g0[:, :3, 3], [st.iterations for st in res.steps]
    u0, it0 = run(1.0, 1.0, 1.0)
    E_factor, F_factor = (1e6, 1.0) if scale == 1e-3 else (1.0, scale ** 2)
    u, it = run(scale, E_factor, F_factor)
    assert it == it0
    assert np.abs(u / scale - u0).max() <= 1e-13 * np.abs(u0).max()


def test_seed_update_of_a_far_part_sees_only_the_prescribed_motion():
    """The seed element's strain state is fed log(g^-1 g_try) at the start of a try with a
    prescribed motion (``newton._try_start``).  A part 1e9 from the origin, turned, whose
    right edge is lifted by 1e-3: the nodes that do not move get exactly 0 (before, inv(g) @ g
    gave them 1.2e-7 of translation -- 1.2e-4 of the lift, a spurious strain of 1e-7 per try
    that the stateful element keeps), the lifted ones the lift R^T dz to edge round-off."""
    from types import SimpleNamespace
    from core_se3.solvers.newton import _try_start
    Q = _rigid([1.2, -0.8, 1.5], 2.19, np.array([3e9, -1e9, 2e9]) / 3.7)
    m = _moved(mesh.rectangle(10.0, 1.0, 8, 2), Q)
    right = m.node_set("x1")
    lift = Q[:3, :3] @ [0.0, 0.0, 1e-3]

    def apply_prescribed(g, lam):
        g[right, :3, 3] += lam * lift
        return g

    fed = []
    problem = SimpleNamespace(element=SimpleNamespace(save=lambda: None, update=fed.append))
    eq = SimpleNamespace(apply_prescribed=apply_prescribed, stateful=True)
    trier = SimpleNamespace(opts=SimpleNamespace(predictor="none"))
    _try_start(problem, eq, trier, m.g0, m.g0, 0.0, 1.0, False, None)
    eta = fed[0]
    still = np.setdiff1d(np.arange(m.n_nodes), right)
    assert np.all(eta[still] == 0.0)
    moved = m.g0[right, :3, 3] + lift                       # the stored lifted positions
    exact = np.einsum("kji,kj->ki", m.g0[right, :3, :3], moved - m.g0[right, :3, 3])
    assert np.abs(eta[right, :3] - exact).max() <= 4 * np.finfo(float).eps * 1e-3
    assert np.all(eta[right, 3:] == 0.0)
