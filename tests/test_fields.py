"""Applied magnetic fields: gradients, Hessians, curl- and divergence-freeness, programmes."""
import numpy as np
import pytest

from core_se3.errors import LoadError
from core_se3.model.fields import (MU0, DipoleField, GradientField, UniformField, UserField, check_field,
                             rotating_direction)

RNG = np.random.default_rng(7)
X = RNG.uniform(-1.0, 1.0, size=(20, 3)) + np.array([0.0, 0.0, 3.0])   # points away from the dipole


def _fd(fn, x, h=1e-6):
    """Central differences of fn (k, ...) along each coordinate -> (k, ..., 3)."""
    cols = []
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        cols.append((fn(x + e) - fn(x - e)) / (2 * h))
    return np.stack(cols, -1)


def test_dipole_gradient_and_hessian_match_finite_differences():
    f = DipoleField(m=(0.3, -0.2, 1.0), x0=(0.1, 0.2, -0.1))
    G = f.gradient(X, 1.0)
    Gfd = _fd(lambda x: f.value(x, 1.0), X)
    # central differences with h = 1e-6 at |r| ~ 3: truncation ~ h^2 |B'''| / |B'| ~ 1e-12 relative
    assert np.abs(G - Gfd).max() <= 1e-8 * np.abs(G).max()
    H = f.hessian(X, 1.0)
    Hfd = _fd(lambda x: f.gradient(x, 1.0), X)
    assert np.abs(H - Hfd).max() <= 1e-7 * np.abs(H).max()


def test_dipole_is_curl_and_divergence_free_and_matches_the_far_field_on_axis():
    f = DipoleField(m=(0.0, 0.0, 2.0), x0=(0.0, 0.0, 0.0))
    curl, div = check_field(f, X)
    assert curl < 1e-13 and div < 1e-13
    # on the axis B = mu0 m / (2 pi z^3) (textbook dipole)
    z = 2.5
    B = f.value(np.array([[0.0, 0.0, z]]), 1.0)[0]
    assert B[2] == pytest.approx(4e-7 * np.pi * 2.0 / (2 * np.pi * z ** 3), rel=1e-14)


def test_gradient_field_must_be_curl_and_divergence_free():
    with pytest.raises(LoadError, match="symmetric"):
        GradientField((0, 0, 0), [[0, 1, 0], [0, 0, 0], [0, 0, 0]])
    with pytest.raises(LoadError, match="trace"):
        GradientField((0, 0, 0), np.eye(3))
    G = np.array([[1.0, 0.5, 0.0], [0.5, -0.25, 0.0], [0.0, 0.0, -0.75]])
    f = GradientField((0.01, 0, 0), G, x0=(1.0, 0.0, 0.0), scale=lambda lam: 2 * lam)
    x = np.array([[2.0, 1.0, 0.0]])
    assert np.allclose(f.value(x, 0.5), (0.01, 0, 0) + G @ (1.0, 1.0, 0.0))
    assert np.allclose(f.gradient(x, 0.5)[0], G)


def test_uniform_field_programmes_scale_and_direction():
    f = UniformField((0.0, 0.0, 0.05), direction=rotating_direction((0, 1, 0), (1, 0, 0), 0.25))
    x = np.zeros((2, 3))
    # a quarter turn about +y takes +x to -z; magnitude |B| * lam
    assert np.allclose(f.value(x, 1.0)[0], (0.0, 0.0, -0.05), atol=1e-15)
    assert np.allclose(f.value(x, 0.5)[0], 0.5 * 0.05 * np.array([np.cos(np.pi / 4), 0, -np.sin(np.pi / 4)]))
    assert np.all(f.gradient(x, 1.0) == 0) and np.all(f.hessian(x, 1.0) == 0)


def test_user_field_finite_difference_hessian_is_flagged_approximate():
    d = DipoleField(m=(0.0, 1.0, 0.5), x0=(0.0, 0.0, 0.0))
    u = UserField(lambda x: d.value(x, 1.0), lambda x: d.gradient(x, 1.0))
    assert u.approximate_hessian
    H, Hd = u.hessian(X, 1.0), d.hessian(X, 1.0)
    assert np.abs(H - Hd).max() <= 1e-6 * np.abs(Hd).max()
    exact = UserField(lambda x: d.value(x, 1.0), lambda x: d.gradient(x, 1.0), lambda x: d.hessian(x, 1.0))
    assert not exact.approximate_hessian


@pytest.mark.parametrize("s", [1.0, 1e-3, 1e-4, 1e3])
def test_user_field_hessian_step_follows_the_length_unit(s):
    """The finite-difference step of a UserField's Hessian is relative to the points' size: the
    same dipole and body in other length units (x s, the moment x s^3 keeps B) get the same
    relative accuracy (now 4e-11 ... 1e-10 at every s).  Before, the step was 1e-6 max(1, |x|),
    an absolute 1e-6 below one unit: 4e-11 at s = 1, 8.8e-7 at s = 1e-3 (a body in mm written in
    metres), 8.8e-5 at s = 1e-4."""
    d = DipoleField(m=np.array([0.0, 1.0, 0.5]) * s ** 3, x0=(0.0, 0.0, 0.0))
    u = UserField(lambda x: d.value(x, 1.0), lambda x: d.gradient(x, 1.0))
    H, Hd = u.hessian(X * s, 1.0), d.hessian(X * s, 1.0)
    assert np.abs(H - Hd).max() <= 1e-9 * np.abs(Hd).max()


@pytest.mark.parametrize("make, match", [
    (lambda: UniformField((0, np.nan, 0)), "finite"),
    (lambda: UniformField((0, 0, 1), direction=(0, 0, 1)), "function"),
    (lambda: DipoleField((0, 0, 1), (0, 0, np.inf)), "finite"),
    (lambda: UserField(1.0, None), "callables"),
])
def test_bad_field_input_raises_load_error(make, match):
    with pytest.raises(LoadError, match=match):
        make()


def test_field_on_the_dipole_and_user_field_with_curl_are_rejected():
    d = DipoleField((0, 0, 1), (0, 0, 0))
    with pytest.raises(LoadError, match="singular"):
        d.value(np.zeros((1, 3)), 1.0)
    W = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])      # curl: a current
    u = UserField(lambda x: x @ W.T, lambda x: np.broadcast_to(W, x.shape[:-1] + (3, 3)))
    with pytest.raises(LoadError, match="curl"):
        check_field(u, X)


def test_a_rotating_direction_from_a_zero_axis_or_start_is_refused_where_it_is_made():
    """rotating_direction((0, 0, 0), (1, 0, 0)) returned a function giving NaN at every load
    factor (a RuntimeWarning at construction); the error came at the first evaluation, naming
    'field direction at load factor 0.5', not the axis.  Now a LoadError naming it at once."""
    import warnings
    from core_se3.errors import LoadError
    from core_se3.model.fields import rotating_direction
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for axis, start, what in (((0, 0, 0), (1, 0, 0), "rotation axis"), ((0, 0, 1), (0, 0, 0), "start direction")):
            with pytest.raises(LoadError, match=f"the {what} is the zero vector"):
                rotating_direction(axis, start)
        with pytest.raises(LoadError, match="must be finite"):
            rotating_direction((0, 0, 1), (1, 0, 0), turns_per_unit=float("nan"))
        assert np.allclose(rotating_direction((0, 0, 2), (3, 0, 0), 0.25)(1.0), [0, 1, 0])


def test_the_dipoles_hessian_at_its_own_position_is_refused_not_1e126():
    """value and gradient at the dipole's position raise LoadError, but the Hessian (a complex
    step of the gradient: r . r = -h^2 there, not 0) returned entries of 1e126 for m = (0.5,
    -1, 2); now the same LoadError.  Beside it the Hessian equals central differences of the
    closed-form gradient (observed 1.6e-10 relative)."""
    d = DipoleField((0.5, -1.0, 2.0), (0.1, 0.2, -0.3))
    x = np.array([[0.7, -0.4, 0.9], [0.1, 0.2, -0.3]])
    for what in ("value", "gradient", "hessian"):
        with pytest.raises(LoadError, match=r"point 1 \(at \[0.1, 0.2, -0.3\]\) lies on the dipole at x0 = \[0.1, "):
            getattr(d, what)(x, 1.0)
    H, h = d.hessian(x[:1], 1.0), 1e-6
    fd = np.stack([(d.gradient(x[:1] + h * e, 1.0) - d.gradient(x[:1] - h * e, 1.0)) / (2 * h) for e in np.eye(3)], -1)
    assert np.abs(H - fd).max() <= 1e-7 * np.abs(H).max()


@pytest.mark.parametrize("returns", [lambda x: "abc", lambda x: [[0.0, "a", 0.0]], lambda x: {"B": 1.0}])
def test_a_user_field_returning_no_numbers_is_a_load_error(returns):
    """A user field's value that is no array of numbers (a string, a dict) raised NumPy's bare
    ValueError/TypeError ('could not convert string to float'); now a LoadError naming the user
    field's value and the shape expected."""
    f = UserField(returns, lambda x: np.zeros(x.shape + (3,)))
    with pytest.raises(LoadError, match=r"user field value must return numbers of shape \(1, 3\)"):
        f.value(np.zeros((1, 3)), 1.0)


@pytest.mark.parametrize("mu0", [-MU0, 0.0, float("nan"), "1e-6", True])
def test_a_dipole_with_a_mu0_that_is_no_positive_number_is_refused(mu0):
    """DipoleField(mu0=-MU0) was the reversed field (a magnet pulled the other way, converged and
    silent), mu0 = 0 no field at all, NaN NaN residuals, "1e-6" a bare TypeError at first use."""
    from core_se3.errors import LoadError
    with pytest.raises(LoadError, match="dipole mu0 must be a positive number"):
        DipoleField((0.0, 0.0, 1.0), (0.0, 0.0, 0.0), mu0=mu0)
