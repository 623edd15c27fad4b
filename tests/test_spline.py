"""The catalogue's not-a-knot cubic spline (core_se3/catalogue/spline.py) against exact
polynomials and against SciPy's CubicSpline, whose default (not-a-knot) interpolant it replaces."""
import numpy as np
import pytest

from core_se3.catalogue.spline import CubicSpline


@pytest.mark.parametrize("n", [4, 5, 9, 41])
def test_a_cubic_is_reproduced_exactly_on_any_knots(n):
    # not-a-knot end conditions reproduce every cubic (de Boor 2001, ch. IV): the error is
    # round-off, inside the table and in extrapolation alike
    rng = np.random.default_rng(n)
    x = np.sort(rng.uniform(-2.0, 3.0, n))
    p = lambda t: 0.7 * t ** 3 - 2.0 * t ** 2 + t - 5.0
    t = np.linspace(x[0] - 0.5, x[-1] + 0.5, 101)
    assert np.allclose(CubicSpline(x, p(x))(t), p(t), rtol=0, atol=1e-11)


def test_two_and_three_knots_give_the_line_and_the_parabola():
    assert CubicSpline([0.0, 2.0], [1.0, 5.0])(np.array([0.5, 3.0])).tolist() == [2.0, 7.0]
    x = np.array([0.0, 1.0, 3.0])
    q = lambda t: 2.0 * t ** 2 - t + 1.0
    assert np.allclose(CubicSpline(x, q(x))(np.array([0.3, 2.5, 4.0])), q(np.array([0.3, 2.5, 4.0])),
                       rtol=0, atol=1e-13)


@pytest.mark.parametrize("n", [2, 3, 4, 5, 7, 20, 93])
def test_the_spline_is_scipys_not_a_knot_cubic_spline(n):
    import scipy.interpolate as scipy_interpolate      # a dependency (pyproject): always compared
    rng = np.random.default_rng(100 + n)
    for _ in range(10):
        x = np.sort(rng.uniform(-3.0, 5.0, n))
        y = rng.standard_normal((n, 2))
        t = np.concatenate([x, rng.uniform(x[0], x[-1], 50), [x[0] - 0.3, x[-1] + 0.3]])
        ref = scipy_interpolate.CubicSpline(x, y, axis=0)(t)
        got = CubicSpline(x, y)(t)
        assert got.shape == ref.shape
        # the two solve the same 4x4..93x93 system by different LU codes: round-off apart,
        # relative to the largest value (random knots may lie close together)
        assert np.abs(got - ref).max() <= 1e-12 * np.abs(ref).max()
        assert CubicSpline(x, y[:, 0])(t).shape == t.shape
        assert CubicSpline(x, y)(1.0).shape == (2,)


def test_bad_knots_are_refused():
    with pytest.raises(ValueError, match="strictly increasing"):
        CubicSpline([0.0, 1.0, 1.0], [0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match="n >= 2"):
        CubicSpline([0.0], [1.0])
    with pytest.raises(ValueError, match="matching length"):
        CubicSpline([0.0, 1.0], [1.0, 2.0, 3.0])
