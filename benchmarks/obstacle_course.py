#!/usr/bin/env python3
"""The shell obstacle course of the default element (issue 30), linear analysis
(``Problem.solve_linear``), with Kratos' thick and thin corotational quads on the same meshes
and the same nodal loads where a Kratos venv is given.

* patch tests (``catalogue.patch_tests``): membrane, bending, drilling on MacNeal and Harder's
  patch and on 100 random convex 3x3 patches;
* the standard cases (``catalogue.shell_course``) at their usual meshes, against the published
  values: Scordelis-Lo roof, pinched cylinder, pinched hemisphere, twisted beam, Raasch hook
  (Cosserat and classical law), Cook's membrane;
* thickness sweeps of the roof and the hemisphere, R/h = 10 ... 1e5 at 2x2 ... 16x16, each
  divided by the 64x64 value of the same element at the same thickness.

    .venv/bin/python benchmarks/obstacle_course.py [--kratos /path/to/kratos-venv/bin/python]

Writes ``benchmarks/results/obstacle_course.{md,json}``.
"""
from __future__ import annotations

import argparse
import datetime
import json
import subprocess
import sys
import time
import types
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
RESULTS = ROOT / "benchmarks" / "results"

from core_se3 import Material                                  # noqa: E402
from core_se3.catalogue import patch_tests as pt               # noqa: E402
from core_se3.catalogue import shell_course as sc              # noqa: E402
from core_se3.errors import AccuracyWarning                    # noqa: E402
from core_se3.mesh import generators as mesh_generators        # noqa: E402

REF = sc.REFERENCES
NOTES = """## Reading

* Patch tests: the membrane-drilling correction (`core_se3/fem/membrane_drilling.py`) is what
  passes the membrane and drilling tests on distorted quads; before it MacNeal and Harder's patch
  gave 2.5 (membrane and drilling) and 30 random patches 1.24 (the bending test passed).  The
  least-turn gauge of the nodal frames (`core_se3/mesh/gauge.py`) is what passes them with frames
  turning about the normal from node to node (before it: 7e-2 with random turns up to 0.1 rad).
* Kept: the membrane-drilling correction and the in-plane shear of curved elements toward its
  element mean (`core_se3/fem/membrane_shear.py`, the part beta = (1 + 12 chi^2)^-1/2 of the
  tied variation kept, chi = phi L / h): the hemisphere's coarse thin meshes no longer lock
  (4x4 at R/h 1e4 / 1e5: 0.626 / 0.017 -> 0.980 / 0.979; the whole hemisphere sweep within 0.8
  ... 1.02), flat elements are unchanged to the bit, the roof is unchanged. The candidate
  remedies' table was measured on the element before it ("as kept (none)" is that element):
  raising the drilling modulus (x 100) leaves the roof's coarse-mesh flexibility where it is and
  locks the hemisphere further; weakening the skew membrane coupling (x 0.01) eases the
  hemisphere's locking (4x4 at R/h 1e4: 0.626 -> 0.814) and leaves the roof unchanged; a
  membrane-order stiffness of the drilling hourglass (the nodal pattern the edge means do not
  see) stiffens the roof at moderate R/h (3x3 at 1e3: 1.030 -> 0.584) and locks the
  hemisphere. Enhanced strains were not measured here; `benchmarks/results/roof_modes.md` has
  the roof's mechanism and the later candidates (Hughes-Brezzi, facet shear, OpenSees' quads).
* What the coarse-mesh roof does (linear energy split at the linear solution, R/h 1e5): 2x2 puts
  99.96 % of its energy in bending, 64x64 63 % in the membrane -- an inextensional mechanism of
  the coarse mesh with (almost) no drilling energy (0.03 %); the eigenvectors of the softest
  modes are the free edge's normal displacement with the in-plane rotations that keep every
  edge twist's translation unchanged (the element ties 3 translational strain components per
  edge: about 6 per node against 6 dofs per node): n free-edge mechanisms on the n x n roof, the
  same for MITC4+'s tying set (`roof_modes.py`, docs/ELEMENTS.md). The thin hemisphere at 4x4
  (R/h 1e4) locked, before membrane_shear, with 37 % of its energy in the membrane (15 % in the
  skew part), 0.1 % at 64x64.
* Kept since: Simo and Rifai's four enhanced membrane modes condensed per element
  (`core_se3/fem/membrane_enhanced.py`): Cook 2x2 / 4x4 0.765 / 0.919 -> 0.834 / 0.947 (Kratos
  thick 0.787 / 0.919), the twisted beam's out-of-plane load 0.9745 -> 0.9774, the cylinder 8x8
  0.803 -> 0.805; the roof (nu = 0) unchanged, the sweeps within 0.01 (hemisphere 6x6 at R/h
  1e5 0.826 -> 0.836), the patch tests unchanged (<= 3e-11). The sweeps, the standard cases and
  the patch tests above are of this element; the candidate remedies' table is of the element
  before membrane_shear (see above).
* Like for like (the last section; each variant divided by its own 64x64 value, Kratos by its
  own 64x64 run): the classical law moves the coarse meshes by less than 1 % (cylinder 8x8
  0.801 -> 0.805, hemisphere R/h 10 4x4 0.926 -> 0.920), so the Cosserat law is not what
  separates core_se3 from Kratos' thick quad. Kratos is closer to its converged value on the
  cylinder (8x8 / 16x16: 0.852 / 0.977 against 0.801 / 0.940), the roof 8x8 (1.006 against
  0.990) and the thick hemisphere 4x4 (0.946 against 0.926: below the issue's 0.95 itself);
  core_se3 is closer on the roof 4x4 (0.971 against 1.034), Cook, the twisted beam and every
  thin hemisphere. No strain measure carries the cylinder's gap alone: taken at its element
  mean (a one-point measure, hourglass-prone, not a remedy), the normal membrane strains give
  8x8 0.827, bending 0.821, transverse shear 0.798; enhanced bending modes (Simo-Rifai's four
  on the curvature) 0.807, and on the thick hemisphere 4x4 0.934.
* Kratos' thick quad on the same meshes and nodal loads: stiffer than core_se3 on the roof at
  R/h 10 (4x4 0.989 vs 0.969) and at 4x4 ... 16x16 of the standard roof and cylinder, far more
  flexible on the thin coarse roofs (2x2 at 1e5: 464 vs 110) and locked on every thin hemisphere.
* Convergence to 128x128 and the shear stabilisation (the last two sections; docs/ELEMENTS.md):
  Kratos' thick quad scales its shear modulus by h^2 / (h^2 + 0.1 L^2) (Lyly, Stenberg and
  Vihinen 1993), which is what makes it converge from above and faster on the cylinder, the roof
  and flat plates. core_se3 has it as an option (alpha = 0.1: cylinder 8x8 / 16x16 0.943 / 0.987
  of its own 128x128 value against Kratos' 0.850 / 0.976), not as the default: it breaks the thin
  sweeps (hemisphere up to 1.051, roof 16x16 at R/h 1e5 1.124). The thick hemisphere's point
  load has no converged value (its increments per mesh halving tend to Reissner-Mindlin's
  P ln 2 / (pi k G h)); the spread-load row is its well-posed version.
"""
SWEEP_MESHES = (2, 3, 4, 6, 8, 12, 16)
SWEEP_RH = (10.0, 1e2, 1e3, 1e4, 1e5)


# ------------------------------------------------------------------ Kratos -----------------
def kratos_model(p, elem):
    """The JSON model of ``kratos_linear.py``: nodes, quads, lab-frame fixed dofs (the body
    dofs a support holds must be lab axes), the nodal forces and moments core_se3 applies."""
    g0 = p.mesh.g0
    R0 = g0[:, :3, :3]
    mask = p.constraint_mask()
    fixed = np.zeros((len(g0), 6), bool)
    for i in range(len(g0)):
        for part in (0, 3):
            dirs = R0[i][:, mask[i, part:part + 3]]
            for a in range(3):
                if dirs.shape[1] and np.linalg.norm(dirs.T @ np.eye(3)[a]) > 1 - 1e-9:
                    fixed[i, part + a] = True
            if fixed[i, part:part + 3].sum() != mask[i, part:part + 3].sum():
                raise ValueError(f"node {i}: the held body dofs are not lab axes")
    f = p.external(g0, 1.0, tangent=False)[0]
    mat = p.material
    return dict(element=elem, E=mat.E, nu=mat.nu, h=mat.h, X=p.mesh.X.tolist(), quads=p.mesh.quads.tolist(),
                fixed=fixed.tolist(), force=np.einsum("nij,nj->ni", R0, f[:, :3]).tolist(),
                moment=np.einsum("nij,nj->ni", R0, f[:, 3:]).tolist())


def kratos_solve(python, p, elem):
    """A Result-like object (steps[0].g, final.g) of Kratos' linear solution."""
    return peer_solve(python, "kratos_linear.py", p, elem)


def peer_solve(python, script, p, elem):
    """A Result-like object (steps[0].g, final.g) of a peer's linear solution: ``script`` in
    benchmarks/ run by ``python`` on the model of :func:`kratos_model`, printing RESULT {"u"}."""
    out = subprocess.run([python, str(ROOT / "benchmarks" / script)],
                         input=json.dumps(kratos_model(p, elem)), capture_output=True, text=True)
    for line in out.stdout.splitlines():
        if line.startswith("RESULT "):
            g = p.mesh.g0.copy()
            g[:, :3, 3] += np.array(json.loads(line[7:])["u"])
            return types.SimpleNamespace(steps=[types.SimpleNamespace(g=p.mesh.g0)],
                                         final=types.SimpleNamespace(g=g))
    raise RuntimeError(out.stderr[-2000:])


def measure(build, kratos, *args, **kw):
    """{'core_se3': value, 'kratos thick': ..., 'kratos thin': ...} of one case."""
    p, meas = build(*args, **kw)
    out = {"core_se3": meas(p.solve_linear())}
    if kratos and "material" not in kw:
        for e in ("thick", "thin"):
            try:
                out[f"kratos {e}"] = meas(kratos_solve(kratos, p, e))
            except (RuntimeError, ValueError) as exc:
                out[f"kratos {e}"] = None
                print(f"kratos {e} failed: {str(exc)[-200:]}", file=sys.stderr)
    return out


# ------------------------------------------------------------------ parts ------------------
def patches(n_random=100):
    mesh, bnd = pt.mh_patch()
    out = {"MacNeal-Harder": {k: pt.patch_test(mesh, bnd, k) for k in pt.PATCH_FIELDS}}
    rng = np.random.default_rng(30)
    worst = dict.fromkeys(pt.PATCH_FIELDS, 0.0)
    for _ in range(n_random):
        m, b = pt.random_patch(rng)
        for k in pt.PATCH_FIELDS:
            worst[k] = max(worst[k], pt.patch_test(m, b, k))
    out[f"{n_random} random convex 3x3"] = worst
    # the nodal frames turned about the normal (docs/ELEMENTS.md "Nodal frames"): the element's
    # least-turn gauge makes them parallel, so the tests stay exact whatever the turns (before
    # the gauge they failed in proportion to the turn: 7e-2 at 0.1 rad)
    out["MacNeal-Harder, frames turned alike by 0.3 rad"] = {
        k: pt.patch_test(pt.turned_frames(mesh, np.full(mesh.n_nodes, 0.3)), bnd, k) for k in pt.PATCH_FIELDS}
    worst = dict.fromkeys(pt.PATCH_FIELDS, 0.0)
    for _ in range(n_random):
        m, b = pt.random_patch(rng)
        m = pt.turned_frames(m, rng.uniform(-1.0, 1.0, m.n_nodes))
        for k in pt.PATCH_FIELDS:
            worst[k] = max(worst[k], pt.patch_test(m, b, k))
    out[f"{n_random} random convex 3x3, frames turned at random by up to 1 rad"] = worst
    for amp in (1e-3, 1e-2, 0.1, 1.0):
        turned = pt.turned_frames(mesh, np.random.default_rng(1).uniform(-amp, amp, mesh.n_nodes))
        out[f"MacNeal-Harder, frames turned at random by up to {amp:g} rad"] = {
            k: pt.patch_test(turned, bnd, k) for k in pt.PATCH_FIELDS}
    for n in (3, 6, 12):
        a = mesh_generators.annulus(6.0, 10.0, 1.0, n, n)
        ab = np.unique(np.concatenate([a.node_set(e) for e in ("x0", "x1", "y0", "y1")]))
        out[f"annulus sector of 1 rad {n}x{n}, the generator's radial frames"] = {
            k: pt.patch_test(a, ab, k) for k in pt.PATCH_FIELDS}
    return out


def standard(kratos):
    rows = []

    def add(case, mesh, ref, build, *a, **kw):
        t = time.perf_counter()
        v = measure(build, kratos, *a, **kw)
        rows.append(dict(case=case, mesh=mesh, ref=ref, values={k: (None if x is None else x / ref) for k, x in v.items()}))
        print(case, mesh, {k: None if x is None else round(x, 4) for k, x in rows[-1]["values"].items()},
              f"{time.perf_counter() - t:.1f} s", flush=True)

    for n in (4, 8, 16):
        add("Scordelis-Lo roof", f"{n}x{n}", REF["scordelis-lo"], sc.scordelis_lo, n)
    for n in (4, 8, 16):
        add("pinched hemisphere", f"{n}x{n}", REF["pinched-hemisphere"], sc.pinched_hemisphere, n)
    for n in (8, 16, 32):
        add("pinched cylinder", f"{n}x{n}", REF["pinched-cylinder"], sc.pinched_cylinder, n)
    add("twisted beam, in-plane load", "12x2", REF["twisted-beam-in-plane"], sc.twisted_beam, "in-plane")
    add("twisted beam, out-of-plane load", "12x2", REF["twisted-beam-out-of-plane"], sc.twisted_beam, "out-of-plane")
    add("Raasch hook", "96x32", REF["raasch-hook"], sc.raasch_hook, 96, 32)
    add("Raasch hook, classical law", "96x32", REF["raasch-hook"], sc.raasch_hook, 96, 32,
        material=Material.classical_shell(3300.0, 0.35, 2.0))
    for n in (2, 4, 8, 16, 32):
        add("Cook's membrane", f"{n}x{n}", REF["cook-membrane"], sc.cook_membrane, n)
    return rows


def sweeps(kratos):
    out = {}
    for case, build, R in (("Scordelis-Lo roof", sc.scordelis_lo, 25.0), ("pinched hemisphere", sc.pinched_hemisphere, 10.0)):
        for rh in SWEEP_RH:
            h = R / rh
            p, meas = build(64, h=h)
            with warnings.catch_warnings():        # its AccuracyWarning: reported below the table
                warnings.simplefilter("ignore", AccuracyWarning)
                res = p.solve_linear()
            conv, accuracy = meas(res), res.log[-1]["error_estimate"]
            row = {}
            for n in SWEEP_MESHES:
                v = measure(build, kratos, n, h=h)
                row[n] = {k: (None if x is None else x / conv) for k, x in v.items()}
            out[f"{case}|{rh:g}"] = dict(converged=conv, converged_error=accuracy, ratios=row)
            print(case, rh, {n: round(r["core_se3"], 3) for n, r in row.items()}, flush=True)
    return out


# ------------------------------------------------------------------ candidate remedies -----
class SkewLaw(Material):
    """Candidate: the membrane law's skew part (the drilling rotation's coupling with the
    in-plane rotation, 2 G h) scaled by ``skew`` (a frozen dataclass field set after init)."""

    def resultant_matrix(self, A1, A2):
        from core_se3.fem.material import strain_operators
        D, j0 = super().resultant_matrix(A1, A2)
        (Mm, _, _, _), Ainv, _ = strain_operators(A1, A2)
        W = np.array([[0, 0, 0, 0], [0, .5, -.5, 0], [0, -.5, .5, 0], [0, 0, 0, 0.]]) @ Mm
        skew = (1 - self.nu) * np.einsum("...ac,...bd->...abcd", Ainv, Ainv).reshape(Ainv.shape[:-2] + (4, 4))
        return D + (self.skew - 1.0) * self.C * (np.swapaxes(W, -1, -2) @ skew @ W), j0


def hourglass_element(alpha):
    """Candidate: a membrane-order stiffness alpha G h A on the drilling hourglass (the nodal
    drilling pattern orthogonal to constant and linear fields, Flanagan-Belytschko's gamma, which
    the edge means do not see), written on the edges' drilling components (a Hughes-Brezzi-type
    coupling of the mode the membrane strain misses)."""
    from core_se3.fem import element_default as ed
    from core_se3.fem.membrane_drilling import reference_G

    class Hourglass(ed.DefaultElement):
        name = f"hourglass-{alpha:g}"

        def __init__(self, mesh, material):
            super().__init__(mesh, material)
            D = reference_G(mesh, ed.edge_twists(mesh.g0, mesh.edge_nodes))[:, 5::6, 5::6]
            X = mesh.X[mesh.quads]
            e1 = X[:, 1] + X[:, 2] - X[:, 0] - X[:, 3]
            e2 = X[:, 2] + X[:, 3] - X[:, 0] - X[:, 1]
            e1 /= np.linalg.norm(e1, axis=1)[:, None]
            e2 -= np.einsum("mi,mi->m", e2, e1)[:, None] * e1
            e2 /= np.linalg.norm(e2, axis=1)[:, None]
            Xc = X - X.mean(1)[:, None]
            Q = np.linalg.qr(np.stack([np.ones(X.shape[:2]),
                                       np.einsum("mki,mi->mk", Xc, e1), np.einsum("mki,mi->mk", Xc, e2)], -1))[0]
            h = np.array([1.0, -1.0, 1.0, -1.0])
            gam = h - np.einsum("mij,mkj,k->mi", Q, Q, h)
            gam /= np.einsum("mi,i->m", gam, h)[:, None]
            c = np.einsum("mki,mk->mi", np.linalg.pinv(D), gam)
            Db = self.Dbar.copy()
            i = 6 * np.arange(4) + 5
            Db[:, i[:, None], i[None, :]] += (alpha * material.G * material.h * self.area)[:, None, None] \
                * c[:, :, None] * c[:, None, :]
            self.Dbar_packed = Db[:, ed._IU[0], ed._IU[1]]
            self.Dz0 = np.einsum("mij,mj->mi", Db, self.z0)
            self._Dbar = None
    from core_se3.fem import ELEMENTS
    if Hourglass.name not in ELEMENTS:
        ed.register_element(Hourglass)
    return Hourglass.name


def remedies():
    """The sweeps with each candidate remedy (the same normalisation: its own 64x64 value)."""
    out = {}
    cands = [("as kept (none)", {}, lambda E, nu, h: Material(E, nu, h)),
             ("drilling modulus x 100", {}, lambda E, nu, h: Material(E, nu, h, drilling=100.0)),
             ("skew membrane coupling x 0.01", {}, lambda E, nu, h: _skew(E, nu, h, 0.01)),
             ("drilling hourglass, alpha 0.1", dict(element=hourglass_element(0.1)), lambda E, nu, h: Material(E, nu, h)),
             ("drilling hourglass, alpha 1", dict(element=hourglass_element(1.0)), lambda E, nu, h: Material(E, nu, h))]
    for name, kw, law in cands:
        for case, build, R, E, nu in (("Scordelis-Lo roof", sc.scordelis_lo, 25.0, 4.32e8, 0.0),
                                      ("pinched hemisphere", sc.pinched_hemisphere, 10.0, 6.825e7, 0.3)):
            for rh in (1e2, 1e3, 1e4, 1e5):
                h = R / rh
                conv = measure(build, None, 64, material=law(E, nu, h), **kw)["core_se3"]
                out[f"{name}|{case}|{rh:g}"] = {n: measure(build, None, n, material=law(E, nu, h), **kw)["core_se3"] / conv
                                               for n in REMEDY_MESHES}
                print(name, case, rh, {n: round(v, 3) for n, v in out[f"{name}|{case}|{rh:g}"].items()}, flush=True)
    return out


REMEDY_MESHES = (2, 3, 4, 8, 16)


# ------------------------------------------------------------------ enhanced strains (linear) --
def _mode(kind, ab, w):
    """One enhanced-strain mode: ('m' membrane e_ab, 'b' bending K_ab: a symmetric 2x2 tensor;
    's' transverse shear g_a: a 2-vector) in the natural coordinates of the element centre,
    weighted by w(x, y)."""
    def f(x, y):
        if kind == "s":
            v = np.zeros(2)
            v[ab] = w(x, y)
            return v
        M = np.zeros((2, 2))
        M[ab] = M[ab[::-1]] = w(x, y)
        return M
    return kind, f


_X, _Y, _XY = (lambda x, y: x), (lambda x, y: y), (lambda x, y: x * y)
_TENS = ((0, 0), (1, 1), (0, 1))
ENHANCED = {
    # on top of the element's own Simo-Rifai modes (e_11 ~ x, e_22 ~ y, e_12 ~ x, y):
    # Andelfinger and Ramm's fifth (e_12 ~ x y); the same four modes on the bending curvature
    "EAS membrane, 5th mode (e_12 ~ xy)": [_mode("m", (0, 1), _XY)],
    "EAS bending, 4 modes": [_mode("b", (0, 0), _X), _mode("b", (1, 1), _Y), _mode("b", (0, 1), _X), _mode("b", (0, 1), _Y)],
    # x, y, x y on a measure at the 2x2 points: that measure taken at its element mean (what its variation costs)
    "membrane normal strains at their mean": [_mode("m", ab, w) for ab in _TENS[:2] for w in (_X, _Y, _XY)],
    "membrane symmetric shear at its mean": [_mode("m", (0, 1), w) for w in (_X, _Y, _XY)],
    "transverse shear at its mean": [_mode("s", a, w) for a in (0, 1) for w in (_X, _Y, _XY)],
    "bending at its mean": [_mode("b", ab, w) for ab in _TENS for w in (_X, _Y, _XY)],
}


def enhanced_gamma(el, modes):
    """Gamma (m, q, 12, k): the enhanced strain twists of the modes at the 2x2 Gauss points, and
    the law's matrices D j0 (m, q, 12, 12) there.  A mode's centre-basis tensor M is mapped as in
    Simo and Rifai (1990): the Cartesian tensor (j_c / j_q) M_cd A^c(0) A^d(0), its covariant
    components at q e_ab = A_a(q) . (...) . A_b(q) carried by c_a += e_ab A^b (membrane), by
    k_a += e_ab A^b x n (bending, K_ab = (n x k_a) . A_b) or by c_a += g_a n (transverse shear);
    so sum_q j0_q Gamma_q = 0 on flat elements: no work against a constant stress (the patch
    tests are kept)."""
    from core_se3.fem import element_default as ed
    from core_se3.fem.material import strain_operators
    from core_se3.fem.quadrature import GAUSS_2x2
    z0 = el.z0
    zeta0 = np.einsum("qij,mj->mqi", ed.tying_matrices(), z0)
    Dm, j0 = el.material.resultant_matrix(zeta0[..., 0:3], zeta0[..., 6:9])
    A = np.stack([zeta0[..., 0:3], zeta0[..., 6:9]], -2)
    _, Ainv, _ = strain_operators(A[..., 0, :], A[..., 1, :])
    Acon = np.einsum("mqab,mqbi->mqai", Ainv, A)
    n = np.cross(A[..., 0, :], A[..., 1, :]) / j0[..., None]
    A0 = 0.5 * np.stack([z0[:, 0:3] + z0[:, 6:9], z0[:, 12:15] + z0[:, 18:21]], 1)
    _, A0inv, jc = strain_operators(A0[:, 0], A0[:, 1])
    Q = np.einsum("mqai,mbc,mci->mqab", A, A0inv, A0)            # A_a(q) . A^b(0)
    s = jc[:, None] / j0
    Gam = np.zeros(j0.shape + (12, len(modes)))
    for k, (kind, f) in enumerate(modes):
        for q, (x, y) in enumerate(GAUSS_2x2):
            M = f(x, y)
            if kind == "s":
                g = np.einsum("mac,c->ma", Q[:, q], M) * s[:, q, None]
                Gam[:, q, 0:3, k], Gam[:, q, 6:9, k] = g[:, :1] * n[:, q], g[:, 1:] * n[:, q]
                continue
            e = np.einsum("mac,cd,mbd->mab", Q[:, q], M, Q[:, q]) * s[:, q, None, None]
            v = np.einsum("mab,mbi->mai", e, Acon[:, q])            # sum_b e_ab A^b
            if kind == "b":
                v = np.cross(v, n[:, q, None])
            off = 0 if kind == "m" else 3
            Gam[:, q, off:off + 3, k], Gam[:, q, 6 + off:9 + off, k] = v[:, 0], v[:, 1]
    return Gam, Dm * j0[..., None, None]


def enhanced_element(key):
    """Candidate: the default element with the enhanced strains ENHANCED[key] condensed per
    element jointly with the element's own four membrane modes (``fem/membrane_enhanced.py``;
    key None: without them, the element before), Dbar = sum_q P_q^T D j0 P_q - L^T H^+ L,
    H = sum_q Gamma^T D j0 Gamma, L = sum_q Gamma^T D j0 P_q (P_q the element's tying with its
    corrections; H^+ the pseudo-inverse: modes that repeat the element's own count once): still a
    quadratic form in the edge twists."""
    from core_se3.fem import ELEMENTS
    from core_se3.fem import element_default as ed
    from core_se3.fem.membrane_enhanced import membrane_enhancement
    name = "candidate: " + str(key)

    class Enhanced(ed.DefaultElement):
        def __init__(self, mesh, material):
            super().__init__(mesh, material)
            Pm = self.tying()
            Gam, Dj = enhanced_gamma(self, ENHANCED.get(key, []))
            if key is not None:
                zeta0 = np.einsum("qij,mj->mqi", ed.tying_matrices(), self.z0)
                Gam = np.concatenate([membrane_enhancement(self.z0, zeta0, self.j0), Gam], -1)
            DP = np.einsum("mqij,mqjb->mqib", Dj, Pm)
            H = np.einsum("mqia,mqij,mqjb->mab", Gam, Dj, Gam)
            L = np.einsum("mqia,mqib->mab", Gam, DP)
            Db = np.einsum("mqia,mqib->mab", Pm, DP)
            if Gam.shape[-1]:
                Db -= np.einsum("mak,mab->mkb", L, np.linalg.pinv(H, hermitian=True) @ L)
            Db = 0.5 * (Db + np.swapaxes(Db, 1, 2))
            self.Dbar_packed = Db[:, ed._IU[0], ed._IU[1]]
            self.Dz0 = np.einsum("mij,mj->mi", Db, self.z0)
            self._Dbar = None
    Enhanced.name = name
    if name not in ELEMENTS:
        ed.register_element(Enhanced)
    return name


LIKE_CASES = (("Scordelis-Lo roof", sc.scordelis_lo, (4, 8, 16), {}, REF["scordelis-lo"]),
              ("pinched hemisphere", sc.pinched_hemisphere, (4, 8, 16), {}, REF["pinched-hemisphere"]),
              ("pinched cylinder", sc.pinched_cylinder, (8, 16, 32), {}, REF["pinched-cylinder"]),
              ("pinched hemisphere R/h 10", sc.pinched_hemisphere, (2, 4, 8), dict(h=1.0), None),
              ("Cook's membrane", sc.cook_membrane, (2, 4, 8), {}, REF["cook-membrane"]),
              ("twisted beam, out-of-plane load", sc.twisted_beam, ("out-of-plane",), {}, REF["twisted-beam-out-of-plane"]))
CONVERGED_MESH = 64


def _like_variants():
    """{variant: (element, law)}: the default element (Cosserat law), the classical law, the
    element without its enhanced membrane modes, the enhanced-strain candidates, and each strain
    measure taken at its element mean."""
    out = {"Cosserat (the default element)": ("default", None), "classical law": ("default", "classical"),
           "without the enhanced membrane (the element before)": (enhanced_element(None), None)}
    for key in ENHANCED:
        out[key] = (enhanced_element(key), None)
    return out


def like_for_like(kratos):
    """Each case of LIKE_CASES at its meshes with every variant (and Kratos' thick quad): the
    displacement / reference, and / the same variant's (Kratos') own 64x64 value (Cook: 32x32
    by the reference; the twisted beam: the published value only)."""
    rows = []
    for case, build, meshes, kw, ref in LIKE_CASES:
        for name, (element, law) in _like_variants().items():
            def run(n, element=element, law=law):
                p, meas = build(n, element=element, **kw)
                if law == "classical":
                    m = p.material
                    p, meas = build(n, element=element, material=Material.classical_shell(m.E, m.nu, m.h), **kw)
                return meas(p.solve_linear())
            conv = run(CONVERGED_MESH) if case not in ("Cook's membrane", "twisted beam, out-of-plane load") else None
            rows.append(dict(case=case, variant=name, ref=ref, conv=conv, values={str(n): run(n) for n in meshes}))
            print(case, name, {n: round(v / (ref or conv), 4) for n, v in rows[-1]["values"].items()}, flush=True)
        if kratos:
            def krun(n):
                p, meas = build(n, **kw)
                return meas(kratos_solve(kratos, p, "thick"))
            conv = krun(CONVERGED_MESH) if case not in ("Cook's membrane", "twisted beam, out-of-plane load") else None
            rows.append(dict(case=case, variant="kratos thick", ref=ref, conv=conv, values={str(n): krun(n) for n in meshes}))
    return rows


CONVERGENCE_CASES = (("Scordelis-Lo roof", sc.scordelis_lo, {}, REF["scordelis-lo"]),
                     ("pinched cylinder", sc.pinched_cylinder, {}, REF["pinched-cylinder"]),
                     ("pinched hemisphere", sc.pinched_hemisphere, {}, REF["pinched-hemisphere"]),
                     ("pinched hemisphere R/h 10, point loads", sc.pinched_hemisphere, dict(h=1.0), None),
                     ("pinched hemisphere R/h 10, loads spread over an arc h", sc.pinched_hemisphere,
                      dict(h=1.0, load_arc=1.0), None))
CONVERGENCE_MESHES = (4, 8, 16, 32, 64, 128)


def convergence(kratos):
    """Each case of CONVERGENCE_CASES on n x n, n = 4 ... 128, core_se3 and Kratos' thick and
    thin quads: the raw displacements (the report divides by the published value and by each
    element's own 128x128 value).  A point load on a shear-deformable shell has no finite
    limit (Reissner-Mindlin: + P ln 2 / (pi k G h) per halving of the mesh at a free edge), which
    the thick hemisphere's point-load row shows; the spread load is its well-posed version."""
    rows = []
    for case, build, kw, ref in CONVERGENCE_CASES:
        elements = {"core_se3": lambda p: p.solve_linear()}
        if kratos:
            elements.update({f"kratos {e}": (lambda p, e=e: kratos_solve(kratos, p, e)) for e in ("thick", "thin")})
        for name, solve in elements.items():
            values = {}
            for n in CONVERGENCE_MESHES:
                p, meas = build(n, **kw)
                try:
                    values[str(n)] = meas(solve(p))
                except (RuntimeError, ValueError) as exc:
                    values[str(n)] = None
                    print(f"{name} {case} {n}: {str(exc)[-200:]}", file=sys.stderr)
            rows.append(dict(case=case, element=name, ref=ref, values=values))
            print(case, name, {n: v for n, v in values.items()}, flush=True)
    return rows


STABILISATION_ALPHAS = (0.02, 0.1)


def _stabilised(build, alpha, classical=False):
    """``build`` with its own law given Lyly-Stenberg-Vihinen's shear stabilisation alpha, as they
    (and Kratos) have it: without the floor (benchmarks/capped_stabilisation.py measures it)."""
    def run(*a, **kw):
        m = build(*a, **kw)[0].material                 # the case's own E, nu, h
        law = (Material.classical_shell if classical else Material)(m.E, m.nu, m.h, shear_stabilisation=alpha,
                                                                    shear_stabilisation_floor=0.0)
        kw.pop("h", None)
        return build(*a, material=law, **kw)
    return run


def stabilisation():
    """The default element with ``Material.shear_stabilisation`` = alpha (STABILISATION_ALPHAS):
    the sweeps (each over its own 64x64 value), the convergence cases to 128x128 and the 16x16
    set of the issue (roof, hemisphere, cylinder 32x32, twisted beam, the hook with the
    classical law) against the published values."""
    out = {}
    for alpha in STABILISATION_ALPHAS:
        sw = {}
        for case, build, R in (("Scordelis-Lo roof", sc.scordelis_lo, 25.0), ("pinched hemisphere", sc.pinched_hemisphere, 10.0)):
            for rh in SWEEP_RH:
                run = _stabilised(build, alpha)
                vals = {n: measure(run, None, n, h=R / rh)["core_se3"] for n in SWEEP_MESHES + (64,)}
                sw[f"{case}|{rh:g}"] = {str(n): vals[n] / vals[64] for n in SWEEP_MESHES}
                print("stabilised", alpha, case, rh, {n: round(v, 3) for n, v in sw[f"{case}|{rh:g}"].items()}, flush=True)
        conv = []
        for case, build, kw, ref in CONVERGENCE_CASES:
            run = _stabilised(build, alpha)
            conv.append(dict(case=case, element=f"core_se3, alpha {alpha:g}", ref=ref,
                             values={str(n): measure(run, None, n, **kw)["core_se3"] for n in CONVERGENCE_MESHES}))
        std = {}
        for case, build, args, ref, classical in (
                ("Scordelis-Lo roof 16x16", sc.scordelis_lo, (16,), REF["scordelis-lo"], False),
                ("pinched hemisphere 16x16", sc.pinched_hemisphere, (16,), REF["pinched-hemisphere"], False),
                ("pinched cylinder 32x32", sc.pinched_cylinder, (32,), REF["pinched-cylinder"], False),
                ("twisted beam 12x2, in-plane load", sc.twisted_beam, ("in-plane",), REF["twisted-beam-in-plane"], False),
                ("twisted beam 12x2, out-of-plane load", sc.twisted_beam, ("out-of-plane",), REF["twisted-beam-out-of-plane"], False),
                ("Raasch hook 96x32, classical law", sc.raasch_hook, (96, 32), REF["raasch-hook"], True)):
            p, meas = _stabilised(build, alpha, classical)(*args)
            std[case] = meas(p.solve_linear()) / ref
        out[f"{alpha:g}"] = dict(sweeps=sw, convergence=conv, standard=std)
    return out


def _stabilisation_report(doc):
    if not doc:
        return []
    L = ["", "## Shear stabilisation (`Material(..., shear_stabilisation=alpha, shear_stabilisation_floor=0)`, opt-in; with the floor: capped_stabilisation.md)", "",
         "Lyly, Stenberg and Vihinen's factor h^2 / (h^2 + alpha L^2) on the transverse-shear modulus "
         "(L: the element's longest edge; Kratos' thick quad uses alpha = 0.1). Sweeps: each over its own "
         "64x64 value (targets 0.8 ... 1.02, at 2x2 at most 1.02).", ""]
    for alpha, d in doc.items():
        L += [f"alpha = {alpha}, the 16x16 set / published value: "
              + ", ".join(f"{k} {v:.4f}" for k, v in d["standard"].items()), ""]
        L += ["| case | R/h | " + " | ".join(f"{n}x{n}" for n in SWEEP_MESHES) + " |", "|---|---|" + "---:|" * len(SWEEP_MESHES)]
        for key, row in d["sweeps"].items():
            case, rh = key.split("|")
            L.append(f"| {case} | {rh} | " + " | ".join(_f(row.get(str(n)), 3) for n in SWEEP_MESHES) + " |")
        L.append("")
    return L


def _convergence_report(rows):
    if not rows:
        return []
    meshes = [str(n) for n in CONVERGENCE_MESHES]
    L = ["", "## Convergence to 128x128", "",
         "Each cell: displacement / published value, and in brackets / the same element's own 128x128 "
         "value (the like-for-like measure of its discretisation error). Kratos on the same meshes and "
         "nodal loads.", ""]
    for case in dict.fromkeys(r["case"] for r in rows):
        L += [f"{case}:", "", "| element | " + " | ".join(f"{n}x{n}" for n in meshes) + " |",
              "|---|" + "---:|" * len(meshes)]
        for r in (r for r in rows if r["case"] == case):
            v, top = r["values"], r["values"].get(meshes[-1])
            cell = lambda x: "n/a" if x is None else (f"{x / r['ref']:.4f} " if r["ref"] else "") + (
                f"({x / top:.4f})" if top else "")
            L.append(f"| {r['element']} | " + " | ".join(cell(v.get(n)) for n in meshes) + " |")
        L.append("")
    return L


def _skew(E, nu, h, f):
    law = SkewLaw(E, nu, h)
    object.__setattr__(law, "skew", f)
    return law


# ------------------------------------------------------------------ report -----------------
def _f(x, nd=4):
    return "n/a" if x is None else f"{x:.{nd}f}"


def write(doc):
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "obstacle_course.json").write_text(json.dumps(doc, indent=1))
    L = ["# The shell obstacle course (linear analysis)", "",
         f"`python benchmarks/obstacle_course.py` on {doc['date']}; Kratos {doc['kratos'] or 'not run'}"
         + (f" (its columns kept from the run of {doc['kratos_from']})" if doc.get("kratos_from") else "") + ".", "",
         "## Patch tests", "",
         "Interior error of the linear patch tests (boundary nodes on the exact field, interior free; "
         "translations / (1e-3 x patch size), rotations / 1e-3): `catalogue/patch_tests.py`.", "",
         "| patch | " + " | ".join(pt.PATCH_FIELDS) + " |", "|---|---:|---:|---:|"]
    for name, v in doc.get("patches", {}).items():
        L.append(f"| {name} | " + " | ".join(f"{v[k]:.1e}" for k in pt.PATCH_FIELDS) + " |")
    cols = ["core_se3", "kratos thick", "kratos thin"]
    L += ["", "## Standard cases", "",
          "Displacement / published value (`catalogue/shell_course.py` for the values and sources).", "",
          "| case | mesh | reference | " + " | ".join(cols) + " |", "|---|---|---:|---:|---:|---:|"]
    for r in doc.get("standard", []):
        L.append(f"| {r['case']} | {r['mesh']} | {r['ref']:g} | " + " | ".join(_f(r["values"].get(c)) for c in cols) + " |")
    L += ["", "## Thickness sweeps", "",
          "Displacement / the 64x64 value of core_se3 at the same thickness (targets: 0.8 ... 1.02, "
          "at 2x2 at most 1.02; hemisphere 4x4 at least 0.95). Kratos columns: the same meshes "
          "and nodal loads, divided by core_se3's 64x64 value.", ""]
    sw = doc.get("sweeps", {})
    for case in dict.fromkeys(k.split("|")[0] for k in sw):
        for c in cols:
            L += ["", f"{case}, {c}:", "", "| R/h | " + " | ".join(f"{n}x{n}" for n in SWEEP_MESHES) + " |",
                  "|---|" + "---:|" * len(SWEEP_MESHES)]
            for key, s in sw.items():
                if key.split("|")[0] != case:
                    continue
                L.append(f"| {key.split('|')[1]} | " + " | ".join(_f(s["ratios"][str(n) if str(n) in s["ratios"] else n].get(c), 3)
                                                            for n in SWEEP_MESHES) + " |")
            errs = [(key.split("|")[1], s["converged_error"]) for key, s in sw.items()
                    if key.split("|")[0] == case and s.get("converged_error") is not None]
            if c == "core_se3" and errs:
                L += ["", "The 64x64 values' own accuracy (the linear solve's error estimate in double precision, "
                      "docs/ELEMENTS.md \"Linear analysis\"): " + ", ".join(f"R/h {k} {e:.1e}" for k, e in errs) + "."]
    rem = doc.get("remedies", {})
    if rem:
        L += ["", "## Candidate remedies for thin curved coarse meshes", "",
              "Each candidate's ratio to its own 64x64 value at the same thickness (the same sweeps).", "",
              "| candidate | case | R/h | " + " | ".join(f"{n}x{n}" for n in REMEDY_MESHES) + " |",
              "|---|---|---|" + "---:|" * len(REMEDY_MESHES)]
        for key, row in rem.items():
            name, case, rh = key.split("|")
            L.append(f"| {name} | {case} | {rh} | " + " | ".join(_f(row.get(str(n), row.get(n)), 3) for n in REMEDY_MESHES) + " |")
    L += _like_report(doc.get("likeforlike", []), doc.get("likeforlike_kratos"))
    L += _convergence_report(doc.get("convergence", []) + [r for d in doc.get("stabilisation", {}).values()
                                                           for r in d["convergence"]])
    L += _stabilisation_report(doc.get("stabilisation", {}))
    L += ["", NOTES, ""]
    (RESULTS / "obstacle_course.md").write_text("\n".join(L))


def _like_report(rows, kratos_date=None):
    """The like-for-like section: per case, each variant's displacement / reference and / its own
    64x64 value."""
    if not rows:
        return []
    L = ["", "## Like for like: the laws, enhanced strains and Kratos' thick quad on the coarse meshes", "",
         f"Kratos' thick quad run on {kratos_date}. " if kratos_date else "",
         "Each cell: displacement / published value, and in brackets / the same variant's own 64x64 value "
         "(Kratos: its own 64x64 run). \"at its mean\" rows take one strain measure at its element mean "
         "(enhanced modes x, y, xy condensed): how much of the coarse-mesh stiffness that measure's "
         "variation carries.", ""]
    for case in dict.fromkeys(r["case"] for r in rows):
        rs = [r for r in rows if r["case"] == case]
        meshes = list(rs[0]["values"])
        L += [f"{case}:", "", "| variant | " + " | ".join(meshes) + " |", "|---|" + "---:|" * len(meshes)]
        for r in rs:
            cell = lambda v: (f"{v / r['ref']:.4f}" if r["ref"] else "") + (
                f" ({v / r['conv']:.4f})" if r["conv"] else "")
            L.append(f"| {r['variant']} | " + " | ".join(cell(r["values"][n]) for n in meshes) + " |")
        L.append("")
    return L


def _carry_peers(old, doc):
    """Keep the last run's Kratos columns in the parts rerun without ``--kratos`` (they depend
    on the meshes and loads only, not on core_se3)."""
    rows = {(r["case"], r["mesh"]): r["values"] for r in old.get("standard", [])}
    for r in doc.get("standard", []):
        for k, v in rows.get((r["case"], r["mesh"]), {}).items():
            r["values"].setdefault(k, v)
    for key, s in doc.get("sweeps", {}).items():
        prev = old.get("sweeps", {}).get(key)
        if prev is None or prev is s:
            continue
        scale = prev["converged"] / s["converged"]          # Kratos / core_se3's 64x64 value
        for n, row in s["ratios"].items():
            for k, v in prev["ratios"].get(str(n), {}).items():
                if k.startswith("kratos"):
                    row.setdefault(k, None if v is None else v * scale)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kratos", default=None, help="python of a Kratos 10.4.0 venv")
    ap.add_argument("--parts", nargs="*", default=["patches", "standard", "sweeps", "remedies", "likeforlike", "convergence", "stabilisation"],
                    help="patches, standard, sweeps, remedies, likeforlike, convergence, stabilisation (none: rewrite the report of the kept results)")
    ap.add_argument("--keep", action="store_true",
                    help="keep the other parts of the last results (and its Kratos columns where --kratos is not given)")
    a = ap.parse_args()
    path = RESULTS / "obstacle_course.json"
    old = json.loads(path.read_text()) if path.exists() and a.keep else {}
    doc = dict(old)
    doc.update(date=datetime.datetime.now().isoformat(timespec="seconds"),
               kratos="10.4.0" if a.kratos else old.get("kratos"))
    if old and (not a.kratos or not {"standard", "sweeps"} <= set(a.parts)):
        doc["kratos_from"] = old.get("kratos_from") or old["date"]
    if a.kratos and "likeforlike" in a.parts:
        doc["likeforlike_kratos"] = doc["date"]
    if "patches" in a.parts:
        doc["patches"] = patches()
        print(doc["patches"], flush=True)
    if "standard" in a.parts:
        doc["standard"] = standard(a.kratos)
    if "sweeps" in a.parts:
        doc["sweeps"] = sweeps(a.kratos)
    if "remedies" in a.parts:
        doc["remedies"] = remedies()
    if "likeforlike" in a.parts:
        kept = [r for r in old.get("likeforlike", []) if r["variant"] == "kratos thick"]
        doc["likeforlike"] = like_for_like(a.kratos) + ([] if a.kratos else kept)
        doc["likeforlike"].sort(key=lambda r: [c[0] for c in LIKE_CASES].index(r["case"]))
    if "convergence" in a.parts:
        kept = [r for r in old.get("convergence", []) if r["element"] != "core_se3"]
        doc["convergence"] = convergence(a.kratos) + ([] if a.kratos else kept)
    if "stabilisation" in a.parts:
        doc["stabilisation"] = stabilisation()
    if old and not a.kratos:
        _carry_peers(old, doc)
    write(doc)


if __name__ == "__main__":
    sys.exit(main())
