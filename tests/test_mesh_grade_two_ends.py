"""Grading from both ends (``mesh.generators.spacing``, the generators' ``grade``, ``[mesh]
grade``): a fraction the two-sided progression cannot give is refused, not replaced (review
finding; the tests fail on the code before)."""
import numpy as np
import pytest

from core_se3 import mesh, scenario
from core_se3.errors import MeshError, ScenarioError
from core_se3.mesh.generators import spacing

pytestmark = pytest.mark.core


@pytest.mark.parametrize("n, first, last, got", [(8, 0.3, 0.3, 0.0964), (6, 0.05, 0.5, 0.36)])
def test_a_fraction_both_ends_cannot_give_is_refused_not_replaced(n, first, last, got):
    # the widths are the smaller of the two progressions: the old code returned end elements of
    # `got` where `first` / `last` was asked for, silently
    with pytest.raises(MeshError, match=f"would get {got}"):
        spacing(0.0, 1.0, n, first=first, last=last)
    with pytest.raises(MeshError, match="grade one end only"):
        mesh.rectangle(8.0, 1.0, n, 2, grade={"x0": first, "x1": last})


def test_the_scenario_names_the_grade_key():
    doc = {"mesh": {"generator": "rectangle", "L": 8.0, "width": 1.0, "nx": 8, "ny": 2,
                    "grade": {"x0": 0.3, "x1": 0.3}},
           "material": {"E": 1e6, "nu": 0.0, "h": 0.01}, "supports": [{"type": "clamp", "edge": "x0"}],
           "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}]}
    with pytest.raises(ScenarioError, match="grade") as exc:
        scenario.from_dict(doc)
    assert exc.value.key == "mesh.grade"


def test_fractions_both_ends_can_give_are_kept_exactly():
    w = np.diff(spacing(0.0, 1.0, 6, first=0.3, last=0.02))
    assert w[0] == pytest.approx(0.3, rel=1e-12) and w[-1] == pytest.approx(0.02, rel=1e-12)
