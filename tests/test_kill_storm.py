"""A reduced kill storm (scripts/kill_storm.py, issue 34): random SIGKILL, SIGTERM and SIGINT during
``core-se3 run`` (load control, arc length) and ``core-se3 sweep`` processes; after every kill every
file is readable and consistent, and every job resumed to its end equals its uninterrupted run
bit for bit.  The full storm (50 kills) is ``python scripts/kill_storm.py``."""
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))

import kill_storm  # noqa: E402


def test_a_reduced_kill_storm(tmp_path):
    s = kill_storm.storm(kills=6, seed=7, workdir=str(tmp_path), log=lambda *a: None)
    assert s["kills"] == 6 and s["chains"] == s["identical"] >= 2
    assert sum(s["by_signal"].values()) == 6
