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


def test_d1_turning_within_quads_is_a_mesh_warning():
    # the tube's axis and its circumferential direction give d1 without turn (the same answer to
    # round-off); a hint 3 deg off the normal +x turns d1 by 79 deg near theta = 0 and moves the
    # tip by 4.6 % of its travel (ux by 8 %), the normal itself (the default +x) by 180 deg
    axis, said = _read([0.0, 0.0, 1.0])
    assert said == []
    ref = _tip(axis)
    around, said = _read([0.0, 1.0, 0.0])
    assert said == [] and np.allclose(_tip(around), ref, rtol=1e-9, atol=1e-9 * np.linalg.norm(ref))
    tilted, said = _read([1.0, 0.0, 0.05])
    assert len(said) == 1 and "turns by 79 deg" in said[0] and "d1_hint" in said[0]
    assert np.linalg.norm(_tip(tilted) - ref) / np.linalg.norm(ref) == pytest.approx(0.046, abs=0.005)
    _, said = _read([1.0, 0.0, 0.0])
    assert len(said) == 1 and "turns by 180 deg" in said[0]


def test_flat_and_shipped_meshes_keep_d1_and_stay_silent():
    import os

    import core_se3
    here = os.path.join(os.path.dirname(core_se3.__file__), "..", "examples")
    for name in ("gripper.msh", "star-gripper.msh"):
        with warnings.catch_warnings():
            warnings.simplefilter("error", MeshWarning)
            m = from_meshio(os.path.join(here, name))
        assert np.allclose(m.g0[:, :3, 0], [1.0, 0.0, 0.0])
