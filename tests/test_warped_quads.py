"""Warped quads (nodes not in a plane) were accepted silently: natural on a curved shell, where
the nodes' normals explain the warp, but a quad warped beyond what its normals explain (a
twisted or folded quad, nodes off the surface the normals describe) gave a wrong answer without a
word (review finding; the warning test fails on the code before: core_se3/fem/warp.py)."""
import sys
import warnings
from pathlib import Path

import meshio
import numpy as np
import pytest

from core_se3 import Material, Problem, mesh
from core_se3.errors import ElementWarning
from core_se3.fem.warp import WARN_WARP, quad_warp
from core_se3.mesh.readers import from_meshio

sys.path.insert(0, str(Path(__file__).parents[1] / "benchmarks"))
from curved_frames import cubed_sphere  # noqa: E402  (the closed cubed sphere, R 10)

pytestmark = pytest.mark.core


def _paraboloid(n, c, normals):
    """The hyperbolic paraboloid z = c x y over [-1/2, 1/2]^2 (n x n), its exact normals or
    normals left along z."""
    m = mesh.rectangle(1.0, 1.0, n, n, x0=-0.5)
    X = m.X.copy()
    X[:, 2] = c * X[:, 0] * X[:, 1]
    d3 = np.stack([-c * X[:, 1], -c * X[:, 0], np.ones(len(X))], 1) if normals == "exact" else np.tile([0, 0, 1.0], (len(X), 1))
    return mesh.Mesh(mesh.frames_from(X, np.tile([1.0, 0, 0], (len(X), 1)), d3), m.quads, edges=m.edges)


def _tip(m, h=0.01):
    p = Problem(m, Material(1e4, 0.3, h))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, h ** 3))
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        u = p.solve_linear().displacements()
    said = [str(w.message) for w in seen if issubclass(w.category, ElementWarning) and "warped" in str(w.message)]
    return float(u[np.asarray(m.node_set("x1")), 2].mean()), said


def test_a_quad_warped_beyond_its_normals_warns_and_a_curved_shells_does_not():
    # the paraboloid c = 2 on 2 x 2: every quad warped by 0.18 of its size.  With its exact normals
    # the warp is explained (to 0.015) and the answer is a coarse mesh's (0.97 of its 32 x 32);
    # with the normals left along z it was 0.47 of it -- solved and silent
    ref, said = _tip(_paraboloid(32, 2.0, "exact"))
    assert not said
    good, said = _tip(_paraboloid(2, 2.0, "exact"))
    assert not said and abs(good / ref - 1.0) < 0.05
    bad, said = _tip(_paraboloid(2, 2.0, "flat"))
    assert bad / ref < 0.6                                   # the wrong answer the warning is about
    assert len(said) == 1 and "4 element(s)" in said[0] and "0.18" in said[0]


def test_a_randomly_warped_plate_from_a_file_warns():
    # a flat plate whose interior nodes are moved off its plane at random by up to 0.1 of the
    # spacing (8 x 8), read from a file: the fitted normals cannot follow nodal-scale bumps
    # (unexplained warp up to 0.07 of the size; its edges held and pressed, it came out 0.75 of
    # the flat plate at h 0.01)
    m = mesh.rectangle(1.0, 1.0, 8, 8)
    X = m.X.copy()
    inside = (X[:, 0] > 0.01) & (X[:, 0] < 0.99) & (np.abs(X[:, 1]) < 0.49)
    X[:, 2] += np.random.default_rng(0).uniform(-0.1, 0.1, len(X)) / 8 * inside
    fm = from_meshio(meshio.Mesh(X, [("quad", m.quads)]))
    assert WARN_WARP < quad_warp(fm.X, fm.quads, fm.g0)[1].max() < 0.1
    with pytest.warns(ElementWarning, match=r"warped .* by more than their nodes' normals d3 explain"):
        Problem(fm, Material(1e4, 0.3, 0.01)).element


@pytest.mark.parametrize("make", [
    lambda: mesh.hemisphere_quarter(10.0, 18.0, 2, 2),
    lambda: mesh.cylinder_panel(10.0, 5.0, 0.0, 1.0, 2, 2),
    lambda: __import__("core_se3.catalogue.shell_course", fromlist=["x"]).twisted_mesh(12.0, 1.1, np.pi / 2, 6, 1),
    lambda: from_meshio(meshio.Mesh(*cubed_sphere(2)[:1], [("quad", cubed_sphere(2)[1])])),
])
def test_curved_generators_and_a_closed_sphere_from_a_file_are_silent(make):
    # their warp is explained by their normals to 0.008 of the quads' size (the twisted beam 6 x 1:
    # warp 0.049, unexplained 3e-4; the closed sphere 2 x 2 per face from a file: 0.022 / 0.008)
    m = make()
    assert quad_warp(m.X, m.quads, m.g0)[1].max() < 0.01
    with warnings.catch_warnings():
        warnings.simplefilter("error", ElementWarning)
        Problem(m, Material(1e4, 0.3, 0.1)).element
