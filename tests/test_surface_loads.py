"""Surface loads (pressure, body force, gravity) against their exact totals."""
import numpy as np
import pytest

from core_se3 import Material, Problem, mesh


def _total(problem, loads):
    """Lab total force of ``loads`` at the reference configuration (frames = identity)."""
    return sum(ld.evaluate(problem.mesh.g0, 1.0, tangent=False).f[:, :3].sum(0) for ld in loads)


@pytest.mark.parametrize("direction", [(0.0, 0.0, 2.0), (0.0, 1.0, 1.0), (0.0, 0.0, 1e-3)])
def test_a_dead_pressure_is_p_per_area_whatever_the_length_of_its_direction(direction):
    """A dead pressure p = 1 on a 2 x 1 plate along direction (0, 0, 2) gave a total 4 (twice
    p A), along (0, 1, 1) sqrt(2) p A: the direction was not normalised (rotation axes and lab
    support directions are).  The total is p A along the unit direction."""
    p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    d = np.asarray(direction) / np.linalg.norm(direction)
    assert np.allclose(_total(p, p.add_load("pressure", p=1.0, direction=direction)), 2.0 * d, rtol=1e-14)
