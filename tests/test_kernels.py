"""The numba backend (core_se3.kernels) against the NumPy reference, to 1e-12 relative.

Residuals and tangents are compared on random states whose nodal rotations span several turns
(a smooth rotation field plus noise plus a rigid motion of 20 pi + 0.7) while every edge turns
by less than MAX_EDGE_ANGLE, including edges past 2 pi/3 (the log's near-pi branch).  Tangents
are compared as CSR data arrays against ``Assembler.matrix`` (same indptr/indices).

Problems are evaluated with both backends (``Problem(..., backend=...)``); every built-in load
kind is compared, and a user load without a compiled kernel goes through the generic block
scatter.  The element kernels' two forms of Dbar are both compared: the split form of the
laws of ``fem.material`` (on aligned meshes and on the disk's general quads) and the general
path of a law coupling membrane and bending (``CoupledLaw``).
"""
import numpy as np
import pytest

from core_se3 import lie as se3
from core_se3 import mesh as M
from core_se3.assembly import Assembler
from core_se3.errors import ElementTooDistortedError
from core_se3.fem import Material, RegionMaterial
from core_se3.fem.element_default import _dexp_inv_jacobian_T
from core_se3.model import Load, LoadEvaluation, NodalLoad, Problem
from core_se3.model.supports import RotationComponentSpring
from core_se3.model.fields import DipoleField, GradientField, Superposition, UniformField

from core_se3 import kernels as K
from core_se3.kernels import lie as KL
from core_se3.kernels import loads as KLd

TOL = 1e-12


def rel(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return np.abs(a - b).max() / max(np.abs(b).max(), 1e-300)


# ------------------------------------------------------------------ scalar kernels ----------

ANGLES = [0.0, 1e-9, 1e-4, 0.3, 0.999, 1.0, 1.001, 2.0, 2.09, 2.1, 2.5, 3.0, 0.97 * np.pi, np.pi - 1e-6]


@pytest.mark.parametrize("t", ANGLES)
def test_log_exp_dexp_inv(t):
    rng = np.random.default_rng(int(t * 1e6) % 1000)
    for _ in range(5):
        n = rng.normal(size=3)
        xi = np.r_[rng.normal(size=3), t * n / np.linalg.norm(n)]
        g = se3.exp(xi)
        gk = np.empty((4, 4))
        KL.exp_se3(xi, gk)
        assert rel(gk, g) <= TOL
        psi = np.empty(6)
        KL.log_se3(np.eye(4), g, np.empty((3, 3)), psi)
        ref = se3.log(g)
        assert np.abs(psi - ref).max() <= TOL * max(1.0, np.abs(ref).max())
        L = np.empty((6, 6))
        KL.dexp_inv_se3(xi, L)
        assert rel(L, se3.dexp_inv(xi)) <= TOL
        F = rng.normal(size=6)
        s = xi[3:] @ xi[3:]
        c, dc, ddc = KL.coef_c(s), KL.coef_dc(s), KL.coef_ddc(s)
        out = np.empty(6)
        for sign in (1.0, -1.0):
            KL.dexp_inv_T_apply(xi, c, dc, sign, F, out, 1.0)
            assert rel(out, se3.dexp_inv_T_apply(sign * xi, F)) <= TOL
        J = np.empty((6, 6))
        KL.dexp_inv_T_jacobian(xi, c, dc, ddc, F, J)
        assert rel(J, _dexp_inv_jacobian_T(xi[None], F[None])[0]) <= TOL


def test_log_at_pi_is_a_valid_log():
    """At exactly pi the axis sign is a free choice: exp(log(R)) = R is what must hold."""
    for axis in np.eye(3):
        g = se3.exp(np.r_[0.1, 0.2, 0.3, np.pi * axis])
        psi = np.empty(6)
        KL.log_se3(np.eye(4), g, np.empty((3, 3)), psi)
        gk = np.empty((4, 4))
        KL.exp_se3(psi, gk)
        assert np.abs(gk - g).max() < 1e-12


# ------------------------------------------------------------------ meshes and states -------

def _meshes():
    flat = M.rectangle(1.5, 1.0, 3, 2)
    arch = M.cylinder_arch(1.0, 1.2, 0.8, 4, 2)
    ann = M.annulus(0.5, 1.0, 1.5 * np.pi, 2, 6)
    disk = M.disk(1.0, 0.3)         # general quads, frames not along the edges: a fuller Dbar
    return {"flat": flat, "arch": arch, "annulus": ann, "disk": disk}


class CoupledLaw:
    """A test-only ResultantLaw that couples membrane and bending (as a laminate's B matrix):
    W = W_base + beta sqrt(C D) H(e, K) (``fem.material``'s e, K and H), i.e. Material's
    resultant matrix plus beta sqrt(C D) (Mm^T H Mb + Mb^T H Mm): positive definite for
    |beta| < 1, and Dbar's v-w blocks are not zero, so the kernels take their general path."""

    def __init__(self, base, beta=0.5):
        self.base, self.beta = base, beta

    def resultant_matrix(self, A1, A2):
        from core_se3.fem.material import strain_operators
        Dm, j0 = self.base.resultant_matrix(A1, A2)
        (Mm, _, Mb, _), Ainv, _ = strain_operators(A1, A2)
        nu = self.base.nu
        H = (nu * np.einsum("...ab,...cd->...abcd", Ainv, Ainv)
             + (1 - nu) * np.einsum("...ac,...bd->...abcd", Ainv, Ainv)).reshape(Ainv.shape[:-2] + (4, 4))
        B = np.swapaxes(Mm, -1, -2) @ H @ Mb
        c = self.beta * np.sqrt(self.base.C * self.base.D)
        return Dm + c * (B + np.swapaxes(B, -1, -2)), j0


def _problem(kind, nu=0.3, backend="numpy"):
    if kind == "region":
        mesh = M.rectangle(2.0, 1.0, 4, 3)
        mat = RegionMaterial.from_regions(mesh.n_elements, Material(1.0e4, 0.3, 0.1),
                                          [(np.arange(0, mesh.n_elements, 3), Material(3.0e4, 0.2, 0.05))])
        return Problem(mesh, mat, backend=backend)
    if kind == "coupled":
        return Problem(M.cylinder_arch(1.0, 1.2, 0.8, 4, 2), CoupledLaw(Material(1.0e4, nu, 0.1)), backend=backend)
    return Problem(_meshes()[kind], Material(1.0e4, nu, 0.1), backend=backend)


KINDS = ["flat", "arch", "annulus", "region", "disk", "coupled"]


def _state(mesh, seed, edge_turn=0.85 * np.pi, noise=0.05):
    """Frames with a smooth rotation field turning by ~edge_turn per element (several turns over
    the mesh), random noise, and a rigid motion of 20 pi + 0.7 about a random axis."""
    rng = np.random.default_rng(seed)
    X = mesh.X
    h = np.median(np.linalg.norm(X[mesh.edge_nodes[:, 1]] - X[mesh.edge_nodes[:, 0]], axis=1))
    ax = rng.normal(size=3)
    ax /= np.linalg.norm(ax)
    d = rng.normal(size=3)
    s = X @ (d / np.linalg.norm(d)) / h                 # coordinate in edge lengths
    w = edge_turn * s[:, None] * ax                     # turns by ~edge_turn per edge
    xi = np.concatenate([0.05 * rng.normal(size=(len(X), 3)), w + noise * rng.normal(size=(len(X), 3))], 1)
    g = mesh.g0 @ se3.exp(xi)
    n = rng.normal(size=3)
    rig = se3.exp(np.r_[rng.normal(size=3), (20 * np.pi + 0.7) * n / np.linalg.norm(n)])
    return rig @ g


def _safe_state(mesh, seed, frames=lambda g: g):
    """A state from _state scaled so that the largest edge turn is below MAX_EDGE_ANGLE (of the
    element's frames ``frames(g)``: ``DefaultElement.frames``, turned about the normals by the
    mesh's gauge)."""
    for turn in np.linspace(0.9 * np.pi, 0.1, 40):
        g = _state(mesh, seed, edge_turn=turn)
        h = frames(g)
        psi = se3.log(se3.inv(h[mesh.edge_nodes[:, 0]]) @ h[mesh.edge_nodes[:, 1]])
        ang = np.linalg.norm(psi[:, 3:], axis=1)
        if ang.max() < 0.96 * np.pi:
            return g, ang
    raise AssertionError("no admissible state")


def _free(mesh, rng):
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    fixed[mesh.edges["x0"] if "x0" in mesh.edges else mesh.edges["rim"][:3]] = True
    fixed[rng.integers(mesh.n_nodes), rng.integers(6)] = True     # a partly constrained node
    return ~fixed.ravel()


# ------------------------------------------------------------------ pattern -----------------

@pytest.mark.parametrize("kind", KINDS)
def test_pattern_equals_assembler(kind):
    p = _problem(kind)
    mesh = p.mesh
    free = _free(mesh, np.random.default_rng(0))
    asm = Assembler(mesh, free)
    pat = K.Pattern(mesh.quads, mesh.edge_nodes, mesh.elem_edges, mesh.n_nodes, free)
    assert pat.nnz == asm.nnz and pat.nfree == asm.nfree
    assert np.array_equal(pat.indptr, asm.indptr) and np.array_equal(pat.indices, asm.indices)
    # colourings are valid: no two elements (edges) of a colour share a node
    for cptr, order, items in [(pat.topo.elem_cptr, pat.topo.elem_order, mesh.quads),
                               (pat.topo.edge_cptr, pat.topo.edge_order, mesh.edge_nodes)]:
        for c in range(len(cptr) - 1):
            nodes = items[order[cptr[c]:cptr[c + 1]]].ravel()
            assert len(np.unique(nodes)) == len(nodes)


# ------------------------------------------------------------------ element -----------------

@pytest.mark.parametrize("mode", ["serial", "colour", "gather"])
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("seed", [1, 2])
def test_element_residual_and_tangent(kind, mode, seed):
    p = _problem(kind)
    mesh, el = p.mesh, p.element
    free = _free(mesh, np.random.default_rng(seed))
    asm = Assembler(mesh, free)
    pat = K.Pattern(mesh.quads, mesh.edge_nodes, mesh.elem_edges, mesh.n_nodes, free)
    ek = K.ElementKernels.from_element(el, pat, mode=mode, error=ElementTooDistortedError)
    g, ang = _safe_state(mesh, seed, el.frames)
    assert ang.max() > 2 * np.pi / 3          # the near-pi branch of the log is exercised
    ev = el.evaluate(g, tangent=True)
    Kref = asm.matrix(ev.element_blocks, ev.edge_blocks, ev.node_blocks)
    res = ek.residual(g)
    assert abs(res["energy"] - ev.energy) <= TOL * ev.energy
    assert rel(res["r"], ev.r) <= TOL
    assert abs(res["force_scale"] - ev.force_scale) <= TOL * ev.force_scale
    tan = ek.tangent(g)
    assert abs(tan["energy"] - ev.energy) <= TOL * ev.energy
    assert rel(tan["r"], ev.r) <= TOL
    assert rel(tan["data"], Kref.data) <= TOL
    # blockwise too: no block may hide under the global max
    D = pat.matrix(tan["data"]).toarray() - Kref.toarray()
    scale = np.abs(Kref.toarray()).max()
    assert np.abs(D).max() <= TOL * scale


def test_dbar_paths():
    """Each law of fem.material gives a Dbar without v-w coupling on parallelograms: the kernels
    read its split form (the two 12x12 diagonal blocks in the order z' = (v of the 4 edges, w
    of the 4 edges)); a law coupling membrane and bending takes the general path (Dbar
    unpacked).  Distorted quads (the disk), whose membrane strain sees the drilling components
    w_3 of the edge twists (fem.membrane_drilling), couple v and w in those 4 columns only: the
    split form then carries them in 4 more columns (m, 24, 16)."""
    from core_se3.kernels.element_dbar import ZP
    for kind, split in [("flat", True), ("disk", True), ("arch", True), ("region", True), ("coupled", False)]:
        el = _problem(kind).element
        mesh = el.mesh
        pat = K.Pattern(mesh.quads, mesh.edge_nodes, mesh.elem_edges, mesh.n_nodes, np.ones(6 * mesh.n_nodes, bool))
        ek = K.ElementKernels.from_element(el, pat, mode="serial")
        assert ek.split is split, kind
        D = np.empty_like(el.Dbar)
        D[:, ZP[:, None], ZP[None, :]] = el.Dbar                    # Dbar in the order z'
        vw = np.abs(D[:, :12, 12:]).max()
        if kind == "disk":
            drill = 12 + 3 * np.arange(4) + 2                         # the w_3 of the 4 edges in z'
            other = np.setdiff1d(np.arange(12, 24), drill)
            assert vw > 0 and np.abs(D[:, :12][:, :, other]).max() == 0.0
            assert ek.Dsplit.shape == (mesh.n_elements, 24, 16)
            assert np.array_equal(ek.Dsplit[:, :12, :12], D[:, :12, :12])
            assert np.array_equal(ek.Dsplit[:, 12:, :12], D[:, 12:, 12:])
            assert np.array_equal(ek.Dsplit[:, :12, 12:], D[:, :12, drill])
            assert not ek.Dsplit[:, 12:, 12:].any()
        elif split:
            assert vw == 0.0 and ek.Dsplit.shape == (mesh.n_elements, 24, 12)
            assert np.array_equal(ek.Dsplit[:, :12], D[:, :12, :12])
            assert np.array_equal(ek.Dsplit[:, 12:], D[:, 12:, 12:])
        else:
            scale = np.sqrt(np.abs(D[:, :12, :12]).max() * np.abs(D[:, 12:, 12:]).max())   # |D_vw| <= that
            assert vw > 0.1 * scale and ek.Dsplit.shape[0] == 0
    # the disk's frames are not along the element edges: more of Dbar's v-v, w-w entries are
    # non-zero than on a rectangle (160 against 64 of 576), and the membrane-drilling coupling
    # adds 64 (the 8 in-plane v components of the 4 edges with the 4 drilling components, both ways)
    nz = {k: int((_problem(k).element.Dbar != 0).any(0).sum()) for k in ("flat", "disk")}
    assert nz == {"flat": 64, "disk": 224}


def test_too_distorted_flag_and_error():
    p = _problem("flat")
    mesh = p.mesh
    pat = K.Pattern(mesh.quads, mesh.edge_nodes, mesh.elem_edges, mesh.n_nodes, np.ones(6 * mesh.n_nodes, bool))
    ek = K.ElementKernels.from_element(p.element, pat, error=ElementTooDistortedError)
    g = mesh.g0.copy()
    node = 5
    g[node] = g[node] @ se3.exp(np.r_[0, 0, 0, 0, 0, 0.985 * np.pi])
    with pytest.raises(ElementTooDistortedError) as ref:
        p.element.evaluate(g)
    with pytest.raises(ElementTooDistortedError) as got:
        ek.residual(g)
    assert str(got.value) == str(ref.value)
    with pytest.raises(ElementTooDistortedError):
        ek.tangent(g)


# ------------------------------------------------------------------ loads -------------------

class _UserLoad(Load):
    """A load with no compiled kernel: a dead couple per node (the backend scatters its blocks)."""

    def __init__(self, n, nodes, moment):
        self.n, self.nodes, self.moment = n, np.asarray(nodes), np.asarray(moment, float)

    def evaluate(self, g, lam, tangent=True):
        f = np.zeros((self.n, 6))
        Mb = lam * np.einsum("nji,j->ni", g[self.nodes, :3, :3], self.moment)
        f[self.nodes, 3:] = Mb
        if not tangent:
            return LoadEvaluation(f)
        Kn = np.zeros((self.n, 6, 6))
        Kn[self.nodes, 3:, 3:] = -se3.hat3(Mb)
        Ke = np.zeros((2, 4, 4, 6, 6))
        Ke[:, 0, 1, :3, 3:] = np.eye(3)            # arbitrary element blocks: they must land too
        return LoadEvaluation(f, Kn, (np.array([0, 4]), Ke))


def _loaded(which, backend):
    mesh = M.rectangle(1.5, 1.0, 3, 2)
    p = Problem(mesh, Material(1.0e4, 0.3, 0.1, rho=2.0), backend=backend)
    p.clamp("x0")
    if which == "nodal_dead":
        p.add_edge_force("x1", (3.0, -2.0, 5.0))
        p.add_edge_moment("x1", (0.5, 1.0, -0.7))
        # a repeated node (the kernels accumulate repeats as np.add.at does; selections refuse them)
        p.add(NodalLoad(mesh.n_nodes, np.array([4, 4, 7]), np.ones(3), force=(1.0, 2.0, 3.0), moment=(-1.0, 0.3, 0.2)))
    elif which == "nodal_follower":
        p.add_edge_force("x1", (3.0, -2.0, 5.0), follower=True)
        p.add_edge_moment("x1", (0.5, 1.0, -0.7), follower=True)
    elif which == "surface_dead":
        p.add_pressure(4.0)
        p.add_pressure(2.0, direction=np.array([0.3, -0.2, 1.0]), elements=[1, 4])
        p.add_body_force((0.1, 0.2, -0.5))
        p.add_gravity(2.0)
    elif which == "surface_follower":
        p.add_pressure(4.0, follower=True)
        p.add_pressure(-1.5, follower=True, elements=[0, 2, 5])
    elif which == "mag_uniform":
        p.add_magnetic((0.1, 0.2, 0.05), UniformField((0.01, -0.02, 0.03)))
    elif which == "mag_gradient":
        p.add_magnetic((0.1, 0.2, 0.05), GradientField((0.01, 0.0, 0.02),
                                                       [[0.5, 0.2, 0.0], [0.2, -0.3, 0.1], [0.0, 0.1, -0.2]]))
    elif which == "mag_dipole":
        p.add_magnetic((0.1, 0.2, 0.05), DipoleField((0.0, 0.5, 2.0), (0.7, 0.1, -0.6)), elements=[0, 1, 3, 4])
    elif which == "mag_superposition":
        p.add_magnetic((0.1, 0.0, 0.3), Superposition(UniformField((0.0, 0.01, 0.0)),
                                                      DipoleField((0.3, 0.0, 1.0), (-0.4, 0.0, 0.5))))
    elif which == "mag_several":
        # four magnets in one batch (model.magnetics.compiled_magnets): two fields, overlapping
        # element sets (shared nodes), a uniform and a dipole field
        B, D = UniformField((0.01, -0.02, 0.03)), DipoleField((0.0, 0.5, 2.0), (0.7, 0.1, -0.6))
        p.add_magnetic((0.1, 0.2, 0.05), B, elements=[0, 1, 2])
        p.add_magnetic((-0.2, 0.1, 0.0), D, elements=[1, 4])
        p.add_magnetic((0.0, 0.3, -0.1), B, elements=[2, 3, 5])
        p.add_magnetic((0.05, 0.0, 0.2), D, elements=[0, 5])
    elif which == "lab_springs":
        p.add_lab_support("x1", np.array([[1.0, 0.0, 0.0], [0.0, 0.6, 0.8]]), 1e3)
        p.add_lab_tilt_support("y0", np.array([0.0, 1.0, 0.0]), 50.0)
    elif which == "rotation_spring":
        p.add_rotation_component_support("x1", np.array([0.0, 1.0, 0.0]), 30.0)
        p.add(RotationComponentSpring(mesh, np.array([5, 5]), np.array([0.6, 0.0, 0.8]), 10.0))   # a repeated node
    elif which == "user_load":
        p.add(_UserLoad(mesh.n_nodes, [5, 6, 6], (0.3, -0.2, 0.9)))
    return p


LOADS = ["nodal_dead", "nodal_follower", "surface_dead", "surface_follower", "mag_uniform",
         "mag_gradient", "mag_dipole", "mag_superposition", "mag_several", "lab_springs", "rotation_spring", "user_load"]


def _load_state(mesh, which):
    rng = np.random.default_rng(3)
    xi = np.concatenate([0.05 * rng.normal(size=(mesh.n_nodes, 3)), 0.4 * rng.normal(size=(mesh.n_nodes, 3))], 1)
    if which == "rotation_spring":
        xi[:, 3:] *= 0.5
    return mesh.g0 @ se3.exp(xi)


@pytest.mark.parametrize("which", LOADS)
def test_problem_evaluation_both_backends(which):
    """Problem.evaluate (element + loads + assembly) agrees between the backends: residual,
    internal and external forces, tangent (CSR data on the same pattern)."""
    pa, pb = _loaded(which, "numpy"), _loaded(which, "numba")
    g = pa.apply_prescribed(_load_state(pa.mesh, which), 0.7)
    for tangent in (True, False):
        ea, eb = pa.evaluate(g, 0.7, tangent), pb.evaluate(g, 0.7, tangent)
        assert rel(eb.f_ext, ea.f_ext) <= TOL and rel(eb.r_int, ea.r_int) <= TOL and rel(eb.r, ea.r) <= TOL
        assert abs(eb.energy - ea.energy) <= TOL * ea.energy
        if tangent:
            assert np.array_equal(eb.K.indptr, ea.K.indptr) and np.array_equal(eb.K.indices, ea.K.indices)
            assert rel(eb.K.data, ea.K.data) <= TOL


@pytest.mark.parametrize("which", ["mag_uniform", "mag_several"])
def test_batched_magnets_equal_the_loads_sum(which):
    """The batched compiled magnets (one field evaluation per field, one kernel call) equal the
    sum of the loads' own compiled evaluations, residual and tangent, to 1e-14."""
    from core_se3.model.magnetics import compiled_magnets
    p = _loaded(which, "numba")
    g = _load_state(p.mesh, which)
    pattern = p.assembler().pattern()
    n = p.mesh.n_nodes
    fa, fb = np.zeros((n, 6)), np.zeros((n, 6))
    da, db = pattern.new_data(), pattern.new_data()
    compiled_magnets(p.loads, pattern)(g, 0.7, fa, da, True)
    for ld in p.loads:
        ld.compiled(pattern)(g, 0.7, fb, db, True)
    assert np.abs(fb).max() > 0 and np.abs(db).max() > 0
    assert rel(fa, fb) <= 1e-14 and rel(da, db) <= 1e-14


def test_rotation_spring_limit():
    pa, pb = _loaded("rotation_spring", "numpy"), _loaded("rotation_spring", "numba")
    g = pa.mesh.g0.copy()
    node = pa.mesh.edges["x1"][1]
    g[node] = g[node] @ se3.exp(np.r_[0, 0, 0, 0.96 * np.pi, 0, 0])
    with pytest.raises(ElementTooDistortedError) as ref:
        pa.evaluate(g, 1.0)
    with pytest.raises(ElementTooDistortedError) as got:
        pb.evaluate(g, 1.0)
    assert str(got.value) == str(ref.value)


def test_dipole_field_kernel():
    fld = DipoleField((0.3, -0.5, 2.0), (0.1, 0.2, -0.6), scale=lambda lam: 2.0 * lam)
    x = np.random.default_rng(0).normal(size=(20, 3))
    B, G, H = np.empty((20, 3)), np.empty((20, 3, 3)), np.empty((20, 3, 3, 3))
    assert KLd.dipole_field(x, fld.m, fld.x0, fld.k, 2.0 * 0.8, B, G, H) == 0
    assert rel(B, fld.value(x, 0.8)) <= TOL
    assert rel(G, fld.gradient(x, 0.8)) <= TOL
    assert rel(H, fld.hessian(x, 0.8)) <= 1e-10      # the reference's complex step: ~1e-13
    assert KLd.dipole_field(fld.x0[None], fld.m, fld.x0, fld.k, 1.0, B[:1], G[:1], H[:1]) == 1


# ------------------------------------------------------------------ Newton -------------------

@pytest.mark.parametrize("name", ["cantilever-shear", "pressure-strip", "torsion"])
def test_newton_same_path_both_backends(name):
    """A catalogue case solved with each backend: the same Newton iterations per step and the
    same states (to 1e-10 of the position scale: the two backends differ by round-off only)."""
    from core_se3 import catalogue
    case = catalogue.get_case(name)
    p = catalogue.case_params(case)
    mesh = None
    res = {}
    for b in ("numpy", "numba"):
        prob = catalogue.build_problem(case, p, mesh)
        prob.backend = b
        res[b] = prob.solve(steps=case.steps)
    for a, b in zip(res["numba"].steps, res["numpy"].steps):
        assert a.iterations == b.iterations
        assert np.abs(a.g - b.g).max() <= 1e-10 * np.abs(b.g[:, :3, 3]).max()


# ------------------------------------------------------------------ mixed (MIP) iteration ----

def _mixed_setup(kind, mode, seed):
    p = _problem(kind)
    mesh, el = p.mesh, p.element
    free = _free(mesh, np.random.default_rng(seed))
    asm = Assembler(mesh, free)
    pat = K.Pattern(mesh.quads, mesh.edge_nodes, mesh.elem_edges, mesh.n_nodes, free)
    ek = K.ElementKernels.from_element(el, pat, mode=mode, error=ElementTooDistortedError)
    g, ang = _safe_state(mesh, seed, el.frames)
    assert ang.max() > 2 * np.pi / 3
    return el, asm, pat, ek, g


@pytest.mark.parametrize("mode", ["serial", "colour", "gather"])
@pytest.mark.parametrize("kind", KINDS)
def test_mixed_tangent_and_stress(kind, mode):
    """tangent(g, data, stress=S): the NumPy element's evaluate(g, stress=S), assembled; the
    returned stress is the NumPy evaluation's Dbar (z - z0); S = that stress gives the ordinary
    tangent, which the kernels still compute after a mixed call."""
    el, asm, pat, ek, g = _mixed_setup(kind, mode, seed=1)
    ev = el.evaluate(g, tangent=True)
    K0 = asm.matrix(ev.element_blocks, ev.edge_blocks, ev.node_blocks)
    rng = np.random.default_rng(7)
    S = rng.normal(size=ev.stress.shape) * np.abs(ev.stress).max()
    evm = el.evaluate(g, True, stress=S)
    Km = asm.matrix(evm.element_blocks, evm.edge_blocks, evm.node_blocks)
    assert rel(Km.data, K0.data) > 1e-3               # the stresses matter
    data = pat.new_data()
    tan = ek.tangent(g, data, stress=S)
    assert tan["data"] is data
    assert rel(data, Km.data) <= TOL
    D = pat.matrix(data).toarray() - Km.toarray()
    assert np.abs(D).max() <= TOL * np.abs(Km.toarray()).max()
    # the residual side is the displacement one
    assert abs(tan["energy"] - evm.energy) <= TOL * evm.energy
    assert rel(tan["r"], evm.r) <= TOL and rel(evm.r, ev.r) == 0.0
    assert abs(tan["force_scale"] - ev.force_scale) <= TOL * ev.force_scale
    # stress of the state, a fresh array, from tangent and from residual
    assert tan["stress"].shape == ev.stress.shape and not np.shares_memory(tan["stress"], ek.fe)
    assert rel(tan["stress"], ev.stress) <= TOL
    res = ek.residual(g)
    assert rel(res["stress"], ev.stress) <= TOL
    # S = the state's own stress: the ordinary tangent
    t0 = ek.tangent(g)["data"].copy()
    assert rel(t0, K0.data) <= TOL
    tm = ek.tangent(g, stress=res["stress"])["data"]
    assert rel(tm, t0) <= TOL
    assert rel(ek.tangent(g)["data"], K0.data) <= TOL  # not mixed again: no trace of the last S
    with pytest.raises(ValueError):
        ek.tangent(g, stress=S[:-1])


@pytest.mark.parametrize("mode", ["serial", "gather"])
@pytest.mark.parametrize("kind", KINDS)
def test_linear_stress(kind, mode):
    """linear_stress(eta) = NumPy's DefaultElement.linear_stress at the state of the last call,
    with O(1) increments (G eta as large as z - z0: its signs are checked), and the first-order
    expansion of the nonlinear stresses Dbar (z(g exp(eps eta)) - z0)."""
    el, asm, pat, ek, g = _mixed_setup(kind, mode, seed=2)
    ev = el.evaluate(g, tangent=True)
    rng = np.random.default_rng(11)
    eta = rng.normal(size=(el.mesh.n_nodes, 6))
    ref = el.linear_stress(ev, eta)
    assert rel(ref, ev.stress) > 0.1
    ek.tangent(el.mesh.g0)                             # another state first: the last call counts
    ek.residual(g)
    got = ek.linear_stress(eta)
    assert got.shape == ref.shape and rel(got, ref) <= TOL
    assert rel(ek.linear_stress(np.zeros_like(eta)), ev.stress) <= TOL
    ek.tangent(g)
    assert rel(ek.linear_stress(eta.ravel()), ref) <= TOL
    eps = 1e-6
    lin = ek.linear_stress(eps * eta) - ev.stress
    fp = ek.residual(g @ se3.exp(eps * eta))["stress"] - ev.stress
    assert np.abs(fp - lin).max() <= 1e-4 * np.abs(lin).max()
    with pytest.raises(ValueError):
        ek.linear_stress(eta[:-1])


@pytest.mark.parametrize("which", ["mag_uniform", "mag_gradient", "mag_several"])
def test_batched_numpy_magnets_equal_the_loads_sum(which):
    """The NumPy backend's batched magnetic forces (model.magnetics.magnets_force, the residual's
    external part) equal the sum of the loads' own forces (their tangent evaluation's f) to 1e-14."""
    from core_se3.model.magnetics import magnets_force
    p = _loaded(which, "numpy")
    g = _load_state(p.mesh, which)
    fa = magnets_force(p.loads, g, 0.7)
    fb = sum(ld.evaluate(g, 0.7, tangent=True).f for ld in p.loads)
    assert np.abs(fb).max() > 0 and rel(fa, fb) <= 1e-14
    assert rel(p.external(g, 0.7, tangent=False)[0], fb) <= 1e-14


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_a_state_of_the_wrong_shape_is_refused(backend):
    """The kernels index the frames and increments by node id without bounds checks: a state of
    fewer frames than nodes (another mesh's, or a slice) read memory past its end on numba (an
    'edge turns by inf rad', or a plausible residual from a view), a short eta in retract gave
    frames of garbage without an error, and NumPy raised a bare IndexError.  Both backends now
    refuse the shapes with a MeshError naming them."""
    from core_se3.errors import MeshError
    p = _loaded("nodal_dead", backend)
    n = p.mesh.n_nodes
    g = _load_state(p.mesh, "nodal_dead")
    for bad in (g[:-3].copy(), np.concatenate([g, g[:2]]), g[:, :3].copy(), g.reshape(n, 16)):
        with pytest.raises(MeshError, match=rf"shape \({', '.join(map(str, bad.shape))}\) for a mesh of {n} nodes"):
            p.evaluate(bad, 0.7)
        with pytest.raises(MeshError, match="a state of frames"):
            p.residual(bad, 0.7)
    with pytest.raises(MeshError, match=rf"increments of shape \({n - 3}, 6\)"):
        p.retract(g, np.zeros((n - 3, 6)))
    with pytest.raises(MeshError, match=rf"frames of shape \({n}, 3, 4\)"):
        p.retract(g[:, :3].copy(), np.zeros((n, 6)))
    # the right shapes in another dtype or layout: the same answer as float64 C order
    ref = p.evaluate(g, 0.7)
    for ok in (np.asfortranarray(g), g.tolist(), np.repeat(g, 2, axis=0)[::2]):
        assert rel(p.evaluate(ok, 0.7).r, ref.r) <= TOL
    assert rel(p.retract(g, np.zeros((n, 6))), g) <= TOL


class _ShapedLoad(_UserLoad):
    """_UserLoad returning its arrays in another shape (``mode``), or element blocks with a
    repeated element id."""

    def __init__(self, n, nodes, moment, mode):
        super().__init__(n, nodes, moment)
        self.mode = mode

    def evaluate(self, g, lam, tangent=True):
        ev = super().evaluate(g, lam, tangent)
        ids, Ke = ev.element_blocks
        if self.mode == "f_one_node":                     # a (6,) force: broadcast onto every node
            return LoadEvaluation(ev.f[self.nodes[0]], ev.node_blocks, ev.element_blocks)
        if self.mode == "blocks_of_the_loaded_nodes":     # (k, 6, 6): numba put them on nodes 0..k-1
            return LoadEvaluation(ev.f, ev.node_blocks[self.nodes], ev.element_blocks)
        if self.mode == "one_block":                      # (1, 6, 6): NumPy broadcast it, numba node 0
            return LoadEvaluation(ev.f, ev.node_blocks[self.nodes[:1]], ev.element_blocks)
        if self.mode == "element_past_the_mesh":          # numba wrote out of bounds (the process died)
            return LoadEvaluation(ev.f, ev.node_blocks, (np.array([0, 99]), Ke))
        if self.mode == "no_element_blocks":
            return LoadEvaluation(ev.f, ev.node_blocks)
        return LoadEvaluation(ev.f, ev.node_blocks, (np.array([4, 4]), Ke))     # "repeated_element"


@pytest.mark.parametrize("mode", ["f_one_node", "blocks_of_the_loaded_nodes", "one_block", "element_past_the_mesh"])
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_a_user_load_of_the_wrong_shapes_is_refused(mode, backend):
    """A user load's LoadEvaluation of other shapes than (n, 6), (n, 6, 6), (ids, (k, 4, 4, 6, 6))
    with ids of the mesh's elements is a LoadError naming the load and the shapes, on both
    backends.  Before: 'one_block' differed by 1.4e-3 of |K| between the backends, the blocks of
    the loaded nodes were a bare broadcast error on NumPy and landed on other nodes on numba, a
    (6,) force acted on every node on both, an element id past the mesh crashed numba."""
    from core_se3.errors import LoadError
    mesh = M.rectangle(1.5, 1.0, 3, 2)
    p = Problem(mesh, Material(1.0e4, 0.3, 0.1), backend=backend)
    p.clamp("x0")
    p.add(_ShapedLoad(mesh.n_nodes, [5, 6, 9], (0.3, -0.2, 0.9), mode))
    g = _load_state(mesh, "user_load")
    with pytest.raises(LoadError, match=r"load 'load' \(_ShapedLoad\): its evaluate returned"):
        p.evaluate(g, 0.7)


def test_element_blocks_of_a_repeated_element_add_up_on_both_backends():
    """Element blocks listing an element twice add twice on both backends (NumPy's Ke[ids] +=
    blocks kept one of them: the element part summed to 3 on NumPy, 6 on numba)."""
    mesh = M.rectangle(1.5, 1.0, 3, 2)
    g = _load_state(mesh, "user_load")
    K = {}
    for backend in ("numpy", "numba"):
        for mode in ("repeated_element", "no_element_blocks"):
            p = Problem(mesh, Material(1.0e4, 0.3, 0.1), backend=backend)
            p.clamp("x0")
            p.add(_ShapedLoad(mesh.n_nodes, [5, 6, 9], (0.3, -0.2, 0.9), mode))
            K[backend, mode] = p.evaluate(g, 0.7).K.toarray()
    assert not np.isin(mesh.quads[4, :2], mesh.node_set("x0")).any()           # its blocks (0, 1) are free
    for backend in ("numpy", "numba"):
        # the block eye(3) at (corner 0, corner 1) of element 4, twice
        assert abs((K[backend, "repeated_element"] - K[backend, "no_element_blocks"]).sum() - 6.0) <= 1e-9
    assert rel(K["numba", "repeated_element"], K["numpy", "repeated_element"]) <= TOL


def test_the_tangent_out_array_is_checked():
    """Problem.evaluate(..., out=data) on numba: the kernels write the tangent into ``out`` by
    position without bounds checks.  Before, a short array was written past its end (then a bare
    scipy ValueError, or a crash), an int array truncated K to whole numbers (3.6e-3 of |K| off,
    silently), a float32 one rounded it (7e-8).  Now each is an OptionError; a right array that
    is not zero is overwritten, and K shares it."""
    from core_se3.errors import OptionError
    p = _loaded("surface_follower", "numba")
    g = p.apply_prescribed(_load_state(p.mesh, "surface_follower"), 0.7)
    ref = p.evaluate(g, 0.7).K.copy()
    nnz = p.assembler().pattern().nnz
    for bad in (np.zeros(nnz // 2), np.zeros(nnz, np.float32), np.zeros(nnz, np.int64), np.zeros(2 * nnz)[::2],
                list(np.zeros(nnz))):
        with pytest.raises(OptionError, match=f"float64 array of the pattern's {nnz} entries"):
            p.evaluate(g, 0.7, out=bad)
    out = np.full(nnz, 7.0)
    K = p.evaluate(g, 0.7, out=out).K
    assert np.shares_memory(K.data, out) and abs(K - ref).max() <= TOL * abs(ref).max()


def test_load_and_support_ids_outside_the_mesh_are_refused():
    """A NodalLoad, SurfaceLoad or penalty spring built directly with ids outside the mesh: the
    kernels write their forces by id without bounds checks, so a node 99 of 12 crashed numba
    (NumPy: a bare IndexError) and a node -1 loaded the last node on both backends, silently.
    Now a LoadError (SupportError for a spring) naming the load and the range, at construction."""
    from core_se3.errors import LoadError, SupportError
    from core_se3.model.loads import SurfaceLoad
    from core_se3.model.supports import LabSpring, LabTiltSpring
    mesh = M.rectangle(1.5, 1.0, 3, 2)
    n, m = mesh.n_nodes, mesh.n_elements
    for nodes in ([3, 99], [3, -1], [3.5], [[3, 4]], [True, False]):
        with pytest.raises(LoadError, match=r"load 'nodal': nodes must be"):
            NodalLoad(n, nodes, np.ones(np.size(nodes)), force=(0.0, 0.0, 1.0))
        with pytest.raises(SupportError, match=r"support 'lab support': nodes must be"):
            LabSpring(mesh, np.array(nodes), np.array([[0.0, 0.0, 1.0]]), 10.0)
        with pytest.raises(SupportError, match=r"support 'lab tilt support': nodes must be"):
            LabTiltSpring(mesh, np.array(nodes), np.array([0.0, 0.0, 1.0]), 10.0)
    for follower, q in ((True, 2.0), (False, (0.0, 0.0, 2.0))):
        for elements in ([0, m], [-1]):
            with pytest.raises(LoadError, match=rf"elements must be ids 0 \.\.\. {m - 1} of the mesh"):
                SurfaceLoad(mesh, q, follower, elements=elements)
    assert NodalLoad(n, np.array([n - 1]), [1.0]).nodes.tolist() == [n - 1]     # the last node: fine


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_stresses_and_increments_of_the_wrong_shape_are_refused(backend):
    """The mixed iteration's element stresses (Problem.evaluate(stress=S)) and the increments of
    Problem.linear_stress are read by size: transposed, (24, m) and (6, n) were read as (m, 24)
    and (n, 6) in the wrong order (the mixed tangent 35 % off, silently, on both backends), a
    short one was a bare broadcast or index error on NumPy.  Now a MeshError naming the shapes;
    (m, 24) and flat arrays give the same answer."""
    from core_se3.errors import MeshError
    p = _loaded("surface_follower", backend)
    g = p.apply_prescribed(_load_state(p.mesh, "surface_follower"), 0.7)
    ev = p.evaluate(g, 0.7)
    S, n, m = ev.stress, p.mesh.n_nodes, p.mesh.n_elements
    eta = np.random.default_rng(4).normal(size=(n, 6))
    ref, lin = p.evaluate(g, 0.7, stress=S).K, p.linear_stress(ev, eta)
    for bad in (S.T.copy(), S[:-1], S[:, :23]):
        with pytest.raises(MeshError, match=rf"element stresses of shape .* shape \({m}, 24\)"):
            p.evaluate(g, 0.7, stress=bad)
    for bad in (eta.T.copy(), eta[:-1]):
        with pytest.raises(MeshError, match=rf"increments eta of shape .* shape \({n}, 6\)"):
            p.linear_stress(ev, bad)
    assert rel(p.evaluate(g, 0.7, stress=S.ravel()).K.data, ref.data) == 0.0
    assert rel(p.linear_stress(ev, eta.ravel()), lin) == 0.0


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_an_assembler_of_another_mesh_is_refused(backend):
    """Problem.evaluate(assembler=...) of another mesh with as many nodes (15, other quads): its
    pattern and slots put the blocks on the wrong node pairs, K 75 % off on NumPy and 120 % on
    numba, silently; of a bigger mesh, a bare IndexError / broadcast error.  Now a MeshError; an
    assembler of an equal mesh (another object, the same quads) is the problem's own."""
    from core_se3.errors import MeshError
    mesh = M.rectangle(2.0, 1.0, 4, 2)
    p = Problem(mesh, Material(1.0e4, 0.3, 0.1), backend=backend)
    p.clamp("x0")
    g = p.apply_prescribed(_load_state(mesh, "user_load"), 0.7)
    free = np.ones(6 * mesh.n_nodes, bool)
    for other in (M.rectangle(2.0, 1.0, 2, 4), M.rectangle(2.0, 1.0, 6, 2)):
        with pytest.raises(MeshError, match="the assembler is of another mesh"):
            p.evaluate(g, 0.7, assembler=Assembler(other, np.ones(6 * other.n_nodes, bool)))
    ref = p.evaluate(g, 0.7, assembler=Assembler(mesh, free)).K
    same = p.evaluate(g, 0.7, assembler=Assembler(M.rectangle(2.0, 1.0, 4, 2), free)).K
    assert abs(same - ref).max() <= TOL * abs(ref).max()


THREADED = """
import sys
import numpy as np
from core_se3 import lie, mesh as M, Problem, Material
from core_se3.fem import RegionMaterial
from core_se3.model.fields import DipoleField
m = M.rectangle(4.0, 4.0, 40, 40)
rng = np.random.default_rng(0)
g = m.g0 @ lie.exp(np.concatenate([0.02 * rng.normal(size=(m.n_nodes, 3)), 0.3 * rng.normal(size=(m.n_nodes, 3))], 1))
mat = RegionMaterial.from_regions(m.n_elements, Material(1e4, 0.3, 0.1),
                                  [(np.arange(0, m.n_elements, 3), Material(3e4, 0.2, 0.05))])
p = Problem(m, mat, backend=sys.argv[1])
p.clamp("x0")
p.add_pressure(2.0, follower=True)
p.add_edge_force("x1", (1.0, 2.0, 3.0))
p.add_magnetic((0.1, 0.0, 0.2), DipoleField((0.0, 0.5, 2.0), (0.7, 0.1, -0.6)), mu0=1e-3)
e = p.evaluate(g, 0.7)
np.savez(sys.argv[2], r=e.r, K=e.K.data)
"""


def test_one_and_two_threads_agree_to_the_bit(tmp_path):
    """The parallel drivers (1600 elements: the element kernels' colour / gather drivers and the
    follower pressure's, above their serial thresholds) give the same residual and tangent with
    one and two numba threads, bit for bit (race-free colouring; measured equal), and agree with
    NumPy to round-off (8e-15 measured).  Each count in its own interpreter (NUMBA_NUM_THREADS is
    read at numba's start)."""
    import os
    import subprocess
    import sys
    out = {}
    for name, backend, threads in (("t1", "numba", "1"), ("t2", "numba", "2"), ("np", "numpy", "1")):
        env = dict(os.environ, NUMBA_NUM_THREADS=threads, CORE_SE3_BACKEND=backend)
        r = subprocess.run([sys.executable, "-c", THREADED, backend, str(tmp_path / f"{name}.npz")], env=env,
                           capture_output=True, text=True, timeout=900)
        assert r.returncode == 0, r.stderr[-2000:]
        out[name] = np.load(tmp_path / f"{name}.npz")
    assert np.array_equal(out["t1"]["r"], out["t2"]["r"]) and np.array_equal(out["t1"]["K"], out["t2"]["K"])
    assert rel(out["t2"]["r"], out["np"]["r"]) <= TOL and rel(out["t2"]["K"], out["np"]["K"]) <= TOL
