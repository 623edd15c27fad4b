"""Mesh files whose surfaces share a line only in space (distinct nodes at one point): the shell
is cut there; the reader says so (review finding; the tests fail on the code before)."""
import warnings

import meshio
import numpy as np
import pytest

from core_se3 import Material, Problem, scenario
from core_se3.errors import MeshWarning
from core_se3.mesh.readers import from_meshio

pytestmark = pytest.mark.core


def _two_strips(merged):
    """Two 4 x 1 strips on [0, 4] and [4, 8] x [0, 1], their common line's nodes shared or not."""
    xs = np.linspace(0.0, 8.0, 9)
    X = np.array([[x, y, 0.0] for y in (0.0, 1.0) for x in xs])
    ids = np.arange(18).reshape(2, 9)
    quads = np.array([[ids[0, i], ids[0, i + 1], ids[1, i + 1], ids[1, i]] for i in range(8)])
    if not merged:                                   # the right strip gets its own copy of x = 4
        X = np.vstack([X, X[[4, 13]]])
        quads[4:][quads[4:] == 4], quads[4:][quads[4:] == 13] = 18, 19
    return meshio.Mesh(X, [("quad", quads)])


def test_distinct_nodes_at_one_point_are_a_mesh_warning_and_the_merged_file_is_silent():
    # the cut shell is two cantilevers: clamped at x = 0 and x = 8 under a pressure, the cut
    # mesh deflects 3.07e-3 at x = 4 against 9.60e-4 merged (3.2 times: q L^4 / 8 EI of the
    # half against q (2 L)^4 / 384 EI), and the old reader was silent
    def deflection(m):
        p = Problem(m, Material(1e6, 0.0, 0.05))
        p.clamp(lambda X: (X[:, 0] < 1e-9) | (X[:, 0] > 8 - 1e-9))
        p.add_pressure(-1e-3)
        return -p.solve_linear().displacements()[4, 2]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cut = from_meshio(_two_strips(False))
    said = [str(w.message) for w in caught if issubclass(w.category, MeshWarning)]
    assert len(said) == 1 and "2 pair(s) of distinct nodes" in said[0] and "4-18" in said[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error", MeshWarning)
        merged = from_meshio(_two_strips(True))
    assert deflection(cut) == pytest.approx(3.2 * deflection(merged), rel=0.01)


def test_a_scenario_names_the_mesh_file_key(tmp_path):
    _two_strips(False).write(tmp_path / "cut.vtu")
    doc = {"mesh": {"file": "cut.vtu"}, "material": {"E": 1e6, "nu": 0.0, "h": 0.05},
           "supports": [{"type": "clamp", "nodes": [0, 9, 8, 17]}],
           "loads": [{"type": "pressure", "p": 1e-3}]}
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        scn = scenario.from_dict(doc, base_dir=str(tmp_path))
    assert any("mesh.file" in w and "distinct nodes" in w for w in map(str, scn.warnings))
