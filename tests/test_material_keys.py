"""[material] shear_stabilisation_floor written where no law uses it (shear_stabilisation 0) is a
plausibility warning at its key (review finding; the test fails on the code before)."""
import warnings

import pytest

from core_se3 import scenario

pytestmark = pytest.mark.core


def _doc(material, material_regions=None):
    doc = {"mesh": {"generator": "rectangle", "L": 8.0, "width": 1.0, "nx": 4, "ny": 1},
           "material": dict({"E": 1e6, "nu": 0.0, "h": 0.01}, **material),
           "supports": [{"type": "clamp", "edge": "x0"}],
           "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}]}
    if material_regions:
        doc["regions"] = {"tip": {"box": {"x": [4.0, 8.0]}}}
        doc["material"]["regions"] = material_regions
    return doc


def _keys(doc):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return [w.key for w in scenario.from_dict(doc).warnings]


def test_a_floor_without_stabilisation_is_named_and_a_used_one_is_not():
    # a floor of 0.2 alone left the shear modulus at ks G h: the law is the unstabilised one
    assert _keys(_doc({"shear_stabilisation_floor": 0.2})) == ["material.shear_stabilisation_floor"]
    assert _keys(_doc({"shear_stabilisation_floor": 0.2, "shear_stabilisation": 0.1})) == []
    # the base floor used by a stabilised region: silent; a region's own unused floor: named
    assert _keys(_doc({"shear_stabilisation_floor": 0.2}, {"tip": {"shear_stabilisation": 0.1}})) == []
    assert _keys(_doc({}, {"tip": {"shear_stabilisation_floor": 0.2}})) == \
        ["material.regions.tip.shear_stabilisation_floor"]
