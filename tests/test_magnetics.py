"""Hard-magnetic loads: load stiffness by finite differences, conservation, objectivity, totals,
and the Zhao et al. 2019 cantilevers against the planar elastica (core_se3/data/elastica.json)."""
import re
import warnings

import numpy as np
import pytest

from core_se3 import Material, Problem, lie, mesh
from core_se3.catalogue import run_case
from core_se3.catalogue.cases_magnetic import ZHAO_BEAMS
from core_se3.errors import LoadError, LoadWarning, ScenarioError
from core_se3.model.fields import MU0, DipoleField, GradientField, Superposition, UniformField, rotating_direction
from core_se3.model.verify import tangent_fd_check

RNG = np.random.default_rng(11)


def _plate(field, Br=None, nx=4, ny=3, elements=None, clamp=True):
    m = mesh.rectangle(0.02, 0.01, nx, ny)
    p = Problem(m, Material(1.0e6, 0.3, 1.0e-3))
    if clamp:
        p.clamp("x0")
    if Br is None:
        # non-uniform magnetisation, a function of position [T]
        Br = lambda X: np.c_[0.1 + 0 * X[:, 0], 20.0 * X[:, 1], 0.05 + 3.0 * X[:, 0]]   # noqa: E731
    load = p.add_magnetic(Br, field, elements=elements)
    return p, load


def _random_state(m, amp_x=3e-3, amp_r=1.0):
    return m.g0 @ lie.exp(RNG.normal(size=(m.n_nodes, 6)) * np.r_[amp_x, amp_x, amp_x, amp_r, amp_r, amp_r])


FIELDS = {
    "uniform": UniformField((0.0, 0.02, 0.05)),
    "uniform+dipole": Superposition(UniformField((0.0, 0.02, 0.05)),
                                    DipoleField((0.3, 0.0, 1.0), (-0.01, 0.0, 0.015), scale=lambda lam: 1.0)),
    "dipole": DipoleField((0.0, 0.5, 2.0), (0.01, 0.002, -0.02)),
    "gradient": GradientField((0.01, 0.0, 0.02), [[0.5, 0.2, 0.0], [0.2, -0.3, 0.1], [0.0, 0.1, -0.2]]),
}


@pytest.mark.parametrize("name", list(FIELDS))
def test_magnetic_load_stiffness_matches_finite_differences(name):
    """-d f_ext/d eta of the couple and the force along g <- g exp(eta), at a random large-rotation
    state.  Central differences with h = 1e-6 (rotations ~1 rad, positions ~1e-2 m): truncation
    ~ h^2 / (length scale)^2 ~ 1e-8 for the dipole (|r| ~ 2e-2), ~1e-12 otherwise."""
    p, load = _plate(FIELDS[name])
    g = _random_state(p.mesh)
    n = p.mesh.n_nodes
    lam = 0.7
    _, Kn, _ = p.external(g, lam)
    h = 1e-6
    worst = 0.0
    for k in range(6 * n):
        d = np.zeros(6 * n)
        d[k] = h
        d = d.reshape(-1, 6)
        fd = -(p.external(g @ lie.exp(d), lam, tangent=False)[0] - p.external(g @ lie.exp(-d), lam, tangent=False)[0]) / (2 * h)
        i = k // 6
        col = np.zeros((n, 6))
        col[i] = Kn[i][:, k % 6]
        worst = max(worst, np.abs(col - fd).max())
    scale = np.abs(Kn).max()
    assert worst <= (1e-6 if "dipole" in name else 1e-8) * scale


def test_full_tangent_with_magnetic_load_matches_finite_differences():
    p, _ = _plate(FIELDS["dipole"], nx=3, ny=2)
    g = _random_state(p.mesh, 1e-3, 0.5)
    err, _, _ = tangent_fd_check(p, g, lam=1.0)
    assert err < 1e-6


@pytest.mark.parametrize("name", list(FIELDS))
def test_magnetic_load_is_conservative(name):
    """f = -dU/deta with U = -sum_i (R_i mu_i) . B(phi_i): the couple and force derive from the
    magnetic potential energy of the nodal dipoles (curl-free fields)."""
    p, load = _plate(FIELDS[name])
    g = _random_state(p.mesh)
    mag = load.mag

    def U(gg):
        m = mag.current(gg)
        return -np.einsum("ki,ki->", m, load.field.value(gg[mag.nodes, :3, 3], 1.0))

    f = p.external(g, 1.0, tangent=False)[0]
    h = 1e-6
    for k in RNG.choice(6 * p.mesh.n_nodes, 25, replace=False):
        d = np.zeros(6 * p.mesh.n_nodes)
        d[k] = h
        d = d.reshape(-1, 6)
        dU = (U(g @ lie.exp(d)) - U(g @ lie.exp(-d))) / (2 * h)
        assert -dU == pytest.approx(f.ravel()[k], abs=1e-7 * np.abs(f).max())


def test_magnetic_load_is_objective():
    """Rotating body and field sources together by Q leaves the body-frame loads unchanged."""
    Q = lie.exp_so3(np.array([2.0, -7.0, 13.0]))           # many turns
    G = np.array([[0.5, 0.2, 0.0], [0.2, -0.3, 0.1], [0.0, 0.1, -0.2]])
    B0 = np.array([0.01, 0.0, 0.02])
    p, _ = _plate(GradientField(B0, G))
    q, _ = _plate(GradientField(Q @ B0, Q @ G @ Q.T))
    g = _random_state(p.mesh)
    h = np.eye(4)
    h[:3, :3] = Q
    f1, K1, _ = p.external(g, 1.0)
    f2, K2, _ = q.external(h @ g, 1.0)
    assert np.abs(f1 - f2).max() <= 1e-12 * np.abs(f1).max()
    assert np.abs(K1 - K2).max() <= 1e-12 * np.abs(K1).max()


@pytest.mark.parametrize("turning", [False, True])
def test_a_lab_fixed_field_does_not_turn_with_the_body(turning):
    """The complement of objectivity: the body turned by Q in a lab-fixed uniform field (its
    magnetisation turning with it, B^r_t = R_t R_0^T B^r_0) sees, in its own frames, the field
    turned by Q^T -- f(Q g; B) = f(g; Q^T B), loads and load stiffness -- and not the field it saw
    before (its couple changes by 1.25 of itself here, 0.14 in the turning field); with a field
    turning with lam (fields.rotating_direction) alike.  Measured 1.8e-16 .. 2.5e-16."""
    Q = lie.exp_so3(np.array([2.0, -7.0, 13.0]))
    B = np.array([0.0, 0.02, 0.05])
    if turning:
        field = lambda R: UniformField(R @ B, direction=(lambda d: lambda lam: R @ d(lam))(      # noqa: E731
            rotating_direction((0.3, 1.0, 0.2), (1.0, 0.0, 0.0), 0.37)))
    else:
        field = lambda R: UniformField(R @ B)                                                    # noqa: E731
    p, _ = _plate(field(np.eye(3)))
    q, _ = _plate(field(Q.T))
    g = _random_state(p.mesh)
    T = np.eye(4)
    T[:3, :3] = Q
    f1, K1, _ = p.external(T @ g, 0.8)
    f2, K2, _ = q.external(g, 0.8)
    f0 = p.external(g, 0.8)[0]
    assert np.abs(f1 - f2).max() <= 1e-12 * np.abs(f1).max()
    assert np.abs(K1 - K2).max() <= 1e-12 * np.abs(K1).max()
    assert np.abs(f1 - f0)[:, 3:].max() > 0.1 * np.abs(f0[:, 3:]).max()


def _lab_totals(g, f):
    R = g[:, :3, :3]
    F = np.einsum("nij,nj->ni", R, f[:, :3])
    M = np.einsum("nij,nj->ni", R, f[:, 3:]) + np.cross(g[:, :3, 3], F)
    return F.sum(0), M.sum(0)


def test_free_plate_in_a_uniform_gradient_field_gets_the_total_force():
    """Reference configuration, piecewise-constant Br per element: the assembled nodal forces sum to
    (1/mu0) int (Br . grad) Ba dV = (h/mu0) sum_e A_e G Br_e (G uniform: exact)."""
    G = np.array([[0.4, -0.1, 0.2], [-0.1, 0.1, 0.0], [0.2, 0.0, -0.5]])
    m = mesh.rectangle(0.03, 0.01, 6, 2)
    Br = RNG.normal(size=(m.n_elements, 3)) * 0.1
    p = Problem(m, Material(1.0e6, 0.3, 1.0e-3))
    p.add_magnetic(Br, GradientField((0.0, 0.01, 0.0), G))
    f, _, _ = p.external(m.g0, 1.0, tangent=False)
    F, _ = _lab_totals(m.g0, f)
    area = (0.03 / 6) * (0.01 / 2)
    expected = 1.0e-3 / MU0 * area * (G @ Br.sum(0))
    assert np.allclose(F, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())


def test_free_plate_in_a_uniform_field_gets_a_pure_couple():
    m = mesh.rectangle(0.03, 0.01, 6, 2)
    Br, Ba = np.array([0.1, 0.02, -0.05]), np.array([0.0, 0.03, 0.04])
    p = Problem(m, Material(1.0e6, 0.3, 1.0e-3))
    p.add_magnetic(Br, UniformField(Ba))
    g = _random_state(m, 0.0, 0.0)                         # reference configuration
    f, _, _ = p.external(g, 1.0, tangent=False)
    F, M = _lab_totals(g, f)
    C = 1.0e-3 / MU0 * 0.03 * 0.01 * np.cross(Br, Ba)       # (h/mu0) A Br x Ba
    assert np.abs(F).max() == 0.0
    assert np.allclose(M, C, rtol=1e-12)


def test_magnetisation_forms_agree_and_only_magnetised_nodes_are_loaded():
    m = mesh.rectangle(0.03, 0.01, 6, 2)
    Br = np.array([0.1, 0.0, 0.05])
    field = UniformField((0.0, 0.0, 0.05))
    loads = []
    for form in (Br, np.tile(Br, (m.n_elements, 1)), np.tile(Br, (m.n_nodes, 1)),
                 lambda X: np.tile(Br, (len(X), 1))):
        p = Problem(m, Material(1.0e6, 0.3, 1.0e-3))
        p.add_magnetic(form, field)
        loads.append(p.external(m.g0, 1.0, tangent=False)[0])
    for f in loads[1:]:
        assert np.allclose(f, loads[0], rtol=1e-13, atol=1e-16)
    # magnetise only the last column of elements: only their nodes carry loads and stiffness
    p = Problem(m, Material(1.0e6, 0.3, 1.0e-3))
    last = np.nonzero(m.X[m.quads].mean(1)[:, 0] > 0.025)[0]
    load = p.add_magnetic(Br, field, elements=last)
    assert set(load.mag.nodes.tolist()) == set(np.unique(m.quads[last]).tolist())
    out = p.output_fields(m.g0, 1.0)
    Bn = np.linalg.norm(out["magnetisation_Br"], axis=1)
    assert np.allclose(Bn[load.mag.nodes], np.linalg.norm(Br)) and np.all(Bn[np.setdiff1d(np.arange(m.n_nodes), load.mag.nodes)] == 0)


def test_magnetisation_forms_agree_on_regions_of_different_thickness(tmp_path):
    """A shell whose thickness differs between regions gets one magnetic load per thickness; a
    magnetisation per node (a table or a node Br_file) or a function of position used to be
    broadcast to one row per element (ValueError / TypeError from NumPy).  Every form of the same
    uniform B^r must give the nodal loads of the 3-vector exactly (the same integrals), h / mu0
    taken per region: the total couple is (1/mu0) sum_regions h A Br x Ba."""
    from core_se3 import scenario
    from core_se3.fem.material import RegionMaterial
    m = mesh.rectangle(0.04, 0.01, 4, 1)
    law = RegionMaterial.from_regions(4, Material(1.0e6, 0.0, 1.0e-3), {(2, 3): Material(1.0e6, 0.0, 2.0e-3)})
    Br, field = np.array([0.1, 0.0, 0.05]), UniformField((0.0, 0.0, 0.05))
    loads = []
    for form in (Br, np.tile(Br, (m.n_elements, 1)), np.tile(Br, (m.n_nodes, 1)),
                 lambda X: np.tile(Br, (len(X), 1))):
        p = Problem(m, law)
        assert len(p.add_magnetic(form, field, mu0=1.0)) == 2
        loads.append(p.external(m.g0, 1.0, tangent=False)[0])
    for f in loads[1:]:
        assert np.allclose(f, loads[0], rtol=1e-13, atol=1e-16)
    _, M = _lab_totals(m.g0, loads[0])
    assert np.allclose(M, (1.0e-3 + 2.0e-3) * 0.02 * 0.01 * np.cross(Br, field.B), rtol=1e-12)
    with pytest.raises(LoadError, match=r"one per node \(10, 3\).*got shape \(5, 3\)"):
        Problem(m, law).add_magnetic(np.zeros((5, 3)), field)
    # the same through a scenario: [material.regions] thickness and a node table
    (tmp_path / "Br.csv").write_text("node,Brx,Bry,Brz\n" + "".join(f"{i},0.1,0.0,0.05\n" for i in range(m.n_nodes)))
    scn = scenario.loads('units = "consistent"\n[mesh]\ngenerator = "rectangle"\nL = 0.04\nwidth = 0.01\nnx = 4\nny = 1\n'
                         '[material]\nE = 1e6\nnu = 0.0\nh = 1e-3\n[regions.tip]\nbox = { x = [0.02, 0.04] }\n'
                         '[material.regions.tip]\nh = 2e-3\n[[supports]]\ntype = "clamp"\nedge = "x0"\n'
                         '[fields.coil]\ntype = "uniform"\nB = [0.0, 0.0, 0.05]\n'
                         '[[magnets]]\nBr_file = "Br.csv"\nmu0 = 1.0\n', base_dir=str(tmp_path))
    f = scn.problem.external(m.g0, 1.0, tangent=False)[0]
    assert np.allclose(f, loads[0], rtol=1e-13, atol=1e-16)


def test_output_fields_of_magnets_on_adjacent_regions_are_area_means_not_sums():
    """The VTU point fields B^r_t, couple and force per unit reference area of one uniform magnet
    split into two magnets on adjacent regions equal those of the single magnet at every node
    (exact: the same nodal integrals over the same area).  Each load used to divide by its own
    area share and Problem.output_fields summed them, so the nodes the regions share showed
    2 B^r and twice the couple (1.0, 1.0, 2.0, 1.0, 1.0 T along the strip)."""
    m = mesh.rectangle(0.04, 0.01, 4, 2)
    field = GradientField((0.01, 0.0, 0.02), [[0.5, 0.2, 0.0], [0.2, -0.3, 0.1], [0.0, 0.1, -0.2]])
    Br = (0.1, 0.0, 0.05)
    g = _random_state(m, 1e-3, 0.3)
    one = Problem(m, Material(1.0e6, 0.3, 1.0e-3))
    one.add_magnetic(Br, field)
    two = Problem(m, Material(1.0e6, 0.3, 1.0e-3))
    left = np.nonzero(m.X[m.quads].mean(1)[:, 0] < 0.02)[0]
    two.add_magnetic(Br, field, elements=left)
    two.add_magnetic(Br, field, elements=np.setdiff1d(np.arange(m.n_elements), left))
    a, b = one.output_fields(g, 0.7), two.output_fields(g, 0.7)
    assert set(a) == set(b) == {"magnetisation_Br", "magnetic_couple", "magnetic_force"}
    for k in a:
        assert np.allclose(b[k], a[k], rtol=1e-13, atol=1e-13 * np.abs(a[k]).max()), k
    Bn = np.linalg.norm(b["magnetisation_Br"], axis=1)
    assert np.allclose(Bn, np.linalg.norm(Br), rtol=1e-13)         # |B^r_t| = |B^r_0| everywhere


def test_output_br_of_one_material_in_two_fields_is_its_br_not_the_sum():
    """The walker's spelling (examples/walker.toml): a magnet per field on each region, the
    same B^r, against one magnet per region in the superposed field -- the same loads, so the
    same couple, force and B^r_t at every node (exact but for the additions' order).  Before,
    the VTU field magnetisation_Br summed the two magnets of a region over its area: 0.156 T
    where the material has 0.078 (the couple was right)."""
    m = mesh.rectangle(4.0, 1.5, 8, 2)
    V = UniformField((0.0, 0.0, 0.003))
    H = GradientField((0.0005, 0.0, 0.0), [[0.01, 0.0, 0.0], [0.0, -0.01, 0.0], [0.0, 0.0, 0.0]])
    rear = np.nonzero(m.X[m.quads].mean(1)[:, 0] < 2.0)[0]
    parts = [(rear, (0.078, 0.0, 0.0156)), (np.setdiff1d(np.arange(m.n_elements), rear), (-0.078, 0.0, 0.0156))]
    two, one = (Problem(m, Material(0.07, 0.0, 0.2)) for _ in range(2))
    for els, Br in parts:
        for f in (V, H):
            two.add_magnetic(Br, f, elements=els, mu0=MU0 * 1e6)
        one.add_magnetic(Br, Superposition(V, H), elements=els, mu0=MU0 * 1e6)
    g = _random_state(m, 1e-2, 0.3)
    a, b = one.output_fields(g, 0.7), two.output_fields(g, 0.7)
    for k in a:
        assert np.allclose(b[k], a[k], rtol=1e-13, atol=1e-13 * np.abs(a[k]).max()), (k, b[k][:2], a[k][:2])
    Bn = np.linalg.norm(b["magnetisation_Br"], axis=1)
    mid = np.abs(m.X[:, 0] - 2.0) < 1e-12              # where +x and -x meet: the mean, (0, 0, 0.0156)
    assert np.allclose(Bn[~mid], np.hypot(0.078, 0.0156), rtol=1e-13)
    assert np.allclose(Bn[mid], 0.0156, rtol=1e-12)


def test_element_selections_are_masks_or_ids_given_once():
    """A boolean mask over the elements was cast to the ids 0 and 1 (mask [T, F, F, T]: elements
    1, 0, 0, 1, total dipole 0.4 instead of 0.2), a repeated id magnetised its element twice and
    a fractional id was truncated -- all silently.  The mask now selects its True elements (the
    same loads as their ids, exactly), and repeated or fractional ids are LoadErrors; gravity
    uses the same selection."""
    m = mesh.rectangle(4.0, 1.0, 4, 1)
    field = UniformField((0.0, 0.0, 1.0))
    mask = m.X[m.quads].mean(1)[:, 0] > 2.0                  # elements 2 and 3
    p, q = Problem(m, Material(1e3, 0.0, 0.1)), Problem(m, Material(1e3, 0.0, 0.1))
    a = p.add_magnetic((1.0, 0.0, 0.0), field, elements=mask, mu0=1.0)
    q.add_magnetic((1.0, 0.0, 0.0), field, elements=[2, 3], mu0=1.0)
    assert a.mag.elements.tolist() == [2, 3] and np.allclose(a.mag.total_lab, (0.2, 0.0, 0.0), rtol=1e-14)
    assert np.array_equal(p.external(m.g0, 1.0, tangent=False)[0], q.external(m.g0, 1.0, tangent=False)[0])
    for bad, match in (([0, 0, 1], "element 0 more than once"), ([0.5], "whole numbers"),
                       (mask[:2], "one entry per element")):
        with pytest.raises(LoadError, match=match):
            Problem(m, Material(1e3, 0.0, 0.1)).add_magnetic((1.0, 0.0, 0.0), field, elements=bad, mu0=1.0)
        with pytest.raises(LoadError, match=match):
            Problem(m, Material(1e3, 0.0, 0.1, rho=1.0)).add_gravity(elements=bad)


@pytest.mark.parametrize("kw, match", [
    (dict(Br=(0.0, np.nan, 0.1)), "non-finite"),
    (dict(Br=np.zeros((5, 3))), "shape"),
    (dict(field="0.05 T"), "Field"),
    (dict(mu0=-1.0), "mu0"),
    (dict(elements=[10 ** 6]), "do not exist"),
    # a string where numbers belong: NumPy's bare ValueError / TypeError before, naming nothing
    (dict(Br="x"), "Br must be numbers"),
    (dict(Br=("a", "b", "c")), "Br must be numbers"),
    (dict(mu0="x"), "mu0 must be a positive number"),
    (dict(elements="nope"), r"elements='nope' \(a region name or element ids\): unknown region"),
])
def test_bad_magnetic_input_raises_load_error(kw, match):
    m = mesh.rectangle(0.03, 0.01, 6, 2)
    p = Problem(m, Material(1.0e6, 0.3, 1.0e-3))
    args = dict(Br=(0.1, 0.0, 0.0), field=UniformField((0, 0, 0.05)))
    args.update(kw)
    with pytest.raises(LoadError, match=match):
        p.add_magnetic(**args)


def test_zero_magnetisation_warns_naming_the_magnet(tmp_path):
    """Br = 0 (a user's slip, or the start of a sweep) adds no load: before, silently (no
    magnetised node, no warning); now a LoadWarning in Python, and in a scenario file a
    ScenarioWarning naming magnets[i].Br and the region.  A non-zero Br says nothing."""
    m = mesh.rectangle(0.03, 0.01, 6, 2)
    m.regions["tip"] = np.array([5, 11])
    p = Problem(m, Material(1.0e6, 0.3, 1.0e-3))
    with pytest.warns(LoadWarning, match="Br is zero on elements='tip'"):
        ld = p.add_magnetic((0.0, 0.0, 0.0), UniformField((0, 0, 0.05)), elements="tip")
    assert len(ld.mag.nodes) == 0
    with pytest.warns(LoadWarning, match="Br is zero on the whole shell"):
        p.add_magnetic(lambda X: 0.0 * X, UniformField((0, 0, 0.05)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p.add_magnetic((0.0, 0.0, 1e-9), UniformField((0, 0, 0.05)))
    from core_se3 import scenario
    text = ('name = "z"\nunits = "SI"\n[mesh]\ngenerator = "rectangle"\nL = 0.03\nwidth = 0.01\nnx = 6\nny = 2\n'
            '[regions.tip]\nbox = { x = [0.025, 0.03] }\n[material]\nE = 1e6\nnu = 0.3\nh = 1e-3\n'
            '[[supports]]\ntype = "clamp"\nedge = "x0"\n[fields.b]\ntype = "uniform"\nB = [0.0, 0.0, 0.05]\n'
            '[[magnets]]\nregion = "tip"\nBr = [0.0, 0.0, 0.0]\n')
    (tmp_path / "z.toml").write_text(text)
    said = [str(w) for w in scenario.load(tmp_path / "z.toml").warnings]
    assert any("[magnets[0].Br]" in w and "Br is zero on region 'tip'" in w for w in said), said


def test_zero_applied_field_warns_naming_the_field(tmp_path):
    """A magnet in a field of B = 0 (a slip, a misspelt value, the start of a sweep) adds no load
    at any load factor: before, silently (no warning in Python or in a file, load number 0, every
    step converged at u = 0); now a LoadWarning in Python and a ScenarioWarning at fields.NAME.B,
    as a zero Br; a field zero only at some points (a gradient's) or a tiny one says nothing, and
    [design] varying the field may start at zero."""
    from core_se3 import scenario
    from core_se3.model.fields import GradientField
    m = mesh.rectangle(0.03, 0.01, 6, 2)
    p = Problem(m, Material(1.0e6, 0.3, 1.0e-3))
    p.clamp("x0")
    with pytest.warns(LoadWarning, match="the applied field is zero on the whole shell"):
        p.add_magnetic((0.1, 0.0, 0.0), UniformField((0.0, 0.0, 0.0)))
    with pytest.warns(LoadWarning, match="the applied field is zero on elements=\\[0, 1\\]"):
        p.add_magnetic((0.1, 0.0, 0.0), GradientField((0.0, 0.0, 0.0), np.zeros((3, 3))), elements=[0, 1])
    assert np.abs(p.solve(steps=1).final.g - m.g0).max() == 0.0         # indeed no load
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p.add_magnetic((0.1, 0.0, 0.0), UniformField((0.0, 0.0, 1e-12)))
        p.add_magnetic((0.1, 0.0, 0.0), GradientField((0.0, 0.0, 0.0), np.diag([1e-3, -1e-3, 0.0]),
                                                       x0=(0.0, 0.0, 0.0)))
    base = {"name": "z", "units": "SI", "mesh": {"generator": "rectangle", "L": 0.03, "width": 0.01, "nx": 6, "ny": 2},
            "regions": {"tip": {"box": {"x": [0.025, 0.03]}}}, "material": {"E": 1e6, "nu": 0.3, "h": 1e-3},
            "supports": [{"type": "clamp", "edge": "x0"}], "fields": {"b": {"type": "uniform", "B": [0.0, 0.0, 0.0]}},
            "magnets": [{"region": "tip", "Br": [0.1, 0.0, 0.0]}], "probes": [{"name": "tip", "edge": "x1"}]}
    (tmp_path / "z.toml").write_text(scenario.dumps(base))
    said = [str(w) for w in scenario.load(tmp_path / "z.toml").warnings]
    assert len(said) == 1 and "[fields.b.B]: the applied field 'b' is zero on region 'tip'" in said[0], said
    assert "magnets[0] in it adds no load" in said[0]
    with pytest.raises(ScenarioError, match=r"\[fields.b.B\]: the applied field 'b' is zero"):
        scenario.load(tmp_path / "z.toml", strict=True)
    ok = dict(base, fields={"b": {"type": "uniform", "B": [0.0, 0.0, 0.01]}})
    assert scenario.from_dict(ok).warnings == []
    design = dict(base, design={"variables": [{"type": "field", "field": "b", "free": ["z"]}],
                                "targets": [{"type": "position", "probe": "tip", "value": [0.03, 0.0, 0.001]}]})
    assert scenario.from_dict(design).warnings == []


def test_gravity_total_and_bad_density():
    m = mesh.rectangle(0.04, 0.03, 4, 3)
    p = Problem(m, Material(4e5, 0.49, 7e-4))
    p.add_gravity(1470.0)
    f, _, _ = p.external(m.g0, 1.0, tangent=False)
    F, _ = _lab_totals(m.g0, f)
    assert np.allclose(F, (0, 0, -1470.0 * 7e-4 * 9.81 * 0.04 * 0.03), rtol=1e-12)
    with pytest.raises(LoadError, match="density"):
        p.add_gravity(-1.0)


# ------------------------------------------------------------------ Zhao et al. 2019 cantilevers
@pytest.mark.parametrize("L, h, nx", ZHAO_BEAMS)
@pytest.mark.parametrize("angle, entry", [(90.0, "3_magnetic_perpendicular_field"),
                                          (135.0, "3_magnetic_field_135deg")])
def test_zhao_cantilever_nu0_matches_the_elastica(L, h, nx, angle, entry):
    """nu = 0 reduces the strip exactly to the rod EI th'' + c0 sin(beta - th) = 0 of
    elastica.json (3_magnetic_*: n = 0, so no shear correction).  The issue's bar: 0.5 % of the
    largest tip displacement up to A Br Ba L^2/(mu0 E I) = 20, on the seed's meshes (nodal
    quadrature and the element are second order; measured 0.40 % on the coarsest, 10-element beam,
    0.10 % on 20)."""
    doc, _, _ = run_case("magnetic-cantilever", mesh=(nx, 1),
                         overrides=dict(L=L, h=h, nu=0.0, field_angle_deg=angle))
    assert doc["reference"]["entry"] == entry
    assert doc["reference"]["error_up_to_load_20"] <= 0.005
    loads = [s["load"]["dimensionless"] for s in doc["steps"]]
    assert max(loads) >= min(20.0, 7.5)      # the path reaches the bar's load (7.6 for the 11 mm beam)


def test_zhao_cantilever_converges_at_second_order():
    e = [run_case("magnetic-cantilever", mesh=(n, 1), overrides=dict(L=11.0, h=1.1, nu=0.0))[0]["reference"]["error"]
         for n in (10, 20)]
    assert np.log2(e[0] / e[1]) == pytest.approx(2.0, abs=0.2)


@pytest.mark.parametrize("L, h, nx", ZHAO_BEAMS)
def test_zhao_cantilever_nu048_lies_between_beam_and_plate_stiffness(L, h, nx):
    """The seed's material (nu = 0.480) on a width-resolved mesh (2 nx x 4): the tip deflection
    lies between the beam-stiffness ('tip') and plate-stiffness ('tip_plate') answers of
    3_magnetic_zhao2019_L..mm_h..mm at every field value."""
    doc, _, _ = run_case("magnetic-cantilever", mesh=(2 * nx, 4), overrides=dict(L=L, h=h))
    br = doc["bracket"]
    assert len(br["rows"]) == 20
    assert br["all_inside"], [r for r in br["rows"] if not r["inside"]][:3]


def test_antiparallel_field_buckles_at_pi2_over_4_and_follows_the_elastica():
    """3_magnetic_antiparallel_field: critical load pi^2/4 (the clamped-free Euler column), bar 1 %;
    post-buckled tip within 1 % of L for loads >= 1.3 x critical (the issue's bars)."""
    doc, _, _ = run_case("magnetic-antiparallel")
    c = doc["critical"]
    assert abs(c["error"]) <= 0.01
    assert doc["perfect_branch"]["max_error_over_L_at_load_ge_1p3_critical"] <= 0.01
    # the imperfect branch (tilted field) turns the tip past 90 deg at the largest load
    assert doc["steps"][-1]["probes"]["tip"]["rotation_angle"] > np.pi / 2


def test_newton_converges_quadratically_in_a_dipole_field():
    m = mesh.rectangle(0.02, 0.005, 10, 2)
    p = Problem(m, Material(1.0e6, 0.0, 5e-4))
    p.clamp("x0")
    p.add_magnetic((0.1, 0.0, 0.0), DipoleField((0.0, 0.0, 5.0), (0.03, 0.0, 0.0)))
    p.add_probe("tip", "x1")
    res = p.solve(steps=2)
    # r_{k+1} <= C r_k^2 (C = 10, as in test_solver) for every pair above the round-off floor
    # (relative residual 1e-12 ~ 1e4 eps); observed 0.43, 0.060, 5.7e-3, 1.8e-6, 2.1e-11, 1.0e-13
    h = res.steps[-1].residual_history
    pairs = [(h[k], h[k + 1]) for k in range(len(h) - 1) if h[k + 1] > 1e-12 and h[k] < 0.1]
    assert len(pairs) >= 2 and all(b <= 10.0 * a * a for a, b in pairs), h
    assert abs(res.final.probes["tip"]["u"][2]) > 1e-4       # the dipole bends it visibly


@pytest.mark.parametrize("name, mesh", [("magnetic-plate", "4x3"), ("magnetic-gripper", "4x2")])
def test_plate_and_gripper_run_from_the_cli_and_write_plots_and_vtu(tmp_path, name, mesh):
    """Predictions (no reference data): the CLI writes the load-deflection plot, the final shape and
    a VTU series with the magnetisation and the magnetic couple; the reactions balance the loads."""
    import json

    import meshio

    from core_se3.cli import main
    out = tmp_path / name
    rc = main(["bench", "run", name, "--mesh", mesh, "--steps", "5", "--plot", str(out / "tip.png"),
               "--vtu", str(out / "vtu"), "--json", str(out / "res.json")])
    assert rc == 0
    assert (out / "tip.png").stat().st_size > 0 and (out / "tip_shape.png").stat().st_size > 0
    doc = json.loads((out / "res.json").read_text())
    assert max(s["balance_error"] for s in doc["steps"]) < 1e-8
    last = meshio.read(out / "vtu" / "step_0005.vtu")
    Br = np.linalg.norm(last.point_data["magnetisation_Br"], axis=1)
    assert Br.max() > 0 and np.abs(last.point_data["magnetic_couple"]).max() > 0
    assert np.abs(last.point_data["displacement"]).max() > 0.1       # mm: it moved visibly


def test_rotating_field_ends_on_the_elastica_of_its_final_direction():
    """A field of fixed magnitude turning from 90 to 135 deg as the load factor grows (the couple
    is conservative, so the end state is path independent) ends where a fixed 135 deg field puts
    the beam: the 3_magnetic_field_135deg elastica at the same load (nu = 0, 19.2 x 1.1 mm beam,
    load 10; bar 0.5 % as for the fixed-field cantilever)."""
    from core_se3.catalogue.family_magnetic import MU0_MM, dimensionless_load
    from core_se3.catalogue.references import elastica_entry
    p = dict(L=19.2, h=1.1, Br=0.143, E=0.8969246350124951)
    Ba = 10.0 / dimensionless_load(p, 1.0)
    m = mesh.rectangle(p["L"], 5.0, 15, 1)
    prob = Problem(m, Material(p["E"], 0.0, p["h"]))
    prob.clamp("x0")
    prob.add_probe("tip", "x1")
    # lam in [0, 1/2]: the perpendicular field (+z) ramps up; lam in [1/2, 1]: it turns about -y by
    # an eighth of a turn (90 -> 135 deg from +x) at full magnitude
    turn = rotating_direction((0.0, -1.0, 0.0), (0.0, 0.0, 1.0), turns_per_unit=1.0 / 4, lam0=0.5)
    prob.add_magnetic((p["Br"], 0.0, 0.0),
                      UniformField((0.0, 0.0, Ba), scale=lambda lam: min(1.0, 2 * lam),
                                   direction=lambda lam: turn(max(lam, 0.5))), mu0=MU0_MM)
    res = prob.solve(steps=20)
    e = elastica_entry("3_magnetic_field_135deg")
    k = e["load"].index(10.0)
    u = res.final.probes["tip"]["u"]
    ref = p["L"] * np.array([e["tip"]["u"][k], e["tip"]["v"][k]])
    scale = p["L"] * max(np.hypot(e["tip"]["u"][j], e["tip"]["v"][j]) for j in range(k + 1))
    assert np.hypot(u[0] - ref[0], u[2] - ref[1]) <= 0.005 * scale
    # and it did move through the 90-degree state first: the tip angle grows with the field's turn
    angles = [s.probes["tip"]["w"] @ np.array([0.0, -1.0, 0.0]) for s in res.steps]
    assert np.all(np.diff(angles) > 0) and angles[-1] > np.pi / 2


def test_a_field_turned_in_big_steps_is_followed_not_jumped_to_another_equilibrium():
    """examples/rotating-field.toml's strip (Zhao's beam, 20x1) in a 5 mT field that ramps up
    over lam in [0, 0.1] and then turns a whole turn about +y.  The strip has several stable
    states in the same field (it is dragged round by the turn), so a load step may only turn
    the field so far: with 4 steps (100 deg each) Newton used to converge at lam = 1 on another
    equilibrium, the tip 12.4 mm from the path's state.  Tries now turn the field by at most
    MAX_LOAD_TURN (pi/4): every step count ends on the path of 40 steps (10 deg each) -- to
    round-off, the states of a conservative couple being the same equilibria -- and a field
    scaled through zero (reversed, not turned) is not split."""
    from core_se3.catalogue.family_magnetic import MU0_MM
    from core_se3.solvers.newton import MAX_LOAD_TURN

    def strip():
        prob = Problem(mesh.rectangle(17.2, 5.0, 20, 1), Material(0.8969, 0.4801, 0.42))
        prob.clamp("x0")
        prob.add_probe("tip", "x1")
        turn = rotating_direction((0.0, 1.0, 0.0), (0.0, 0.0, 1.0), turns_per_unit=1 / 0.9, lam0=0.1, lam1=1.0)
        ld = prob.add_magnetic((0.143, 0.0, 0.0), UniformField((0.0, 0.0, 0.005), scale=lambda lam: min(1.0, lam / 0.1),
                                                               direction=turn), mu0=MU0_MM)
        return prob, ld
    fine = {round(s.load_factor, 9): s.probes["tip"]["u"] for s in strip()[0].solve(steps=40).steps}
    for steps in (4, 1):
        res = strip()[0].solve(steps=steps)
        assert len(res.log) >= 8                             # split into tries of <= pi/4
        for s in res.steps:
            assert np.abs(s.probes["tip"]["u"] - fine[round(s.load_factor, 9)]).max() < 1e-9 * 17.2
    prob, ld = strip()
    assert ld.direction_turn(prob.mesh.g0, 0.1, 1.0) == pytest.approx(2 * np.pi, rel=1e-12)
    assert ld.direction_turn(prob.mesh.g0, 0.1, 0.1 + 0.9 / 8) <= MAX_LOAD_TURN + 1e-12
    m = mesh.rectangle(2.0, 1.0, 2, 1)
    reversing = Problem(m, Material(1.0, 0.0, 0.1)).add_magnetic((1.0, 0, 0), UniformField((0, 0, 1.0), scale=lambda lam: 2 * lam - 1),
                                                      mu0=1.0)
    assert reversing.direction_turn(m.g0, 0.0, 1.0) == 0.0


def test_a_field_turning_whole_turns_between_samples_is_not_measured_as_still():
    """direction_turn measured a step's turn at 16 samples, each at most pi (the angle between two
    directions): 16 whole turns in one step measured 0 and 15.9 turns 0.63 rad, so the split
    rule let the step through.  A session of examples/rotating-field.toml's strip at load factor
    0.1 (full field, not turned) then took update(lam=1.0) -- the field turning 16 times -- in one
    sub-step and returned its start as converged; the path meets a limit point near 0.16 (a
    load-stepped solve stops there).  The turn of a field rotating in a plane at a constant rate
    is 2 pi turns exactly; the session now refuses the command there."""
    from core_se3.catalogue.family_magnetic import MU0_MM
    from core_se3.control import Session
    from core_se3.errors import ControlError

    def strip(turns):
        prob = Problem(mesh.rectangle(17.2, 5.0, 20, 1), Material(0.8969, 0.4801, 0.42))
        prob.clamp("x0")
        prob.add_probe("tip", "x1")
        turn = rotating_direction((0.0, 1.0, 0.0), (0.0, 0.0, 1.0), turns_per_unit=turns / 0.9, lam0=0.1, lam1=1.0)
        ld = prob.add_magnetic((0.143, 0.0, 0.0), UniformField((0.0, 0.0, 0.005), scale=lambda lam: min(1.0, lam / 0.1),
                                                               direction=turn), mu0=MU0_MM)
        return prob, ld
    for turns in (1.0, 8.0, 15.9, 16.0, 32.0):
        prob, ld = strip(turns)
        assert ld.direction_turn(prob.mesh.g0, 0.1, 1.0) == pytest.approx(2 * np.pi * turns, rel=1e-9)
    prob, _ = strip(16.0)
    s = Session(prob, 0.1)
    before = s.state
    with pytest.raises(ControlError, match="could not be followed beyond load factor 0.1[56]"):
        s.update(lam=1.0)
    assert s.state is before


def test_a_dipole_near_a_coarse_magnet_is_reported():
    """The nodal quadrature of a dipole's couple and force is off by about (element size /
    distance)^2 when the dipole is within a few element sizes of the magnet.  A strip 1 x 0.1
    clamped at x = 0 with a dipole 0.05 above its tip: refined along the strip only (160 x 1, the
    width 0.1 one element) its tip deflection converged to 3.89e-5 against 2.12e-5 on 160 x 16
    -- 83 % off -- without a word.  The solve now ends with a MeshWarning naming the distance in
    element sizes and the estimate; none when the dipole is 10 sizes away or more."""
    from core_se3.errors import MeshWarning

    def strip(nx, ny, height):
        p = Problem(mesh.rectangle(1.0, 0.1, nx, ny), Material(1e4, 0.0, 0.01))
        p.clamp("x0")
        p.add_magnetic((1.0, 0.0, 0.0), DipoleField((0.0, 0.0, 1.6e-8), (1.0, 0.05, height), mu0=1.0), mu0=1.0)
        return p
    p = strip(40, 1, 0.05)
    with pytest.warns(MeshWarning, match=r"lies 0.5\d* element sizes from the magnetised node .* off by about"):
        res = p.solve(steps=2)
    from core_se3.model.magnetics import dipole_resolution
    ratio, node, _ = dipole_resolution(p.loads, res.final.g, 1.0)
    assert np.isclose(np.linalg.norm(res.final.g[node, :3, 3] - (1.0, 0.05, 0.05)), ratio * 0.1, rtol=1e-12)
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error", MeshWarning)
        strip(10, 1, 1.5).solve(steps=2)                      # 1.5 away, elements 0.1: 15 sizes


@pytest.mark.parametrize("kind", ["uniform", "gradient", "dipole"])
def test_equilibrium_is_objective_and_flips_with_the_field(kind):
    """Guard (passed before): the whole solve, not only the load, is objective -- the mesh, the
    field's sources and the magnetisation moved by a rigid motion (rotation of several turns'
    axis, and a shift) give the moved equilibrium to round-off (measured 4e-15 of the tip
    displacement) -- and in a uniform field, reversing B^a or B^r mirrors the equilibrium
    (the couple changes sign), reversing both leaves it, exactly."""
    from core_se3.mesh.core import Mesh
    Q = lie.exp_so3(np.array([0.3, -1.1, 0.7]))
    t = np.array([0.2, -0.5, 1.0])
    G = np.array([[5.0, 2.0, 0.0], [2.0, -3.0, 1.0], [0.0, 1.0, -2.0]]) * 0.5

    def solve(moved, Br=(1.0, 0.3, 0.5), B=(0.0, 10.0, 25.0)):
        m = mesh.rectangle(1.0, 0.2, 8, 2)
        q, s = (Q, t) if moved else (np.eye(3), np.zeros(3))
        if moved:
            H = np.eye(4)
            H[:3, :3], H[:3, 3] = Q, t
            m = Mesh(H @ m.g0, m.quads, dict(m.edges), m.shape, dict(m.regions))
        p = Problem(m, Material(1e6, 0.3, 0.01))
        p.clamp("x0")
        p.add_probe("tip", "x1")
        field = {"uniform": lambda: UniformField(q @ B),
                 "gradient": lambda: GradientField(q @ B, q @ G @ q.T, x0=q @ (0.5, 0.0, 0.3) + s),
                 "dipole": lambda: DipoleField(q @ (0.0, 0.0, 1e5), q @ (2.5, 0.1, 0.4) + s, mu0=1.0)}[kind]()
        p.add_magnetic(q @ np.asarray(Br), field, mu0=1.0)
        return p.solve(steps=4).final.probes["tip"]["u"]
    u = solve(False)
    assert np.abs(Q @ u - solve(True)).max() <= 1e-12 * np.abs(u).max()
    if kind == "uniform":
        mirror = np.array([1.0, -1.0, -1.0])                  # the reflection y, z -> -y, -z of the strip
        assert np.abs(solve(False, Br=(1.0, 0.0, 0.0), B=(0.0, 0.0, -30.0))
                      - mirror * solve(False, Br=(1.0, 0.0, 0.0), B=(0.0, 0.0, 30.0))).max() <= 1e-12
        assert np.abs(solve(False, Br=(-1.0, -0.3, -0.5), B=(0.0, -10.0, -25.0)) - u).max() <= 1e-12 * np.abs(u).max()


def _torus(R=3.0, r=1.0, nu=8, nv=6):
    """A closed torus of nu x nv quads: as many nodes as elements (48)."""
    from core_se3.mesh.core import Mesh, frames_from
    u, v = np.meshgrid(2 * np.pi * np.arange(nu) / nu, 2 * np.pi * np.arange(nv) / nv, indexing="ij")
    X = np.stack([(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u), r * np.sin(v)], -1).reshape(-1, 3)
    d1 = np.stack([-np.sin(u), np.cos(u), 0 * u], -1).reshape(-1, 3)
    d3 = np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    at = lambda a, b: (a % nu) * nv + (b % nv)                                      # noqa: E731
    return Mesh(frames_from(X, d1, d3), np.stack([at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)],
                                                 -1).reshape(-1, 4))


def test_a_br_table_that_fits_per_element_and_per_node_needs_br_per():
    """On a closed torus (48 nodes, 48 elements) a per-node Br table (B^r on node 0 alone) was
    read per element, silently: element 0 magnetised (4 magnetised nodes) where the node table
    magnetises the 4 elements around node 0 (9 nodes).  Now refused without Br_per, naming it;
    Br_per='node' / 'element' pick the table; a 3-vector and unambiguous tables need no keyword."""
    from core_se3 import Problem
    m = _torus()
    assert m.n_nodes == m.n_elements == 48
    Br = np.zeros((48, 3))
    Br[0, 2] = 1.0
    def magnet(**kw):
        p = Problem(m, Material(1e4, 0.3, 0.05))
        return p.add_magnetic(Br, UniformField((0.0, 0.0, 1.0)), mu0=1.0, **kw).mag
    with pytest.raises(LoadError, match=r"fits both.*Br_per='element' or Br_per='node'"):
        magnet()
    assert len(magnet(Br_per="node").nodes) == 9 and len(magnet(Br_per="element").nodes) == 4
    with pytest.raises(LoadError, match=r"per node must have shape \(48, 3\)"):
        Problem(m, Material(1e4, 0.3, 0.05)).add_magnetic(Br[:5], UniformField((0.0, 0.0, 1.0)), Br_per="node")
    p = Problem(m, Material(1e4, 0.3, 0.05))
    assert len(p.add_magnetic(Br[:10], UniformField((0.0, 0.0, 1.0)), elements=np.arange(10), mu0=1.0).mag.nodes) == 4
    assert len(p.add_magnetic((0.0, 0.0, 1.0), UniformField((0.0, 0.0, 1.0)), mu0=1.0).mag.nodes) == 48


_DIPOLE_SCENE = '''units = "{u}"
[mesh]
generator = "rectangle"
L = {L}
width = {w}
nx = 10
ny = 2
[material]
E = {E}
nu = 0.3
h = {h}
[[supports]]
type = "clamp"
edge = "x0"
[fields.magnet]
type = "dipole"
m = [0.0, 0.0, {m}]
x0 = [{L}, {y0}, 0.05{z0}]
[[magnets]]
Br = [0.1, 0.0, 0.0]
[[probes]]
name = "tip"
edge = "x1"
'''


def test_a_dipole_scene_in_si_and_in_n_mm_mpa_agree_and_the_python_dipole_needs_mu0_times_1e3():
    """A strip 20 x 5 x 0.5 mm (E = 1 MPa, B^r = 0.1 T) under a 1 A m^2 dipole 50 mm above its
    tip: the scenario in SI (m, Pa, A m^2) and in N-mm-MPa (mm, MPa, A mm^2; the magnets' mu0
    MU0 * 1e6, the dipole's MU0 * 1e3) give the same tip displacement to round-off (observed
    3e-16).  The Python dipole in mm: MU0 * 1e3 gives the SI field in T; the magnets' MU0 * 1e6,
    which the docs used to name for every N-mm-MPa model, gives 1000 times it."""
    from core_se3 import scenario
    si = scenario.loads(_DIPOLE_SCENE.format(u="SI", L=0.02, w=0.005, E=1e6, h=0.0005, m=1.0, y0=0.0025, z0=""))
    mm = scenario.loads(_DIPOLE_SCENE.format(u="N-mm-MPa", L=20.0, w=5.0, E=1.0, h=0.5, m=1e6, y0=2.5, z0="e3"))
    a, b = (s.problem.solve(steps=4).final.probes["tip"]["u"] for s in (si, mm))
    assert abs(b[2]) > 0.1                                    # a visible deflection [mm]
    assert np.abs(1e3 * a - b).max() <= 1e-12 * np.abs(b).max()
    x = np.array([[0.01, 0.002, 0.003]])
    B_si = DipoleField((0.0, 0.0, 1.0), (0.02, 0.0025, 0.05)).value(x, 1.0)
    B_mm = DipoleField((0.0, 0.0, 1e6), (20.0, 2.5, 50.0), mu0=MU0 * 1e3).value(1e3 * x, 1.0)
    assert np.abs(B_mm - B_si).max() <= 1e-14 * np.abs(B_si).max()
    fd = mm.problem.scenario_parts["fields"]["magnet"]
    assert fd.k == MU0 * 1e3 / (4 * np.pi)                    # the scenario's dipole in mm


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_a_node_on_a_point_dipole_is_named_with_both_positions(backend):
    """A magnetised node exactly at a point dipole's position: the LoadError said only 'a point
    lies on the dipole' (no node, no position, on every evaluation path).  Now it names the node,
    its position and the dipole's: the residual, the tangent, and the dipole inside a
    superposition."""
    pytest.importorskip("numba") if backend == "numba" else None
    m = mesh.rectangle(0.02, 0.01, 4, 2)
    node = 7
    x0 = m.g0[node, :3, 3].tolist()
    for field in (DipoleField((0.0, 0.0, 1e-3), x0), Superposition(UniformField((0, 0, 1e-3)),
                                                                  DipoleField((0.0, 0.0, 1e-3), x0))):
        p = Problem(m, Material(1.0e6, 0.3, 1.0e-3), backend=backend)
        p.clamp("x0")
        p.add_magnetic((0.1, 0.0, 0.0), field)
        for tangent in (False, True):
            with pytest.raises(LoadError, match=re.escape(f"magnetised node {node} (at {x0}) lies on the point "
                                                          f"dipole at x0 = {x0}")):
                p.evaluate(m.g0, 1.0, tangent=tangent)
    with pytest.raises(LoadError, match=re.escape(f"point 1 (at {x0}) lies on the dipole at x0 = {x0}")):
        DipoleField((0.0, 0.0, 1e-3), x0).value(np.array([[0.0, 0.0, 0.0], x0]), 1.0)


def test_a_user_field_with_a_curl_in_the_body_is_said_at_add_magnetic():
    """The magnets' couple and force (B^r . grad) B^a hold for a field without currents or sources
    in the body; a UserField with a curl as large as its gradient was taken as given (check_field
    existed, nothing called it).  Now add_magnetic warns, naming the curl; a curl-free user field
    and the built-in fields say nothing."""
    from core_se3.model.fields import UserField
    c = 10.0
    value = lambda x: np.c_[np.zeros(len(x)), np.zeros(len(x)), 0.01 + c * x[:, 0]]
    curl = UserField(value, lambda x: np.broadcast_to(np.array([[0, 0, 0], [0, 0, 0], [c, 0, 0.0]]), x.shape + (3,)))
    free = UserField(lambda x: value(x) + np.c_[c * x[:, 2], 0 * x[:, :2]],
                     lambda x: np.broadcast_to(np.array([[0, 0, c], [0, 0, 0], [c, 0, 0.0]]), x.shape + (3,)))
    said = {}
    for name, field in (("curl", curl), ("free", free), ("gradient", GradientField((0, 0, 0.01), np.diag([c, -c, 0.0])))):
        p = Problem(mesh.rectangle(0.0172, 0.005, 10, 1), Material(E=0.8969e6, nu=0.0, h=0.42e-3))
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            p.add_magnetic(Br=(0.143, 0.0, 0.0), field=field)
        said[name] = [str(w.message) for w in seen if issubclass(w.category, LoadWarning)]
        assert all(w.filename == __file__ for w in seen)                  # said at the caller's line
    assert len(said["curl"]) == 1 and re.search(r"relative \|curl B\| 1\.00e\+00, \|div B\| 0\.00e\+00", said["curl"][0])
    assert said["free"] == [] and said["gradient"] == []


def test_br_frame_along_d1_across_the_cuts_of_a_files_frames_is_refused(tmp_path):
    """A magnet's Br_frame gives components along each element's reference directors, the mean
    of its nodes' frames.  A mesh file's default frames on a closed doubly curved shell follow a
    cross field, whose d1 jumps by quarter turns across cuts: there the mean frame is no director
    of any node (on the closed cubed sphere, 4 x 4 per face, up to 40 deg off every node's d1 and
    d2 on 30 of its 96 elements) and "along d1" differs from element to element by quarter turns;
    such a magnet was built without a word.  Now in-plane components there are a ScenarioError
    naming magnets[0].Br_frame; along d3 alone it is built, and so is an in-plane one on a mesh
    without cuts."""
    import sys
    from pathlib import Path

    import meshio

    from core_se3 import scenario
    sys.path.insert(0, str(Path(__file__).parents[1] / "benchmarks"))
    from curved_frames import cubed_sphere
    X, q = cubed_sphere(4)
    meshio.write(tmp_path / "sphere.vtk", meshio.Mesh(X, [("quad", q)]))
    base = ('units = "consistent"\n[mesh]\nfile = "sphere.vtk"\n[material]\nE = 6.825e7\nnu = 0.3\nh = 0.1\n'
            '[[supports]]\ntype = "clamp"\nnodes = [0]\n[fields.coil]\ntype = "uniform"\nB = [0.0, 0.0, 0.05]\n'
            '[[magnets]]\nmu0 = 1.0\nBr_frame = ')
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ScenarioError, match=r"\[magnets\[0\]\.Br_frame\]: .*turn by quarter turns across cuts "
                                                r"\(30 of its elements"):
            scenario.loads(base + "[0.1, 0.0, 0.0]\n", base_dir=str(tmp_path))
        assert len(scenario.loads(base + "[0.0, 0.0, 0.1]\n", base_dir=str(tmp_path)).problem.loads) == 1
    dome = scenario.loads(base.replace('file = "sphere.vtk"', 'generator = "hemisphere_quarter"\nR = 10.0\nhole_deg = 18.0\nnt = 4\nnf = 4')
                          + "[0.1, 0.0, 0.0]\n", base_dir=str(tmp_path))
    assert len(dome.problem.loads) == 1


def test_a_br_or_field_in_mt_given_as_tesla_warns_in_python_too(tmp_path):
    """|B^r| or |B^a| above 2 T (mT meant, or M in A/m given as B^r) in the Python API: before,
    the scenario's plausibility check said it but ``Problem.add_magnetic`` ran Zhao's strip with
    Br = 143 (0.143 T in mT) to a converged tip 1000 times too strongly loaded without a word; now
    a LoadWarning for a mu0 in tesla units (SI's MU0, N-mm-MPa's MU0 * 1e6), none for plausible
    values or for own consistent units (mu0 = 1), and a scenario says it once, at its key."""
    from core_se3 import scenario
    m = mesh.rectangle(0.0172, 0.005, 6, 1)
    p = Problem(m, Material(0.8969e6, 0.0, 0.42e-3))
    with pytest.warns(LoadWarning, match=r"\|Br\| = 143 T exceeds 2 T .*did you give mT\?"):
        p.add_magnetic((143.0, 0.0, 0.0), UniformField((0.0, 0.0, 0.01)))
    with pytest.warns(LoadWarning, match=r"applied field reaches \|B\| = 50 T at load factor 1"):
        p.add_magnetic((0.0, 0.0, 0.143), UniformField((0.0, 0.0, 50.0)), mu0=MU0 * 1e6)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p.add_magnetic((0.143, 0.0, 0.0), UniformField((0.0, 0.0, 0.05)))
        p.add_magnetic((0.143, 0.0, 0.0), DipoleField((0.0, 0.0, 1.0), (0.0, 0.0, 0.01)))   # 0.1 mT on the strip
        p.add_magnetic((143.0, 0.0, 0.0), UniformField((0.0, 0.0, 50.0)), mu0=1.0)        # own units
        mm = Problem(mesh.rectangle(17.2, 5.0, 6, 1), Material(0.8969, 0.0, 0.42))        # N, mm, MPa
        mm.add_magnetic((0.143, 0.0, 0.0), UniformField((0.0, 0.0, 0.05)), mu0=MU0 * 1e6)
    # the same strip in mm and MPa without mu0 (SI's, stresses in Pa): its loads were 1e6 times
    # too strong, and a weak field (1e-8 T, load number 2.5e-5) bent it to u = (-12.4, 0, 15.2) mm
    with pytest.warns(LoadWarning, match=r"mu0 = 1.25664e-06 makes stresses Pa, so E = 0.8969 is 0.897 Pa"):
        mm.add_magnetic((0.143, 0.0, 0.0), UniformField((0.0, 0.0, 1e-8)))
    with pytest.warns(LoadWarning, match=r"makes stresses MPa, so E = 896900 is 8.97e\+11 Pa"):
        p.add_magnetic((0.143, 0.0, 0.0), UniformField((0.0, 0.0, 0.05)), mu0=MU0 * 1e6)   # SI E, mm's mu0
    # a dipole in mm with SI's mu0 (the default): its field 1000 times too weak; the magnets' 1e6: too strong
    for k, times in ((1.0, "0.001"), (1e6, "1000")):
        with pytest.warns(LoadWarning, match=rf"has mu0 = {MU0 * k:.6g}, but with the magnets' mu0 = 1.25664 \(N-mm-MPa\) a "
                                             rf"dipole's is 0.00125664 .* its field is {times} times the meant one"):
            mm.add_magnetic((0.143, 0.0, 0.0), DipoleField((0.0, 0.0, 1e6), (17.2, 2.5, 50.0), mu0=MU0 * k), mu0=MU0 * 1e6)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mm.add_magnetic((0.143, 0.0, 0.0), DipoleField((0.0, 0.0, 1e6), (17.2, 2.5, 50.0), mu0=MU0 * 1e3), mu0=MU0 * 1e6)
    text = ('name = "t"\nunits = "SI"\n[mesh]\ngenerator = "rectangle"\nL = 0.0172\nwidth = 0.005\nnx = 6\nny = 1\n'
            '[material]\nE = 0.8969e6\nnu = 0.0\nh = 0.42e-3\n[[supports]]\ntype = "clamp"\nedge = "x0"\n'
            '[fields.b]\ntype = "uniform"\nB = [0.0, 0.0, 0.01]\n[[magnets]]\nBr = [143.0, 0.0, 0.0]\n')
    (tmp_path / "t.toml").write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error", LoadWarning)
        said = [str(w) for w in scenario.load(tmp_path / "t.toml").warnings]
    br = [w for w in said if "143 T" in w]
    assert len(br) == 1 and "[magnets[0]]" in br[0] and not any("Br is zero" in w for w in said), said
    # units = "consistent" (no plausibility check of its own) with SI's mu0 and E in MPa: said at the magnet
    text = text.replace('units = "SI"', 'units = "consistent"').replace("L = 0.0172\nwidth = 0.005", "L = 17.2\nwidth = 5.0")
    text = text.replace("E = 0.8969e6", "E = 0.8969").replace("h = 0.42e-3", "h = 0.42").replace("[143.0,", "[0.143,")
    (tmp_path / "t.toml").write_text(text + f"mu0 = {MU0!r}\n")
    said = [str(w) for w in scenario.load(tmp_path / "t.toml").warnings]
    assert [w.split(": ", 1)[1] for w in said if "makes stresses" in w] == [
        "[magnets[0]]: mu0 = 1.25664e-06 makes stresses Pa, so E = 0.8969 is 0.897 Pa, outside the range of real solids "
        "(10 Pa .. 700 GPa): give mu0 in the units of E (fields.MU0 for Pa, MU0 * 1e6 for N-mm-MPa)"], said
