"""The nodal frames of a curved mesh from a file: d1 is d1_hint projected on each node's tangent
plane, so where the hint is nearly normal to the shell d1 turns fast, up to 180 deg within one
quad.  The elements interpolate in the nodal frames, so that changed the answer for an isotropic
material without a word (review finding; the warning tests fail on the code before)."""
import warnings

import meshio
import numpy as np
import pytest

from core_se3 import Material, Problem
from core_se3.errors import MeshWarning
from core_se3.mesh.readers import from_meshio

pytestmark = pytest.mark.core


def _half_tube():
    """A half cylinder of radius 1 about z, theta in [-60, 60] deg (d3 = +x on theta = 0), 4
    long, 8 x 8 quads; clamped at z = 0."""
    th = np.radians(np.linspace(-60.0, 60.0, 9))
    X = np.array([[np.cos(t), np.sin(t), z] for z in np.linspace(0.0, 4.0, 9) for t in th])
    q = np.array([[j * 9 + i, j * 9 + i + 1, (j + 1) * 9 + i + 1, (j + 1) * 9 + i] for j in range(8) for i in range(8)])
    return meshio.Mesh(X, [("quad", q)])


def _read(hint):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = from_meshio(_half_tube(), d1_hint=hint)
    return m, [str(w.message) for w in caught if issubclass(w.category, MeshWarning)]


def _tip(m):
    p = Problem(m, Material(1e6, 0.3, 0.02))
    p.clamp(lambda X: X[:, 2] < 1e-9)
    tip = np.flatnonzero(np.isclose(m.X[:, 2], 4.0))
    p.add_nodal_load(tip, force=[1e-4 / len(tip), 1e-4 / len(tip), 0.0])
    return p.solve_linear().displacements()[tip, :3].mean(0)


def test_d1_turning_within_quads_of_a_developable_shell_does_not_matter():
    # the tube's axis and its circumferential direction give d1 without turn (the same answer to
    # round-off); a hint 3 deg off the normal +x turns d1 by 79 deg near theta = 0 and had moved
    # the tip by 4.6 % of its travel (ux by 8 %), the normal itself (the default +x) by 180 deg and
    # had stopped the solve.  The element's least-turn gauge (mesh.gauge) makes the frames of a
    # developable shell parallel: both give the axis' answer (measured 2.1e-12 and 5.8e-12)
    axis, said = _read([0.0, 0.0, 1.0])
    assert said == []
    ref = _tip(axis)
    for hint in ([0.0, 1.0, 0.0], [1.0, 0.0, 0.05], [1.0, 0.0, 0.0]):
        m, said = _read(hint)
        assert said == [] and np.linalg.norm(_tip(m) - ref) <= 1e-10 * np.linalg.norm(ref), hint


def _cap():
    """A spherical cap (radius 1, polar angle 0.3 ... 0.9, azimuth -0.6 ... 0.6), 8 x 8 quads."""
    t, f = np.linspace(0.3, 0.9, 9), np.linspace(-0.6, 0.6, 9)
    X = np.array([[np.sin(a) * np.cos(b), np.sin(a) * np.sin(b), np.cos(a)] for a in t for b in f])
    q = np.array([[j * 9 + i, j * 9 + i + 1, (j + 1) * 9 + i + 1, (j + 1) * 9 + i] for j in range(8) for i in range(8)])
    return meshio.Mesh(X, [("quad", q)])


def test_d1_turning_within_quads_of_a_doubly_curved_shell_is_a_mesh_warning():
    # a doubly curved part keeps the user's frames (mesh.gauge): a hint along the normal at the
    # cap's centre flips d1 by 180 deg within a quad, which the reader names (the solve then stops
    # with ElementTooDistortedError); a hint along the parallels is silent
    for hint, n_warnings in (([0.0, 1.0, 0.0], 0), ([np.sin(0.6), 0.0, np.cos(0.6) + 0.02], 1)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            m = from_meshio(_cap(), d1_hint=hint)
        said = [str(w.message) for w in caught if issubclass(w.category, MeshWarning)]
        assert not m.gauge_angles.any() and len(said) == n_warnings
    assert "turns by 180 deg" in said[0] and "doubly curved" in said[0]


def test_flat_and_shipped_meshes_keep_d1_and_stay_silent():
    import os

    import core_se3
    here = os.path.join(os.path.dirname(core_se3.__file__), "..", "examples")
    for name in ("gripper.msh", "star-gripper.msh"):
        with warnings.catch_warnings():
            warnings.simplefilter("error", MeshWarning)
            m = from_meshio(os.path.join(here, name))
        assert np.allclose(m.g0[:, :3, 0], [1.0, 0.0, 0.0])
