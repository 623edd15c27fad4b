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
