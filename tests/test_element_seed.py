"""The seed's scheme (``--element seed``): centroid strain twist updated incrementally.

Its properties a-e are measured side by side with the default element in
``benchmarks/elements.py`` (table in docs/ELEMENTS.md); here we check that it discretises the
same mechanics: in the linear range the cantilever tip deflection matches the exact
shear-deformable (Timoshenko) value, and a failed step restores the strain state.
"""
import numpy as np
import pytest

from core_se3 import Material, Problem, mesh
from core_se3.errors import ConvergenceError


def test_seed_linear_cantilever_matches_timoshenko():
    # exact linear tip deflection v = P L^3/(3 EI) + P L/(G A) (shear factor 1, nu = 0);
    # 16 x 1 elements, P L^2/EI = 0.01 (rotation 0.005 rad: linear to 1e-5).  Both elements
    # integrate one constant strain per element along the strip, whose discretisation error is
    # about 1e-3 here (the default element gives -0.099 %), so the bar is 0.5 %.
    E, h, L, w = 1.2e6, 0.1, 10.0, 1.0
    EI = E * w * h ** 3 / 12
    P = 0.01 * EI / L ** 2
    p = Problem(mesh.rectangle(L, w, 16, 1), Material(E, 0.0, h), element="seed")
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, P))
    p.add_probe("tip", "x1")
    # the seed's tangent is not the derivative of its residual (centroid stresses, 2x2-point
    # tangent), so Newton converges only linearly: allow many iterations
    res = p.solve(steps=1, max_cutbacks=0, max_iter=600, rtol=1e-8, dtol=1e-8)
    v = res.final.probes["tip"]["u"][2]
    exact = P * L ** 3 / (3 * EI) + P * L / (0.5 * E * w * h)
    assert abs(v / exact - 1) < 5e-3
    assert res.final.iterations > 20      # linear, not quadratic, convergence (measured 235)


def test_seed_state_restored_after_failed_step():
    p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1), element="seed")
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 4.0))
    zeta_before = p.element.zeta.copy()
    with pytest.raises(ConvergenceError):
        p.solve(steps=1, max_cutbacks=0, max_iter=3)
    assert np.array_equal(p.element.zeta, zeta_before)


def test_seed_on_a_thin_mesh_says_it_locks():
    """The stress study of ``python -m comparison`` (reports/REPORT.md) found the seed's torsion
    strip 10 x 4 at L/h = 1e4 converged to 130 times the torsion constant, silently; the element
    now warns on meshes more than SEED_THIN thicknesses per element, and not below."""
    from core_se3.errors import ElementWarning
    from core_se3.fem.element_seed import SEED_THIN
    thin = Problem(mesh.rectangle(10.0, 1.0, 10, 4), Material(1.2e6, 0.0, 1e-3), element="seed")
    with pytest.warns(ElementWarning, match="thin mesh: element size / thickness = 1e\\+03"):
        thin.element
    thick = Problem(mesh.rectangle(10.0, 1.0, 10, 4), Material(1.2e6, 0.0, 1.0 / SEED_THIN * 1.01), element="seed")
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error", ElementWarning)
        thick.element


def test_seed_refuses_frames_that_jump_by_quarter_turns():
    # a mesh file's default frames on a closed sphere jump by quarter turns across cuts, which the
    # default element matches (fem.element_default, "Cuts"); the seed's scheme interpolates the
    # nodal increments in each node's own frame and cannot: once the default element it builds on
    # took the cuts, the pressurised closed sphere (R/h 100, 16 x 16 per face) came out 0.14 ... 3.6
    # times the exact displacement with element "seed", silent.  A mesh without such jumps builds.
    import sys
    import warnings
    from pathlib import Path

    import meshio

    from core_se3.errors import ElementTooDistortedError
    sys.path.insert(0, str(Path(__file__).parents[1] / "benchmarks"))
    from curved_frames import cubed_sphere
    X, q = cubed_sphere(4)
    m = mesh.from_meshio(meshio.Mesh(X, [("quad", q)]))
    with pytest.raises(ElementTooDistortedError, match=r"element 'seed' .* more than 45 deg .* use element = 'default'"):
        Problem(m, Material(6.825e7, 0.3, 0.1), element="seed").element
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        Problem(mesh.hemisphere_quarter(10.0, 18.0, 4, 4), Material(6.825e7, 0.3, 0.1), element="seed").element
