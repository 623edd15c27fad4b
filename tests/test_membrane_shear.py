"""The in-plane shear of curved elements at its element mean (``fem/membrane_shear.py``, issue 30
item 2): thin coarse curved meshes without membrane locking, flat elements untouched, no
spurious zero-energy mode, a consistent tangent.

Bars: the hemisphere's bar is the issue's target (4x4 at least 0.95 of the converged value;
measured 0.980 at R/h 1e4, 0.979 at 1e5; before 0.626 and 0.017); the converged value is the
element's own 64x64 at the same thickness (128x128 gives 1.0013 and 1.0033 of it, checked by
hand).  Zero modes and the tangent: exact properties (bars as
tests/test_element.py).
"""
import numpy as np
import pytest

from core_se3 import Material, Problem, lie, mesh
from core_se3.catalogue import shell_course as sc
from core_se3.model import verify


def _no_mean(monkeypatch):
    """Switch the correction off (the tied shear of main before item 2)."""
    import core_se3.fem.element_default as ed
    monkeypatch.setattr(ed, "shear_retention", lambda z0, *a: np.ones(len(z0)))


def _ratio(n, rh):
    def val(k):
        p, meas = sc.pinched_hemisphere(k, h=10.0 / rh)
        return meas(p.solve_linear())
    return val(n) / val(64)


@pytest.mark.parametrize("rh", [1e4, 1e5])
def test_thin_coarse_hemisphere_does_not_lock(rh):
    assert 0.95 <= _ratio(4, rh) <= 1.02


def test_thin_coarse_hemisphere_locks_without_the_mean(monkeypatch):
    """Negative control: the tied shear's variation locks the 4x4 hemisphere at R/h 1e4 (0.734;
    0.626 before the enhanced membrane modes of ``membrane_enhanced``, whose symmetric shear
    modes relax part of it)."""
    _no_mean(monkeypatch)
    assert _ratio(4, 1e4) < 0.8


def test_flat_elements_keep_the_tied_shear_to_the_bit(monkeypatch):
    """beta = 1 on a flat distorted mesh: Dbar is the one without the correction, bit for bit
    (Cook's membrane and the flat patch tests unchanged)."""
    m = mesh.rectangle(2.0, 1.0, 4, 3)
    rng = np.random.default_rng(2)
    m.g0[:, :2, 3] += rng.uniform(-0.08, 0.08, (m.n_nodes, 2))
    law = Material(1e6, 0.3, 0.01)
    el = Problem(m, law).element
    assert np.all(el.shear_beta == 1.0) and el.drill_Ek.any()
    _no_mean(monkeypatch)
    assert np.array_equal(el.Dbar_packed, Problem(m, law).element.Dbar_packed)


@pytest.mark.parametrize("kind", ["cylinder 3x3", "hemisphere 4x4"])
@pytest.mark.parametrize("drilling", [0.0, 1.0])
def test_no_spurious_zero_mode_on_thin_curved_patches(kind, drilling, monkeypatch):
    """h = 1e-3 on unit-size curved patches (chi ~ 100: beta ~ 3e-3).  Exactly six zero modes at
    the default drilling modulus, as with the tied shear; at drilling = 0 the cylinder has the
    count of the tied shear (7: its one drilling mode of main), where the full element mean
    (beta = 0) gives 11: the kept part beta of the variation is what holds the drilling
    gradients.  At drilling = 0 the hemisphere has 7 as well, where the tied shear (with the
    drilling correction at full strength) has 6: the correction is kept with the same beta since
    at full strength it locked thin doubly curved meshes (docs/ELEMENTS.md, "Doubly curved
    shells"); a zero drilling modulus leaves that drilling mode free, the default holds it."""
    m = mesh.cylinder_arch(1.0, 1.0, 1.0, 3, 3) if kind.startswith("cyl") else mesh.hemisphere_quarter(1.0, 18.0, 4, 4)
    law = Material(1e6, 0.3, 1e-3, drilling=drilling)
    p = Problem(m, law)
    assert p.element.shear_beta.max() < 0.01
    nzero = verify.zero_modes(p)[1]
    if drilling:
        assert nzero == 6
    import core_se3.fem.element_default as ed
    retention = ed.shear_retention
    monkeypatch.setattr(ed, "shear_retention", lambda z0, *a: np.zeros(len(z0)))       # the full mean
    full = verify.zero_modes(Problem(m, law))[1]
    monkeypatch.setattr(ed, "shear_retention", retention)
    _no_mean(monkeypatch)
    tied = verify.zero_modes(Problem(m, law))[1]
    if drilling or kind.startswith("cyl"):
        assert nzero == tied
    else:
        assert (nzero, tied) == (7, 6)
    if not drilling and kind.startswith("cyl"):
        assert full == 11


def test_curved_mesh_keeps_a_consistent_tangent_and_both_backends_agree():
    """A coarse thin hemisphere (beta 0.006 .. 0.011) at a large-rotation state: the tangent matches
    central differences (bar 1e-6 as tests/test_element.py) and the numba backend the NumPy
    one (residual and tangent, 1e-12 as tests/test_kernels.py)."""
    m = mesh.hemisphere_quarter(1.0, 18.0, 3, 3)
    law = Material(1.0e6, 0.3, 0.005)
    p = Problem(m, law, backend="numpy")
    assert p.element.shear_beta.max() < 0.02
    rng = np.random.default_rng(4)
    g = lie.exp(np.r_[rng.normal(size=3), 8.0 * np.array([0.6, 0.0, 0.8])]) @ m.g0 \
        @ lie.exp(np.c_[0.005 * rng.normal(size=(m.n_nodes, 3)), 0.2 * rng.normal(size=(m.n_nodes, 3))])
    err, _, _ = verify.tangent_fd_check(p, g, 1.0, h=1e-6, free_all=True)
    assert err < 1e-6, err
    q = Problem(m, law, backend="numba")
    from core_se3.assembly import Assembler
    asm = Assembler(m, np.ones(6 * m.n_nodes, bool))
    Ka, Kb = p.tangent(g, 1.0, asm).toarray(), q.tangent(g, 1.0, asm).toarray()
    assert np.abs(Ka - Kb).max() <= 1e-12 * np.abs(Ka).max()
