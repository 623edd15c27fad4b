"""fenicsx_ref (DOLFINx Naghdi shell): cantilever-shear accuracy, locking, linear limit, Newton.

Reference: core_se3/data/elastica.json, entry ``1_cantilever_tip_force_kirchhoff`` (Kirchhoff
elastica master curve, PL^2/EI = 0..10 step 0.25, accurate to 1e-11) for every test here, via the
case definition ``core_se3.cases['cantilever-shear']`` (E = 1.2e6, nu = 0, h = 0.1, L = 10,
w = 1, P to 4, i.e. PL^2/EI to 4).

These tests need DOLFINx: the module imports it unconditionally, so a missing DOLFINx is a
collection error (a failure), never a skip.  The JIT cache is shared (see fenicsx_ref/README.md).

Numbers measured when the bars were chosen (Q2, DOLFINx 0.5.2; error = the project's measure,
max over the reference loads of |u - u_ref| / max |u_ref|):

    mesh    L/h    full        psri        small-load (PL^2/EI = 0.25) ratio v/v_ref full | psri
    4x1     100    4.04e-1     3.99e-3     0.9455 | 0.9988
    4x1     1000   8.43e-1     4.06e-3     0.4949 | 0.9987
    8x1     100    9.81e-2     6.77e-4     0.9935 | 0.9998
    8x1     1000   6.28e-1     7.47e-4     0.8351 | 0.9998
    16x1    100    9.49e-3     2.36e-5     0.9991 | 1.0000
    16x1    1000   2.78e-1     8.68e-5     0.9816 | 1.0000
    32x1    1000   4.75e-2     6.26e-6     0.9986 | 1.0000
"""
import numpy as np

import dolfinx  # noqa: F401  -- must fail (not skip) without DOLFINx
import dolfinx.fem.petsc

from core_se3.catalogue import beam_EI, get_case
from fenicsx_ref import run_case
from fenicsx_ref.reference import reference_entry

REF = "1_cantilever_tip_force_kirchhoff"
CASE = "cantilever-shear"


def _scaled(h, alpha_max):
    """Overrides for thickness h with the end load scaled to PL^2/EI = alpha_max."""
    p = dict(get_case(CASE).params, h=h)
    return dict(h=h, load_max=alpha_max * beam_EI(p) / p["L"] ** 2)


def _check_schema(r):
    assert r["schema"] == "core-se3-result" and r["version"] == 1 and r["model"] == "fenicsx_ref"
    for k in ("case", "variant", "params", "mesh", "steps", "timings", "reference"):
        assert k in r
    assert set(r["timings"]) >= {"setup", "jit", "assembly", "solve", "other"}
    s = r["steps"][-1]
    tip = s["probes"]["tip"]
    assert len(tip["u"]) == 3 and np.shape(tip["rotation"]) == (3, 3)
    R = np.array(tip["rotation"])
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert s["load"]["name"] == "P" and s["iterations"] > 0


def test_cantilever_shear_psri_16x1(record_property):
    """Acceptance: cantilever-shear with PSRI, error <= 1 % up to P = 4 (PL^2/EI = 4).

    16x1 Q2 gives 2.4e-5; the bar 1e-3 keeps a 40x margin but stays far below the 1 %
    acceptance.  (The shell is shear-deformable, the reference Kirchhoff: at L/h = 100 the two
    differ by ~1e-4 of v, so a bar much below 1e-4 would test the model, not the mesh.)"""
    r = run_case(CASE, mesh=(16, 1), integration="psri")
    _check_schema(r)
    assert r["status"] == "ok"
    ref = r["reference"]
    assert ref["entry"] == REF
    assert ref["n_points"] == 16  # PL^2/EI = 0.25 ... 4
    assert abs(r["steps"][-1]["load"]["value"] - 4.0) < 1e-12
    record_property("error_psri_16x1", ref["error"])
    print(f"cantilever-shear psri 16x1: error {ref['error']:.3e}, timings {r['timings']}")
    assert ref["error"] <= 1e-3
    # the tip rotation follows the reference too (|theta - theta_ref| in rad)
    assert ref["theta_error_max"] < 1e-3


def test_locking_full_vs_psri_Lh1000(record_property):
    """L/h = 1000 (h = 0.01), end load scaled to the same PL^2/EI (to 4), on the same 16x1 mesh.

    Measured: full integration error 0.278 (membrane locking of the bent Q2 strip; issue bar
    'above 10 %'), PSRI 8.7e-5 (bar 'below 2 %')."""
    ov = _scaled(0.01, 4.0)
    errs = {}
    for integ in ("full", "psri"):
        r = run_case(CASE, mesh=(16, 1), overrides=ov, integration=integ)
        assert r["status"] == "ok" and r["reference"]["entry"] == REF
        errs[integ] = r["reference"]["error"]
        record_property(f"error_{integ}_Lh1000_16x1", errs[integ])
    print(f"L/h=1000, 16x1: full {errs['full']:.3e}  psri {errs['psri']:.3e}")
    assert errs["full"] > 0.10
    assert errs["psri"] < 0.02
    assert errs["psri"] < 1e-3  # what 16x1 actually gives (8.7e-5)


def test_shear_locking_small_load_coarse(record_property):
    """Small load PL^2/EI = 0.25 (a reference load of REF), L/h = 1000, coarse 4x1 mesh:
    full integration is far too stiff (measured v/v_ref = 0.495; bar < 0.6), PSRI is within
    a few 1e-3 (measured 0.9987).  At L/h = 100 the same mesh gives 0.946 (full): the stiffening
    grows with L/h, i.e. it is locking, not plain discretisation error."""
    e = reference_entry(REF)
    v_ref = e["tip"]["v"][e["load"].index(0.25)] * get_case(CASE).params["L"]
    ratios = {}
    for h in (0.1, 0.01):
        for integ in ("full", "psri"):
            r = run_case(CASE, mesh=(4, 1), overrides=_scaled(h, 0.25), steps=1, integration=integ)
            ratios[(h, integ)] = r["steps"][-1]["probes"]["tip"]["u"][2] / v_ref
            record_property(f"ratio_{integ}_h{h}_4x1", ratios[(h, integ)])
    print("small-load ratios v/v_ref (4x1):", ratios)
    assert ratios[(0.01, "full")] < 0.6
    assert ratios[(0.01, "full")] < ratios[(0.1, "full")] - 0.3
    for h in (0.1, 0.01):
        assert abs(ratios[(h, "psri")] - 1.0) < 5e-3


def test_linear_limit_timoshenko():
    """PL^2/EI = 1e-3: the tip deflection and rotation match the exact linear Timoshenko
    cantilever, v = PL^3/(3EI) + PL/(k G h w), theta = PL^2/(2EI), for k = 1 and 5/6.
    Measured (16x1 PSRI): v -2.7e-5 (k=1) / -2.2e-5 (k=5/6) relative, theta -9e-8."""
    p = dict(get_case(CASE).params)
    EI, G = beam_EI(p), p["E"] / 2.0
    P = 1e-3 * EI / p["L"] ** 2
    for ks in (1.0, 5.0 / 6.0):
        r = run_case(CASE, mesh=(16, 1), overrides=dict(load_max=P), steps=1, shear_factor=ks,
                     include_reference_loads=False)
        tip = r["steps"][-1]["probes"]["tip"]
        v_lin = P * p["L"] ** 3 / (3 * EI) + P * p["L"] / (ks * G * p["h"] * p["width"])
        assert abs(tip["u"][2] / v_lin - 1) < 1e-4
        assert abs(tip["rotation_angle"] / (P * p["L"] ** 2 / (2 * EI)) - 1) < 1e-5
        assert abs(tip["u"][1]) < 1e-12


def test_newton_consistent_tangent_and_rate():
    """Quadratic convergence rests on the Jacobian being the exact derivative of the residual:
    Taylor test at a large-deflection state (PL^2/EI = 2), |F(w + e d) - F(w) - e J d| = O(e^2)
    (exercises the Rodrigues series/closed-form branches).  And every load step of the path
    converges in a handful of iterations without cut-backs."""
    r, st = run_case(CASE, mesh=(8, 1), overrides=_scaled(0.1, 2.0), steps=4,
                     include_reference_loads=False, return_state=True)
    assert r["status"] == "ok"
    assert all(s["iterations"] <= 10 and s["cutbacks"] == 0 for s in r["steps"])
    model, L, a = st["model"], st["L"], st["a"]
    w = model.w
    w0 = w.x.array.copy()
    rng = np.random.default_rng(0)
    d = rng.standard_normal(w0.shape) * 1e-2

    def F():
        b = dolfinx.fem.petsc.assemble_vector(L)
        return b.array.copy()

    F0 = F()
    A = dolfinx.fem.petsc.assemble_matrix(a)
    A.assemble()
    x, y = A.createVecs()
    x.array[:] = d
    A.mult(x, y)
    Jd = y.array.copy()
    rem = []
    eps = [1e-1, 5e-2, 2.5e-2, 1.25e-2]
    for e in eps:
        w.x.array[:] = w0 + e * d
        rem.append(np.linalg.norm(F() - F0 - e * Jd))
    w.x.array[:] = w0
    rates = np.log(np.array(rem[:-1]) / np.array(rem[1:])) / np.log(2.0)
    print("Taylor remainders", rem, "rates", rates)
    assert np.all(rates > 1.9), rates


def test_point_load_matches_edge_load():
    """A dead point force P e_z at the tip node (added to the assembled residual) gives the same
    tip displacement as the case's uniform edge shear of the same total (nu = 0, 16x1): measured
    6e-5 relative (the local 2-D spreading near the point), bar 1e-3."""
    a = run_case(CASE, mesh=(16, 1), load_factors=[0.25, 0.5, 0.75, 1.0])
    P = get_case(CASE).params["load_max"]
    b = run_case(CASE, mesh=(16, 1), overrides=dict(load_max=0.0), load_factors=[0.25, 0.5, 0.75, 1.0],
                 point_loads=[((get_case(CASE).params["L"], 0.0), (0.0, 0.0, P))])
    assert a["status"] == b["status"] == "ok"
    ua, ub = (np.array(r["steps"][-1]["probes"]["tip"]["u"]) for r in (a, b))
    assert np.linalg.norm(ua - ub) / np.linalg.norm(ua) < 1e-3


def test_triangles_p2_cantilever(record_property):
    """P2 on triangles (each cell of the nx x ny grid split in two): cantilever-shear to
    PL^2/EI = 4.  Measured (error = project measure):

        L/h    mesh   psri      full        (re-measured at ba3fb16)
        100    16x1   6.8e-4    6.8e-3
        100    32x1   3.2e-5
        1000   16x1   2.3e-2    0.22
        1000   32x1   9.1e-4    3.2e-2
        1000   64x1   4.3e-5

    Plain P2 locks more than Q2 (no bubble enrichment, unlike FEniCSx-Shells' P2+B3), so PSRI needs
    about twice the elements along the strip; on 32x1 it meets the 1 % acceptance at both
    slendernesses (bars 1e-3 and 5e-3) while full integration at L/h = 1000 stays > 2 % and
    > 10x the PSRI error."""
    r = run_case(CASE, mesh=(32, 1), cell="triangle")
    assert r["status"] == "ok" and r["mesh"]["cell"] == "triangle" and r["reference"]["entry"] == REF
    record_property("error_tri_psri_Lh100_32x1", r["reference"]["error"])
    assert r["reference"]["error"] < 1e-3
    errs = {}
    for integ in ("psri", "full"):
        r = run_case(CASE, mesh=(32, 1), overrides=_scaled(0.01, 4.0), integration=integ, cell="triangle")
        assert r["status"] == "ok"
        errs[integ] = r["reference"]["error"]
        record_property(f"error_tri_{integ}_Lh1000_32x1", errs[integ])
    print(f"P2 triangles 32x1, L/h = 1000: psri {errs['psri']:.3e}, full {errs['full']:.3e}")
    assert errs["psri"] < 5e-3
    assert errs["full"] > 2e-2 and errs["full"] > 10 * errs["psri"]
