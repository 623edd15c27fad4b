"""fenicsx_ref: half-circle arch (R = 0.5, clamp at the origin) under a follower tip force,
tangential (``arch-follower``) and toward the centre (``arch-follower --set direction=1``).

References (core_se3/data/elastica.json, Reissner rod with the shell's stiffnesses: EA = E w h,
kGA = EA/2 (nu = 0, k_s = 1), EI = E w h^3/12):
``4_arch_halfcircle_follower_tangential_plus_shell_ks1`` and
``4_arch_halfcircle_follower_normal_inward_shell_ks1``, P = 100 ... 3000 N (PL^2/EI to 20.6).
Error = the project measure (max over the 30 reference loads of |u - u_ref| / max |u_ref|).

Measured (Q2, PSRI):

    mesh          20x1     30x1     40x1     60x1     80x1     120x1    160x1
    tangential    4.7e-3   1.3e-3   5.2e-4   1.1e-3   1.5e-3   1.7e-3   1.7e-3
    inward        4.2e-3   6.4e-4   7.8e-4   1.7e-3   2.1e-3   2.3e-3   2.3e-3

The tangential tip rotation reaches 2.95 rad = 0.94 pi at P = 3000.  Near the 2-parameter map's
singularity at pi the out-of-plane stiffness falls as (sin|theta|/|theta|)^2 and the round-off floor
of the Newton increments rises with it (1e-10 at 2875 N); the Newton test is therefore also
|dx| < rtol |w| (solver.py), not only rtol |dx_1|, which cut-backs shrink below that floor.  With the
latter alone the tangential path was a coin flip of round-off (BLAS kernel, MUMPS ordering): 20x1
failed at 2910 N on one machine and passed on another, 40x1 failed at 2875 N, 80x1 at 2763 N.
The plateau under refinement, 1.7e-3 / 2.3e-3 at the largest
load, is the shell model against the rod (the Naghdi bending strain phi_,a . d_,b carries the
stretch: (1 + eps) kappa), not the mesh: full integration gives the same 2.3e-3 at 160x1.  The
coarser meshes' smaller errors are a cancellation of mesh and model error.  The bar 5e-3 sits
above the plateau and at half the project's 1 % scale.
"""
from math import pi

import dolfinx  # noqa: F401  -- must fail (not skip) without DOLFINx

from fenicsx_ref import run_case


def _check(r, entry):
    assert r["status"] == "ok"
    ref = r["reference"]
    assert ref["entry"] == entry and ref["n_points"] == 30
    assert abs(r["steps"][-1]["load"]["value"] - 3000.0) < 1e-9
    assert abs(r["steps"][-1]["probes"]["tip"]["rotation_angle"]) < pi
    return ref


def test_arch_follower_tangential_40x1(record_property):
    r = run_case("arch-follower", mesh=(40, 1))
    ref = _check(r, "4_arch_halfcircle_follower_tangential_plus_shell_ks1")
    record_property("error_tangential_40x1", ref["error"])
    print(f"arch-follower tangential 40x1: error {ref['error']:.3e}, theta {ref['theta_error_max']:.2e}")
    assert ref["error"] < 5e-3
    assert ref["theta_error_max"] < 1e-2


def test_arch_follower_inward_40x1(record_property):
    r = run_case("arch-follower", mesh=(40, 1), overrides={"direction": 1.0})
    ref = _check(r, "4_arch_halfcircle_follower_normal_inward_shell_ks1")
    record_property("error_inward_40x1", ref["error"])
    print(f"arch-follower inward 40x1: error {ref['error']:.3e}, theta {ref['theta_error_max']:.2e}")
    assert ref["error"] < 5e-3
    assert ref["theta_error_max"] < 1e-2
