"""Sze, Liu & Lo (2004) s3.4 (hemisphere), s3.5 (pull-out), s3.6 (pinched cylinder) with
core_se3 (issue 6, P2), on coarse meshes, and the lab-frame diaphragm springs they use.

References: core_se3/data/literature.json ``sze3.4_hemisphere_18deg_hole``,
``sze3.5_pullout_open_cylinder``, ``sze3.6_pinched_cylinder_diaphragms``.  Measure: largest
distance of a computed point to the table polyline in (P/P_max, u/u_max).  Measured (default
element):

    sze-hemisphere        8x8 4.71 %    16x16 1.47 %
    sze-pullout           18x12 2.70 %  (table mesh 36x24: benchmarks/results/sze.md)
    sze-pinched-cylinder  16x16 3.79 %  (rigid diaphragm u_x = u_z = theta_y = 0; the table
                          mesh 48x48 gives 2.13 % in the benchmarks, 4.39 % with the diaphragm
                          rotations free, docs/PATHFOLLOWING.md; on 8x8 the sequence of
                          wrinkling snaps is not resolved and the path wanders onto unstable
                          branches, so it has no curve test)

The hemisphere's R = 10 (marked unverified in LITERATURE.md) is the MacNeal-Harder geometry,
confirmed by the linear MacNeal-Harder reference (radial deflection 0.0924 under F = 2, two
public sources) checked below; the column signs are confirmed by the curve itself (a flipped
sign would deviate by > 100 %).
"""
import numpy as np
import pytest

from core_se3 import catalogue, lie, solvers as C
from core_se3.model import verify
from core_se3.catalogue import get_case
from core_se3.model.supports import LabSpring, LabTiltSpring, RotationComponentSpring


def test_lab_spring_tangent_matches_finite_differences():
    """The pinched cylinder's diaphragm springs (k = 100 E h) on a 4x4 octant, at a random
    deformed state: tangent vs central differences of the residual, relative 1e-6
    (measured 6e-9)."""
    case = get_case("sze-pinched-cylinder")
    prob = catalogue.build_problem(case, catalogue.case_params(case), (4, 4))
    assert any(isinstance(ld, LabSpring) for ld in prob.loads)
    rng = np.random.default_rng(0)
    g = prob.mesh.g0 @ lie.exp(0.01 * rng.standard_normal((prob.mesh.n_nodes, 6)))
    err, _, _ = verify.tangent_fd_check(prob, g, 0.5)
    assert err < 1e-6, err


def test_lab_tilt_spring_tangent_and_hold():
    """The diaphragm study option ``diaphragm_tilt=1`` (LabTiltSpring: normal kept normal to the
    ring, c = d3 . t = 0): tangent vs central differences on a 4x4 octant at a random deformed
    state, relative 1e-6 (measured 3e-11); on 8x8 to P = 0.06 P_max |c| < 1e-5 (a sine; the
    penalty error M/k_r, measured 1.5e-7) while without it the normal tilts by > 1e-4
    (measured 4.6e-4): the option is the only thing that holds it."""
    case = get_case("sze-pinched-cylinder")
    p = catalogue.case_params(case, {"diaphragm_theta_axis": 0.0, "diaphragm_tilt": 1.0})
    prob = catalogue.build_problem(case, p, (4, 4))
    tilt = [ld for ld in prob.loads if isinstance(ld, LabTiltSpring)]
    assert len(tilt) == 1
    rng = np.random.default_rng(1)
    g = prob.mesh.g0 @ lie.exp(0.05 * rng.standard_normal((prob.mesh.n_nodes, 6)))
    err, _, _ = verify.tangent_fd_check(prob, g, 0.5)
    assert err < 1e-6, err
    cs = []
    for on in (1.0, 0.0):
        prob = catalogue.build_problem(case, catalogue.case_params(case, {"diaphragm_theta_axis": 0.0,
                                                                  "diaphragm_tilt": on}), (8, 8))
        res = C.arc_length(prob, lam_end=0.06, dlam0=0.02)
        y0 = prob.mesh.node_set("y0")
        cs.append(np.abs(np.einsum("ni,ni->n", res.final.g[y0, :3, 2], prob.mesh.g0[y0, :3, 0])).max())
    assert cs[0] < 1e-5 and cs[1] > 1e-4, cs


def test_rotation_component_spring_tangent_and_hold():
    """The diaphragm's theta_y = 0 (``diaphragm_theta_axis=1``, RotationComponentSpring: the lab
    y component of the total rotation vector log(R R0^T) held, as Abaqus applies UR2 = 0):
    tangent vs central differences on a 4x4 octant at random states with node rotations up to
    ~1 rad, relative 1e-6 (measured 2e-11 and 2e-10); on 8x8 to P = 0.06 P_max |c| < 1e-5 rad
    (penalty error M/k_r; measured 7.7e-8) while without it the component exceeds 1e-4 rad
    (measured 2.8e-4)."""
    case = get_case("sze-pinched-cylinder")
    p = catalogue.case_params(case, {"diaphragm_theta_axis": 1.0})
    prob = catalogue.build_problem(case, p, (4, 4))
    springs = [ld for ld in prob.loads if isinstance(ld, RotationComponentSpring)]
    assert len(springs) == 1
    rng = np.random.default_rng(1)
    for amp in (0.05, 0.5):
        g = prob.mesh.g0 @ lie.exp(amp * rng.standard_normal((prob.mesh.n_nodes, 6)))
        err, _, _ = verify.tangent_fd_check(prob, g, 0.5)
        assert err < 1e-6, (amp, err)
    cs = []
    for on in (1.0, 0.0):
        prob = catalogue.build_problem(case, catalogue.case_params(case, {"diaphragm_theta_axis": on}), (8, 8))
        res = C.arc_length(prob, lam_end=0.06, dlam0=0.02)
        probe = RotationComponentSpring(prob.mesh, prob.mesh.node_set("y0"), (0.0, 1.0, 0.0), 1.0)
        cs.append(np.abs(probe.component(res.final.g)).max())
    assert cs[0] < 1e-5 and cs[1] > 1e-4, cs


def test_pinched_cylinder_diaphragm_holds_before_the_snap():
    """8x8 octant to P = 0.06 P_max (before the first snap): at the diaphragm the radial and
    circumferential displacements are below 1e-4 of the deflection under the load (penalty
    error |F|/k), while the axial one is free (it moves by > 1e-2 of it)."""
    case = get_case("sze-pinched-cylinder")
    prob = catalogue.build_problem(case, catalogue.case_params(case), (8, 8))
    res = C.arc_length(prob, lam_end=0.06, dlam0=0.02)
    g = res.final.g
    y0 = prob.mesh.node_set("y0")
    g0 = prob.mesh.g0[y0]
    u = g[y0, :3, 3] - g0[:, :3, 3]
    wa = -res.final.probes["A"]["u"][2]
    assert wa > 10.0
    assert np.abs(np.einsum("ni,ni->n", u, g0[:, :3, 2])).max() < 1e-4 * wa
    assert np.abs(np.einsum("ni,ni->n", u, g0[:, :3, 0])).max() < 1e-4 * wa
    assert np.abs(u[:, 1]).max() > 1e-2 * wa


def test_hemisphere_linear_macneal_harder():
    """MacNeal-Harder: F = 2 (P = 2, half loads on the quarter) gives the radial deflection
    0.0924 under the loads; 8x8 quarter: 0.09146 (outward) and 0.09248 (inward), bar 2 %."""
    case = get_case("sze-hemisphere")
    prob = catalogue.build_problem(case, catalogue.case_params(case), (8, 8))
    res = C.arc_length(prob, lam_end=2.0 / 400.0, dlam0=2.0 / 400.0)
    assert abs(res.final.load_factor - 0.005) < 1e-14
    ua, ub = res.final.probes["A"]["u"][0], -res.final.probes["B"]["u"][1]
    assert abs(ua - 0.0924) < 0.02 * 0.0924 and abs(ub - 0.0924) < 0.02 * 0.0924, (ua, ub)


def test_hemisphere_8x8_curve():
    """Hemisphere 8x8 quarter, arc length to P_max = 400: deviation <= 5 % (measured 4.71 %;
    16x16 gives 1.47 %, inside the 3 % acceptance bar; the 8x8 quarter is ~4 % stiff at the
    end of this very large-rotation path)."""
    doc, res, prob = catalogue.run_case("sze-hemisphere", mesh=(8, 8))
    assert doc["reference"]["deviation"] <= 0.05, doc["reference"]["curves"]
    assert abs(doc["steps"][-1]["load_factor"] - 1.0) < 1e-12


def test_pullout_18x12_within_3_percent():
    """Pull-out, 18x12 octant (half the table mesh each way), arc length (psi = 1) to P_max:
    deviation <= 3 % over W_A, -U_B, -U_C (measured 2.67 %).  The snap-through: -U_B grows
    from the table's 3.653 to its 4.061 while P/P_max stays in [0.49, 0.53] (the table's jump
    lies between 0.50 and 0.525; measured: 3.647 at 0.496 to 4.062 at 0.509 in 12 arc-length
    steps through a limit point at 0.507; with the tied in-plane shear of curved elements the
    arc length took it in one step, 3.646 at 0.496 to 4.029 at 0.507)."""
    doc, res, prob = catalogue.run_case("sze-pullout", mesh=(18, 12))
    ref = doc["reference"]
    assert ref["deviation"] <= 0.03, ref["curves"]
    lam = np.array([s["load_factor"] for s in doc["steps"]])
    ub = np.array([-s["probes"]["B"]["u"][0] for s in doc["steps"]])
    i0 = int(np.nonzero(ub < 3.653)[0].max())                # the last step before the jump
    i1 = int(np.nonzero(ub > 4.0)[0].min())                  # the first one past it
    assert i1 > i0 and 0.49 <= lam[i0:i1 + 1].min() and lam[i0:i1 + 1].max() <= 0.53, (lam[i0:i1 + 1], ub[i0:i1 + 1])


def test_pinched_cylinder_16x16_curve():
    """Pinched cylinder, 16x16 octant (a third of the table mesh each way), arc length to
    P_max with the rigid diaphragm u_x = u_z = theta_y = 0: deviation <= 5 % over -W_A and U_B
    (measured 3.16 %, at P/P_max = 0.31; 3.79 % on 2026-12-01).  The bar is the coarse mesh's own
    error: the octant converges from the stiff side (U_B at P_max 33.59, 34.69, 35.03 on 16x16,
    24x24, 48x48; the table mesh 48x48 is within 2.20 % of the table, docs/PATHFOLLOWING.md), and
    the 16x16 offset from 48x48 is 1.44 / 34.27 = 4.2 % of u_max at P_max.  The path must snap past
    the first limit point (U_B turns from inward to outward, the table's sign change between
    P/P_max 0.15 and 0.175) and end at P_max.  Its limit points (8 measured, none on 24x24 and
    48x48) are the coarse mesh's snaps: the table's load rises monotonically, and the report says so."""
    doc, res, prob = catalogue.run_case("sze-pinched-cylinder", mesh=(16, 16))
    ref = doc["reference"]
    assert ref["deviation"] <= 0.05, ref["curves"]
    lam = np.array([s["load_factor"] for s in doc["steps"]])
    ub = np.array([s["probes"]["B"]["u"][0] for s in doc["steps"]])
    assert abs(lam[-1] - 1.0) < 1e-12
    assert ub[lam < 0.12].max() <= 0.0 and ub[-1] > 30.0, (ub[lam < 0.12].max(), ub[-1])
    crossing = lam[np.argmax(ub > 0.0)]
    assert 0.12 < crossing < 0.2, crossing
    from core_se3.catalogue.family_sze import report
    assert ref["monotonic"] and doc["critical_points"]
    assert [x for x in report(doc) if "no limit point" in x and "snaps of this discrete model" in x]


def test_rotation_component_spring_refuses_a_turn_near_pi():
    """Past 0.95 pi of total rotation (the principal log's cut is at pi) the spring raises
    ElementTooDistortedError naming the node, which the solvers treat as a rejected step."""
    from core_se3.errors import ElementTooDistortedError
    case = get_case("sze-pinched-cylinder")
    prob = catalogue.build_problem(case, catalogue.case_params(case), (4, 4))
    spring = [ld for ld in prob.loads if isinstance(ld, RotationComponentSpring)][0]
    g = prob.mesh.g0.copy()
    node = int(spring.nodes[1])
    g[node] = g[node] @ lie.exp(np.array([0.0, 0.0, 0.0, 0.96 * np.pi, 0.0, 0.0]))
    with pytest.raises(ElementTooDistortedError, match=f"node {node} has turned"):
        spring.evaluate(g, 1.0)
    g[node] = prob.mesh.g0[node] @ lie.exp(np.array([0.0, 0.0, 0.0, 0.9 * np.pi, 0.0, 0.0]))
    ev = spring.evaluate(g, 1.0)
    f, K = ev.f, ev.node_blocks
    assert np.all(np.isfinite(f)) and np.all(np.isfinite(K))
