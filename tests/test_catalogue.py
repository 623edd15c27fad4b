"""Catalogue cases against their references (issue 2 acceptance), through the same runner the
CLI uses.  Errors use the project's measure (core_se3/catalogue.py): max over the path of the
distance between computed and reference tip displacement / largest reference displacement.
References: core_se3/data/elastica.json, entries named in each case."""
import numpy as np
import pytest

from core_se3.catalogue import run_case


@pytest.mark.parametrize("follower", [0.0, 1.0])
def test_pressure_strip(follower):
    # 5_plate_cylindrical_bending_pressure_{dead,follower}; measured 0.073 % / 0.060 % on 16x1,
    # bar 0.5 % (the issue's); the discretisation error of 16 elements is ~1e-3 (h^2 rate)
    doc, _, _ = run_case("pressure-strip", overrides=dict(follower=follower))
    assert doc["reference"]["entry"].endswith("dead" if follower == 0 else "follower")
    assert doc["reference"]["error"] < 5e-3


def test_cantilever_steel_plate():
    # 1_cantilever_tip_force_seed_plate_nu0 (N, mm), PL^2/EI to 10 on 20x1: measured 0.040 %, bar 1 %
    doc, _, _ = run_case("cantilever-shear-steel")
    assert doc["reference"]["error"] < 1e-2


@pytest.mark.parametrize("k,steps", [(2.0, 16), (-1.0, 8)])
def test_curved_rollup_exact_circle(k, steps):
    # 4_arch_halfcircle_end_moment_R10over2pi is the closed-form circle of curvature 1/R + M/EI:
    # a constant commuting strain field, exact on any mesh whose elements turn by < pi, so the
    # tip must lie on it to Newton tolerance (bar 1e-6 L as in the issue; measured 3e-16)
    doc, res, prob = run_case("curved-rollup", mesh=(10, 1), steps=steps, overrides=dict(k=k),
                              rtol=1e-12, dtol=1e-12)
    p = {key: v["value"] for key, v in doc["params"].items()}
    EI = p["E"] * p["width"] * p["h"] ** 3 / 12
    R, s = p["R"], np.pi * p["R"]
    kap = 1 / R + k * 2 * np.pi * EI / 10.0 / EI
    tip = np.array([np.sin(kap * s) / kap, 0.0, (1 - np.cos(kap * s)) / kap]) if abs(kap) > 1e-12 \
        else np.array([s, 0.0, 0.0])
    u = np.array(doc["steps"][-1]["probes"]["tip"]["u"])
    assert np.linalg.norm(u - (tip - np.array([0.0, 0.0, 2 * R]))) < 1e-6 * s


def test_torsion_constant_between_mindlin_and_thin_plate():
    # 5_strip_torsion_seed_strip: Mindlin plate ks=1 6.41e-5 < J < thin plate w h^3/3 8.33e-5.
    # The Cosserat law penalises the skew curvature and the rigid end edge restrains warping,
    # both stiffening (see README); measured 7.62e-5 on 20x6.  A locking or mis-scaled twist
    # law would leave this bracket.
    from core_se3 import catalogue
    from core_se3.catalogue.references import elastica_entry
    e = elastica_entry("5_strip_torsion_seed_strip")["params"]
    J = catalogue.torsion_constant(catalogue.case_params(catalogue.get_case("torsion")), (20, 6))
    assert e["J_mindlin_ks=1"] < J < e["J_kirchhoff_plate=wh^3/3"]


def test_inplane_rollup_small_k_circle():
    # 2_pure_bending_rollup_inplane_drilling: circle of radius EI/M with the membrane in-plane
    # stiffness E h w^3/12 only.  The Cosserat drilling-curvature modulus (seed: D(1-nu)) adds
    # drilling * D(1-nu) w, which for this h = w strip equals E h w^3/12 at drilling = 1 (the
    # seed's value doubles the stiffness).  drilling = 0 leaves a seventh zero mode (checked
    # below), so the comparison uses 1 % of the seed's modulus: expected deviation <~ 1 %
    # (measured 0.48 % on 40x4 at k = 0.25); bar 1 % as the issue.
    from core_se3 import Material, Problem, mesh
    from core_se3.model import verify
    doc, _, _ = run_case("inplane-rollup", mesh=(40, 4), steps=5, overrides=dict(k=0.25, drilling=0.01))
    assert doc["reference"]["error"] < 1e-2
    p = Problem(mesh.rectangle(1.0, 1.0, 2, 2), Material(1200.0, 0.0, 1.0, drilling=0.0))
    assert verify.zero_modes(p)[1] == 7
    p = Problem(mesh.rectangle(1.0, 1.0, 2, 2), Material(1200.0, 0.0, 1.0, drilling=0.01))
    assert verify.zero_modes(p)[1] == 6


def test_reference_follows_the_parameters_or_is_not_compared():
    """A reference table is only compared where it holds (a silent wrong error otherwise):
    the roll-up circle depends on k = M L / (2 pi EI) alone, so with other E, h and L it is the
    same exact circle by similarity (error at round-off); a table computed for one physical
    section (cantilever-shear-steel's h = 10 mm) is not compared at another, and says why."""
    from core_se3.catalogue import run_case
    doc, _, _ = run_case("rollup", overrides=dict(k=0.5, h=0.001, E=3.0e6, L=7.0), steps=2)
    assert doc["reference"]["error"] < 1e-12
    doc, _, _ = run_case("cantilever-shear-steel", overrides=dict(h=5.0), steps=2)
    assert doc["reference"]["error"] is None and "h = 10" in doc["reference"]["note"]
    assert all(s.get("error") is None for s in doc["steps"])
    doc, _, _ = run_case("cantilever-shear-steel", steps=2)           # its own section: compared
    assert doc["reference"]["error"] < 5e-3
