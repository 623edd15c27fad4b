"""A mesh file's length unit: its coordinates are read as lengths in the scenario's unit, so the
gripper's Gmsh file (mm) in a scenario with units = "SI" is 1000 times too large.  The only sign
was a load number 10^6 times too large whose warning blamed the load (review finding; the test
fails on the code before)."""
import copy
import os
import shutil
import tomllib
import warnings

import pytest

import core_se3
from core_se3 import scenario

pytestmark = pytest.mark.core

EXAMPLES = os.path.join(os.path.dirname(core_se3.__file__), "..", "examples")


def _gripper(tmp_path, units, E, h):
    with open(os.path.join(EXAMPLES, "gripper.toml"), "rb") as fh:
        doc = tomllib.load(fh)
    shutil.copy(os.path.join(EXAMPLES, "gripper.msh"), tmp_path / "gripper.msh")
    doc = copy.deepcopy(doc)
    doc.pop("output", None)
    doc["units"], doc["material"]["E"], doc["material"]["h"] = units, E, h
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return [str(w) for w in scenario.from_dict(doc, base_dir=str(tmp_path)).warnings]


def test_a_mesh_file_in_mm_read_as_si_names_the_files_length_unit(tmp_path):
    # the same gripper in SI (E in Pa, h = 0.7e-3 m) on the file in mm: load number 5.64e5
    # (0.564 with the file in m), the warning now names the mesh file's unit
    said = _gripper(tmp_path, "SI", 0.4698783e6, 0.7e-3)
    numbers = [w for w in said if "load number" in w]
    assert len(numbers) == 4 and all("= 5.64e+05 in the first step" in w for w in numbers)
    assert all("the mesh file's length unit (its coordinates are read as m" in w for w in numbers)
    assert _gripper(tmp_path, "N-mm-MPa", 0.4698783, 0.7) == []
