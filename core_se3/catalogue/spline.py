"""The not-a-knot cubic spline through tabulated reference points (NumPy only).

The catalogue compares computed load paths with reference tables (``core_se3/data``) between
their tabulated load levels, on the same interpolant SciPy's ``CubicSpline`` builds by default:
a C2 piecewise cubic whose third derivative is continuous across the second and the
second-to-last knots ("not-a-knot").  It is written here rather than imported because
``scipy.interpolate`` pulls in ``scipy.optimize``, ``scipy.special`` and ``scipy.spatial``: about
0.1 s of imports, a third of a one-shot ``core-se3 bench run`` process, for a few dozen points
(``benchmarks/results/peers.md``).  ``tests/test_spline.py`` checks it against SciPy's
``CubicSpline`` to round-off.

The slopes s_i at the knots solve the tridiagonal system of C2 continuity with the not-a-knot
end conditions (de Boor, *A Practical Guide to Splines*, rev. ed. 2001, ch. IV), for intervals
h_i = x_{i+1} - x_i and secants d_i = (y_{i+1} - y_i) / h_i:

    h_i s_{i-1} + 2 (h_{i-1} + h_i) s_i + h_{i-1} s_{i+1} = 3 (h_i d_{i-1} + h_{i-1} d_i),
    h_1 s_0 + (h_0 + h_1) s_1 = ((h_0 + 2 (h_0 + h_1)) h_1 d_0 + h_0^2 d_1) / (h_0 + h_1),

(and the mirror image at the right end); on each interval the cubic is the Hermite cubic of
(y_i, s_i, y_{i+1}, s_{i+1}).  Two points give the straight line, three the parabola.
"""
from __future__ import annotations

import numpy as np

__all__ = ["CubicSpline"]


class CubicSpline:
    """Not-a-knot cubic spline through (x_i, y_i), evaluated like SciPy's ``CubicSpline``.

    Parameters
    ----------
    x : (n,) array_like
        Strictly increasing knots, n >= 2.
    y : (n,) or (n, m) array_like
        Values at the knots (axis 0 runs along x).

    Calling the spline at points t returns the values (t.shape + y.shape[1:]); points outside
    [x_0, x_{n-1}] are extrapolated with the end cubics (as SciPy does).

    Example
    -------
    >>> import numpy as np
    >>> x = np.linspace(0.0, 2.0, 6)
    >>> s = CubicSpline(x, x ** 3 - x)            # a cubic is reproduced exactly
    >>> float(np.round(s(1.3), 12)), float(np.round(1.3 ** 3 - 1.3, 12))
    (0.897, 0.897)
    """

    def __init__(self, x, y):
        x = np.asarray(x, float)
        y = np.asarray(y, float)
        if x.ndim != 1 or len(x) < 2 or y.shape[:1] != x.shape:
            raise ValueError(f"need n >= 2 knots and values of matching length, got x {x.shape}, y {y.shape}")
        h = np.diff(x)
        if not np.all(h > 0):
            raise ValueError("the knots x must be strictly increasing")
        flat = y.reshape(len(x), -1)
        d = np.diff(flat, axis=0) / h[:, None]                       # secants (n-1, m)
        n = len(x)
        if n == 2:                                                   # the straight line
            s = np.vstack([d, d])
        elif n == 3:                                                 # the parabola
            c = (d[1] - d[0]) / (x[2] - x[0])                        # half its second derivative
            s = np.vstack([d[0] - c * h[0], d[0] + c * h[0], d[1] + c * h[1]])
        else:
            A = np.zeros((n, n))
            b = np.empty((n, flat.shape[1]))
            i = np.arange(1, n - 1)
            A[i, i - 1] = h[1:]
            A[i, i] = 2.0 * (h[:-1] + h[1:])
            A[i, i + 1] = h[:-1]
            b[1:-1] = 3.0 * (h[1:, None] * d[:-1] + h[:-1, None] * d[1:])
            w0, w1 = h[0] + h[1], h[-1] + h[-2]
            A[0, :2] = h[1], w0
            b[0] = ((h[0] + 2.0 * w0) * h[1] * d[0] + h[0] ** 2 * d[1]) / w0
            A[-1, -2:] = w1, h[-2]
            b[-1] = (h[-1] ** 2 * d[-2] + (2.0 * w1 + h[-1]) * h[-2] * d[-1]) / w1
            s = np.linalg.solve(A, b)
        # Hermite cubic per interval: y_i + s_i t + c2 t^2 + c3 t^3, t = x - x_i
        self.x, self._shape = x, y.shape[1:]
        self.c0, self.c1 = flat[:-1], s[:-1]
        self.c2 = (3.0 * d - 2.0 * s[:-1] - s[1:]) / h[:, None]
        self.c3 = (s[:-1] + s[1:] - 2.0 * d) / (h ** 2)[:, None]

    def __call__(self, t):
        t = np.asarray(t, float)
        k = np.clip(np.searchsorted(self.x, t.ravel(), side="right") - 1, 0, len(self.x) - 2)
        dt = (t.ravel() - self.x[k])[:, None]
        v = self.c0[k] + dt * (self.c1[k] + dt * (self.c2[k] + dt * self.c3[k]))
        return v.reshape(t.shape + self._shape)
