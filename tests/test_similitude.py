"""Dimensional similitude: the same physics in other units (lengths x s_L, moduli x s_E, loads by
their dimension) gives the same non-dimensional answer and the same step decisions
(``benchmarks/similitude.py``, ``benchmarks/results/similitude.md``)."""
import warnings

import numpy as np
import pytest

from core_se3 import Material, Problem, mesh
from core_se3.catalogue.case import get_case
from core_se3.catalogue.run import run_case
from core_se3.solvers.convergence import relative_residual


@pytest.mark.parametrize("s", [1.0, 1e6])
def test_residual_floor_of_a_stressed_reference_is_finite_and_silent(s):
    """At lam = 0 a curved shell's reference carries element forces that cancel (its force
    scale) while nothing is loaded: the relative residual's round-off floor is then the cap 1e300
    in every unit.  Before, it was 1e3 eps F / 1e-300: 1.3e301 for this roof and, with lengths
    x 1e6 (F 1.7e29), inf with a bare NumPy 'overflow encountered in scalar divide'."""
    p = Problem(mesh.cylinder_arch(2540.0 * s, 0.2, 508.0 * s, 4, 4), Material(3.1e9, 0.3, 12.7 * s))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, -1.0))
    ev = p.evaluate(p.mesh.g0, 0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rn, floor = relative_residual(p.assembler(), ev, p.length_scale)
    assert rn == 0.0 and floor == 1e300


def _scaled(case, sL, sE):
    dims = {"force/length^2": (0, 1), "length": (1, 0), "force": (2, 1)}
    return {k: v * sL ** dims.get(case.units[k], (0, 0))[0] * sE ** dims.get(case.units[k], (0, 0))[1]
            for k, v in case.params.items()}


@pytest.mark.parametrize("sL, sE", [(1e-3, 1e6), (1e6, 1e9), (1e-3, 1e-6)])
def test_cantilever_in_other_units_takes_the_same_steps(sL, sE):
    """cantilever-shear (16x1, P L^2/EI to 4 in 4 steps) with lengths x sL and E x sE (the force
    x sE sL^2): the same tip u / L to 1e-12 and the same Newton iterations and tries per step
    (measured 1.7e-15 at every scaling of benchmarks/similitude.py)."""
    case = get_case("cantilever-shear")
    _, base, _ = run_case("cantilever-shear", mesh=(16, 1), steps=4)
    _, other, _ = run_case("cantilever-shear", mesh=(16, 1), steps=4, overrides=_scaled(case, sL, sE))
    assert [(st.iterations, st.attempts) for st in other.steps] == [(st.iterations, st.attempts) for st in base.steps]
    for a, b in zip(base.steps, other.steps):
        assert np.abs(b.probes["tip"]["u"] / sL - a.probes["tip"]["u"]).max() <= 1e-12 * 10.0
