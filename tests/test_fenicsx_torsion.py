"""fenicsx_ref: ``torsion`` -- the strip (L = 1, w = 0.25, h = 0.1, nu = 0.3) clamped on x0, its end
edge x1 rotated rigidly about the strip axis (prescribed u_y, u_z and rotation vector, u_x free).

Reference: core_se3/data/elastica.json ``5_strip_torsion_seed_strip``, 'J_mindlin_ks=1' =
6.4095e-5 = (w h^3/3)[1 - tanh(a w/2)/(a w/2)], a = sqrt(12 k_s)/h: the Saint-Venant torsion
constant of a Reissner-Mindlin plate strip with shear factor 1 (ELASTICA.md).

J = T L/(G angle) from the end torque T at small twist is NOT that constant on this strip: the
clamp and the rigid end edge both hold the rotation about the width axis (beta_2) at zero, which
free twist wants to be -tau y (the plate's "warping"), so each end adds a restrained layer and J
exceeds the Saint-Venant value by c/L.  Measured (Q2 PSRI, small twist 1e-4 rad):

    mesh / L            J / J_ref   J_interior / J_ref (twist rate between s = 0.4 L and 0.6 L)
    10x3   / 1          1.0865      1.0057
    20x6   / 1          1.0815      1.0016
    40x12  / 1          1.0806      1.0009
    80x24  / 1          1.0805      1.0008     (stations 0.3/0.7 L: 1.0023; 0.25/0.75 L: 1.0043)
    40x6   / 2          1.0396
    80x6   / 4          1.0198      -> Richardson 2 J(4) - J(2) = 1.00001 J_ref
    160x6  / 8          1.0102

so J - J_ref = 0.080 J_ref / L (end layers), and the plate constant itself is reproduced to 1e-5.
Large twist: the rotation vector has 2 components, so the path stops below pi: the case's 24 steps
of pi/8 are followed to 7 pi/8 (the 8th step, pi, is dropped and recorded).
"""
from math import pi

import numpy as np

import dolfinx  # noqa: F401  -- must fail (not skip) without DOLFINx
import dolfinx.fem.petsc

from core_se3.catalogue import get_case
from core_se3.catalogue.references import elastica_entry
from fenicsx_ref import run_case
from fenicsx_ref.solver import torsion_constant

J_REF = elastica_entry("5_strip_torsion_seed_strip")["params"]["J_mindlin_ks=1"]


def _clamp_moment(model, L_form):
    """Moment about the x axis that the shell exerts on the clamp x0 (r . delta w of a virtual
    rigid rotation about x: delta u = e_x x X = (0, 0, y) on the flat edge, delta beta_1 = 1)."""
    b = dolfinx.fem.petsc.assemble_vector(L_form)
    r = b.array.copy()
    T = 0.0
    for comp in ("uz", "beta1"):
        _, _, dV, _, X = model.component_bc("x0", comp)
        T += float(r[dV] @ (X[:, 1] if comp == "uz" else np.ones(len(dV))))
    return T


def test_torsion_small_twist_constant(record_property):
    """Small twist on the case's 20x6 mesh.  Bars: the interior (Saint-Venant) constant within
    0.5 % of J_mindlin_ks=1 (measured +0.16 %; +0.08 % converged, the tail of the end layers at
    the stations); the end-to-end J = T L/(G angle) carries the end restraint: 1.06 .. 1.10 J_ref
    (measured 1.0815); with L doubled and quadrupled (same element size) its excess scales as 1/L
    and the Richardson extrapolation 2 J(4) - J(2) recovers J_ref within 0.2 % (measured 1e-5).
    The end torque and the clamp moment balance (the reaction is computed consistently)."""
    case = get_case("torsion")
    d = torsion_constant(mesh=(20, 6))
    J, Ji = d["J"], d["J_interior"]
    record_property("J_over_Jref_20x6", J / J_REF)
    record_property("J_interior_over_Jref_20x6", Ji / J_REF)
    print(f"torsion 20x6: J = {J:.5e} ({J / J_REF:.4f} J_ref), interior {Ji:.5e} ({Ji / J_REF:.5f})")
    assert abs(Ji / J_REF - 1) < 5e-3
    assert 1.06 < J / J_REF < 1.10
    J2 = torsion_constant(mesh=(40, 6), overrides={"L": 2.0})["J"]
    J4 = torsion_constant(mesh=(80, 6), overrides={"L": 4.0})["J"]
    excess = [J / J_REF - 1, J2 / J_REF - 1, J4 / J_REF - 1]
    print("excess over J_ref for L = 1, 2, 4:", excess, "Richardson", (2 * J4 - J2) / J_REF)
    assert 0.45 < excess[1] / excess[0] < 0.55 and 0.45 < excess[2] / excess[1] < 0.55
    assert abs((2 * J4 - J2) / J_REF - 1) < 2e-3
    # moment balance between the two ends (at the small-twist state)
    r, st = run_case("torsion", mesh=(20, 6), load_factors=[1e-4 / case.params["angle"]],
                     include_reference_loads=False, rtol=1e-12, return_state=True)
    T = r["steps"][-1]["reactions"][0]["moment_about_axis"]
    assert abs(_clamp_moment(st["model"], st["L"]) + T) < 1e-8 * abs(T)


def test_torsion_large_twist_to_valid_angle(record_property):
    """The case path (24 steps of pi/8 toward 3 pi) is followed to 7 pi/8, the last angle below
    the 2-parameter rotation's singularity; the drop is recorded.  The end edge is exactly at the
    prescribed rotation; the torque grows monotonically and stiffens (Wagner effect: fibres off
    the axis become helices and stretch): at 7 pi/8 the secant stiffness is 3.5 % above the
    small-twist one (bar 1 % .. 8 %; the thin-strip Wagner estimate E w^5 h tau^2 / (360 G J),
    +7.7 %, is an upper guide: this strip is thick, w/h = 2.5, and its axial warping is held at
    the clamp).  At the largest twist the two ends' moments balance only to the discretisation
    error: interpolating rotation vectors is not objective (and a superposed rigid rotation needs
    a drilling component this model lacks), so a virtual rigid rotation is not exactly in the
    discrete space.  Measured imbalance 1.9e-2 / 2.9e-3 / 3.4e-4 on 10x3 / 20x6 / 40x12
    (O(h^3)); bar 1e-2 on 20x6.  (At small twist it is 1e-8-exact: see the test above.)"""
    case = get_case("torsion")
    p = case.params
    r, st = run_case("torsion", mesh=(20, 6), return_state=True)
    assert r["status"] == "ok"
    assert "reference_truncated_at" in r["options"]
    angles = [s["reactions"][0]["angle"] for s in r["steps"]]
    assert np.allclose(angles, [k * pi / 8 for k in range(1, 8)], atol=1e-12)
    for s, a in zip(r["steps"], angles):
        tip = s["probes"]["tip"]
        assert abs(tip["rotation_angle"] + a) < 1e-10 or abs(tip["rotation_angle"] - a) < 1e-10
        R = np.array(tip["rotation"])
        assert np.allclose(R, [[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]],
                           atol=1e-10)
    T = np.array([s["reactions"][0]["moment_about_axis"] for s in r["steps"]])
    assert np.all(np.diff(T) > 0)
    G = p["E"] / (2 * (1 + p["nu"]))
    J0 = torsion_constant(mesh=(20, 6))["J"]
    k_lin = G * J0 / p["L"]
    stiffening = T[-1] / (k_lin * angles[-1]) - 1
    record_property("secant_stiffening_7pi_8", stiffening)
    print(f"torsion 20x6: T(7 pi/8) = {T[-1]:.4f}, secant stiffening {stiffening:.4f}; "
          f"tip u_x {r['steps'][-1]['probes']['tip']['u'][0]:.5f}; timings {r['timings']}")
    assert 0.01 < stiffening < 0.08
    assert np.all(np.diff(T / np.array(angles)) > 0)
    imbalance = abs(_clamp_moment(st["model"], st["L"]) + T[-1]) / abs(T[-1])
    record_property("moment_imbalance_7pi_8", imbalance)
    assert imbalance < 1e-2
