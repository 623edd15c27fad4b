"""Error norms, rate fits and time-to-accuracy estimates for the cross-model studies (NumPy only).

Conventions (the project's error measure, ``core_se3.catalogue.measures``, whose
``path_distance`` and ``interp_reference`` this module re-exports): a probe path is a sequence of
displacement vectors d_k at the load levels k; the distance between two paths is
max_k |d_k - e_k| / S with S = the largest displacement |e_k| of the reference path (for two
models without a reference, S = the largest displacement of either path).
"""
from __future__ import annotations

from math import tanh

import numpy as np

from core_se3.catalogue.measures import interp_reference, path_distance

__all__ = ["path_distance", "interp_reference", "fit_rate", "time_to_error", "mindlin_strip_J",
           "circle_tip", "arc_tip", "geometric_mean_ratio"]


def fit_rate(h, err, last=3):
    """Observed convergence rate p and constant C of err = C h^p, least squares in log-log on
    the ``last`` finest points with err > 0.  Returns (p, C) or (nan, nan) with < 2 points."""
    h, err = np.asarray(h, float), np.asarray(err, float)
    ok = np.isfinite(h) & np.isfinite(err) & (err > 0) & (h > 0)
    h, err = h[ok], err[ok]
    if len(h) < 2:
        return float("nan"), float("nan")
    order = np.argsort(h)[:last]
    x, y = np.log(h[order]), np.log(err[order])
    if np.ptp(x) == 0:
        return float("nan"), float("nan")
    p, logc = np.polyfit(x, y, 1)
    return float(p), float(np.exp(logc))


def time_to_error(times, errs, target, extrapolate=True, last=3):
    """Wall time to reach ``target`` error along a refinement sequence.

    Returns (time, how): how = 'measured' (log-log interpolation between the two runs that
    bracket the target, or the first run already below it), 'extrapolated' (power law
    t = C err^q fitted to the ``last`` most accurate runs, only if the errors still fall),
    or 'not reached' (time nan)."""
    t, e = np.asarray(times, float), np.asarray(errs, float)
    ok = np.isfinite(t) & np.isfinite(e) & (e > 0) & (t > 0)
    t, e = t[ok], e[ok]
    if len(t) == 0:
        return float("nan"), "not reached"
    order = np.argsort(t)
    t, e = t[order], e[order]
    below = np.nonzero(e <= target)[0]
    if len(below):
        k = int(below[0])
        if k == 0:
            return float(t[0]), "measured"
        # interpolate log t linearly in log e between runs k-1 and k
        x0, x1 = np.log(e[k - 1]), np.log(e[k])
        y0, y1 = np.log(t[k - 1]), np.log(t[k])
        if x0 == x1:
            return float(t[k]), "measured"
        s = (np.log(target) - x0) / (x1 - x0)
        return float(np.exp(y0 + s * (y1 - y0))), "measured"
    if not extrapolate or len(t) < 2:
        return float("nan"), "not reached"
    q, C = fit_rate(e, t, last=last)  # t = C e^q; q < 0 when accuracy costs time
    # the errors must still be falling over the fitted runs, else the model has hit a floor
    tail = e[-last:]
    if not (q < 0) or not np.all(np.diff(tail) < 0):
        return float("nan"), "not reached"
    return float(C * target ** q), "extrapolated"


def mindlin_strip_J(w, h, shear_factor=1.0):
    """Saint-Venant torsion constant of a Reissner-Mindlin plate strip of width w, thickness h:
    J = w h^3/3 (1 - tanh(x)/x), x = sqrt(12 k_s) w/(2 h); -> w h^3/3 as h/w -> 0."""
    x = np.sqrt(12.0 * shear_factor) * w / (2.0 * h)
    return float(w * h ** 3 / 3.0 * (1.0 - tanh(x) / x))


def circle_tip(L, kappa):
    """Tip displacement (u, v) and rotation of a clamped strip of length L bent into a circular
    arc of curvature kappa (pure end moment: the exact answer of every rod/shell model whose
    bending is uncoupled from stretch)."""
    kappa = np.asarray(kappa, float)
    th = kappa * L
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.where(np.abs(th) > 1e-8, np.sin(th) / np.where(kappa == 0, 1, kappa) - L,
                     -L * th ** 2 / 6)
        v = np.where(np.abs(th) > 1e-8, (1 - np.cos(th)) / np.where(kappa == 0, 1, kappa),
                     L * th / 2)
    return u, v, th


def arc_tip(S, kappa0, dkappa):
    """Tip displacement (u, v) of a clamped arc of length S, reference curvature kappa0 (tangent +x
    and centre on +v at the clamp), whose curvature an end moment changes uniformly by dkappa
    (= M/EI): the arc stays circular, tip = (sin(k S)/k, (1 - cos(k S))/k), k = kappa0 + dkappa."""
    k = kappa0 + np.asarray(dkappa, float)

    def pos(k):
        k = np.asarray(k, float)
        small = np.abs(k * S) < 1e-6
        ks = np.where(small, 1.0, k)
        x = np.where(small, S - k ** 2 * S ** 3 / 6, np.sin(ks * S) / ks)
        y = np.where(small, k * S ** 2 / 2, (1 - np.cos(ks * S)) / ks)
        return x, y
    x, y = pos(k)
    x0, y0 = pos(np.asarray(kappa0, float))
    return x - x0, y - y0


def geometric_mean_ratio(a, b):
    """exp(mean(log(a/b))) over the finite positive pairs: a robust 'how many times slower'."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    ok = np.isfinite(a) & np.isfinite(b) & (a > 0) & (b > 0)
    if not ok.any():
        return float("nan")
    return float(np.exp(np.mean(np.log(a[ok] / b[ok]))))
