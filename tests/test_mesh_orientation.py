"""Mesh files whose quads are oriented oppositely where the edge check cannot see it: separate
parts, or the two sides of a cut (distinct nodes at one point).  The normal d3 is the right-hand
side of each quad's node order and a follower pressure acts along it, so such a file pushed half
the shell the other way without a word (review finding; the warning tests fail on the code
before)."""
import warnings

import meshio
import numpy as np
import pytest

from core_se3 import Material, Problem, scenario
from core_se3.errors import MeshWarning
from core_se3.mesh.readers import from_meshio

pytestmark = pytest.mark.core


def _two_strips(flip, gap):
    """Two 4 x 1 strips along x, side by side in y (the second at y = 1 + gap: gap = 0 puts it
    against the first, its own nodes on the common line), the second's quads reversed if flip."""
    X = np.array([[x, y, 0.0] for y in (0.0, 1.0) for x in np.linspace(0.0, 4.0, 5)])
    q = np.array([[i, i + 1, i + 6, i + 5] for i in range(4)])
    q2 = q + 10
    return meshio.Mesh(np.r_[X, X + [0.0, 1.0 + gap, 0.0]], [("quad", np.r_[q, q2[:, ::-1] if flip else q2])])


def _read(raw, hint=(1.0, 0.0, 0.0)):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = from_meshio(raw, d1_hint=hint)
    return m, [str(w.message) for w in caught if issubclass(w.category, MeshWarning)]


def _tip_deflections(m):
    """The x = 4 deflections of both strips clamped at x = 0 under a follower pressure."""
    p = Problem(m, Material(1e6, 0.0, 0.05))
    p.clamp(lambda X: X[:, 0] < 1e-9)
    p.add_pressure(-1e-3, follower=True)
    u = p.solve_linear().displacements()
    tip = np.flatnonzero(np.isclose(m.X[:, 0], 4.0))          # the first strip's nodes are 0 ... 9
    return u[tip[tip < 10], 2], u[tip[tip >= 10], 2]


def test_separate_parts_facing_opposite_ways_are_a_mesh_warning():
    # the same pressure bends the consistently oriented strips both down by q L^4 / 8 EI =
    # 3.07e-3; with the second strip's node order reversed it goes up by as much, silently before
    m, said = _read(_two_strips(flip=True, gap=0.5))
    first, second = _tip_deflections(m)
    assert first == pytest.approx(-3.07e-3, rel=0.01) and second == pytest.approx(-first, rel=1e-6)
    assert len(said) == 1 and "2 separate parts" in said[0] and "faces opposite" in said[0]
    assert "[0.0, 0.0, 1.0]" in said[0] and "[0.0, 0.0, -1.0]" in said[0] and "reverse" in said[0]
    m, said = _read(_two_strips(flip=False, gap=0.5))
    assert said == [] and np.allclose(np.r_[_tip_deflections(m)], first[0], rtol=1e-6)


def test_a_cut_between_opposite_orientations_is_a_mesh_warning():
    # the strips' common line y = 1 is two rows of nodes at one point: the cut warning said so,
    # but not that the sides' normals are opposite (the edge check sees only shared nodes)
    m, said = _read(_two_strips(flip=True, gap=0.0))
    first, second = _tip_deflections(m)
    assert np.all(second > 0) and np.all(first < 0)
    assert len(said) == 2 and "distinct nodes lie at one point" in said[0]
    assert "oriented oppositely" in said[1] and "6-11" in said[1] and "separate parts" not in " ".join(said)
    _, said = _read(_two_strips(flip=False, gap=0.0))
    assert len(said) == 1 and "oriented oppositely" not in said[0]


def test_parts_that_face_each_other_only_by_curvature_are_silent():
    # a closed cylinder-like band of 8 quads (d1 along its axis) is one part whose mean normal
    # vanishes, and two separate strips at right angles (normals +z and +x) are not opposite
    th = np.linspace(0.0, 2 * np.pi, 9)[:-1]
    X = np.r_[np.c_[np.cos(th), np.sin(th), np.zeros(8)], np.c_[np.cos(th), np.sin(th), np.ones(8)]]
    band = np.array([[i, (i + 1) % 8, (i + 1) % 8 + 8, i + 8] for i in range(8)])
    assert _read(meshio.Mesh(X, [("quad", band)]), hint=(0.0, 0.0, 1.0))[1] == []
    flat = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]])
    wall = np.array([[3, 0, 0], [3, 1, 0], [3, 1, 1], [3, 0, 1.0]])
    assert _read(meshio.Mesh(np.r_[flat, wall], [("quad", np.array([[0, 1, 2, 3], [4, 5, 6, 7]]))]))[1] == []


def test_a_scenario_names_the_mesh_file_key_for_opposite_parts(tmp_path):
    _two_strips(flip=True, gap=0.5).write(tmp_path / "two.vtu")
    doc = {"mesh": {"file": "two.vtu"}, "material": {"E": 1e6, "nu": 0.0, "h": 0.05},
           "supports": [{"type": "clamp", "nodes": [0, 5, 10, 15]}],
           "loads": [{"type": "pressure", "p": 1e-3, "follower": True}]}
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        scn = scenario.from_dict(doc, base_dir=str(tmp_path))
    assert any("mesh.file" in w and "faces opposite" in w for w in map(str, scn.warnings))
