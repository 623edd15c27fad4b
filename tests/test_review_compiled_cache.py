"""The numba backend's compiled evaluation follows the problem's supports and loads: it was keyed
on the id()s of the assembler and the loads, which Python reuses once they are freed (review
finding; the test fails on the code before)."""
import importlib.util

import numpy as np
import pytest

from core_se3 import Material, Problem, mesh

pytestmark = pytest.mark.skipif(importlib.util.find_spec("numba") is None, reason="needs numba")


def test_a_support_added_after_an_evaluation_reaches_the_compiled_tangent():
    # evaluate, fix one more dof, evaluate: the new assembler was most often allocated where
    # the dropped one had been (18 times in 20), so the compiled evaluation kept the old free
    # dofs' pattern: K 144 x 144 and r (144,) for 141 free dofs
    for _ in range(20):
        p = Problem(mesh.rectangle(10.0, 1.0, 8, 2), Material(1.2e6, 0.3, 0.1), backend="numba")
        p.clamp("x0")
        p.add_edge_force("x1", (0.0, 0.0, 1e-2))
        p.evaluate(p.mesh.g0, 1.0)
        p.fix("x1", [0])
        ev = p.evaluate(p.mesh.g0, 1.0)
        nfree = p.assembler().nfree
        assert ev.K.shape == (nfree, nfree) and ev.r.shape == (nfree,)
    q = Problem(mesh.rectangle(10.0, 1.0, 8, 2), Material(1.2e6, 0.3, 0.1), backend="numba")
    q.clamp("x0")
    q.add_edge_force("x1", (0.0, 0.0, 1e-2))
    q.fix("x1", [0])
    fresh = q.evaluate(q.mesh.g0, 1.0)
    assert abs(ev.K - fresh.K).max() == 0.0 and np.array_equal(ev.r, fresh.r)
