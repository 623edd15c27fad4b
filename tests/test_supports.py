"""Supports: a rigid-body motion left free is reported by name before any solve (issue 2, item 8)."""
import numpy as np
import pytest

from core_se3 import Material, Problem, mesh
from core_se3.errors import SingularSystemError


def _strip():
    return Problem(mesh.rectangle(10.0, 1.0, 8, 2), Material(1.2e6, 0.3, 0.1))


def test_free_drilling_rotation_is_named():
    # one node with translations and two rotations fixed: the rigid rotation about the
    # normal through that node (0, -0.5, 0) stays free
    p = _strip()
    p.fix([0], [0, 1, 2, 3, 4])
    p.add_edge_force("x1", (0, 0, 1.0))
    with pytest.raises(SingularSystemError, match=r"rotation about \[0\.0, 0\.0, 1\.0\] through \[0\.0, -0\.5"):
        p.solve(steps=1)


def test_translations_only_on_a_line_leave_rotation_free():
    # pinning every node of the edge x0 leaves the rotation about that edge free
    p = _strip()
    p.fix("x0", [0, 1, 2])
    p.add_edge_force("x1", (0, 0, 1.0))
    with pytest.raises(SingularSystemError, match=r"rotation about \[0\.0, -?1\.0, 0\.0\]"):
        p.solve(steps=1)


def test_clamped_edge_restrains_all_rigid_motions():
    p = _strip()
    p.clamp("x0")
    p.add_edge_force("x1", (0, 0, 1e-3))
    res = p.solve(steps=1)
    assert np.isfinite(res.final.g).all()
