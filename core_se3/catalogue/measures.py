"""The project's error measures, used by the catalogue, ``comparison/`` and ``fenicsx_ref``.

Reference paths (``elastica.json``): at each computed load level, the distance between the
computed and the reference probe displacement (the reference interpolated by a cubic spline in
the load), divided by the largest reference probe displacement on the path; the case's error is
the maximum over the path (:func:`error_against_reference`, built on :func:`interp_reference`
and :func:`path_distance`).

Tables (Sze et al. 2004, ``literature.json``): the largest distance from a computed point to the
tabulated polyline in the plane (P/P_max, u/u_max) (:func:`point_curve_distances`); it serves
snap-throughs and snap-backs, where a comparison at equal load is ill-defined.
"""
from __future__ import annotations

import numpy as np

from .references import literature_entry
from .spline import CubicSpline

__all__ = ["path_distance", "interp_reference", "error_against_reference", "point_curve_distances",
           "table_curves", "curve_columns", "curve_deviation", "errors_at_table_loads",
           "lifted_length_from_gaps"]


def path_distance(d, e, scale=None):
    """max_k |d_k - e_k| / scale and the per-step values.

    d, e: (n, m) arrays of probe displacements at the same load levels; scale defaults to
    max(max_k |e_k|, max_k |d_k|) (the largest displacement on either path).

    Returns: (float, (n,) ndarray); ValueError for paths of different shapes or a zero scale.

    Example
    -------
    >>> round(path_distance([[1.0, 0.0], [2.0, 0.0]], [[1.0, 0.0], [2.0, 0.1]], scale=2.0)[0], 12)
    0.05
    """
    d, e = np.atleast_2d(np.asarray(d, float)), np.atleast_2d(np.asarray(e, float))
    if d.shape != e.shape:
        raise ValueError(f"paths of different shapes {d.shape} and {e.shape}")
    if scale is None:
        scale = max(np.linalg.norm(e, axis=1).max(), np.linalg.norm(d, axis=1).max())
    if not scale > 0:
        raise ValueError("zero displacement scale: the paths do not move")
    per = np.linalg.norm(d - e, axis=1) / scale
    return float(per.max()), per


def interp_reference(load, ref_load, ref_values):
    """Reference values at the given loads: cubic spline (not-a-knot) in the load through the
    tabulated points, per component.  ref_values: (n_ref, m).  Loads outside the table -> nan.

    Parameters: load (k,), ref_load (n_ref,) (sorted here; repeats dropped), ref_values
    (n_ref, m).  Returns: (k, m) ndarray.

    Example
    -------
    >>> import numpy as np
    >>> L = np.linspace(0, 1, 5)
    >>> interp_reference([0.3, 2.0], L, np.c_[L ** 2]).round(12).ravel().tolist()
    [0.09, nan]
    """
    L = np.asarray(ref_load, float)
    V = np.asarray(ref_values, float)
    order = np.argsort(L)
    L, V = L[order], V[order]
    keep = np.concatenate([[True], np.diff(L) > 0])
    L, V = L[keep], V[keep]
    out = CubicSpline(L, V)(np.asarray(load, float))
    x = np.asarray(load, float)
    out[(x < L[0] - 1e-12 * abs(L[0])) | (x > L[-1] + 1e-12 * abs(L[-1]))] = np.nan
    return out


def error_against_reference(loads_ref_axis, disps, ref):
    """Max over the path of |d - d_ref(load)| / max |d_ref| (module docstring).

    loads_ref_axis: the computed load levels on the reference's load axis; disps: (k, 2) the
    computed probe displacements in the reference plane; ref: dict(load, u, v) in case units.
    Returns (error, load at the worst point, per-step errors (NaN outside the table)).

    Example
    -------
    >>> ref = dict(load=[0.0, 1.0, 2.0], u=[0.0, 1.0, 2.0], v=[0.0, 0.0, 0.0])
    >>> err, at, errs = error_against_reference([0.0, 1.0, 2.0], [[0, 0], [1.0, 0.0], [2.0, 0.1]], ref)
    >>> round(err, 12), at, errs.round(12).tolist()          # 0.1 off at the largest reference, 2
    (0.05, 2.0, [0.0, 0.0, 0.05])
    """
    L = np.asarray(ref["load"], float)
    order = np.argsort(L)
    L, u, v = L[order], np.asarray(ref["u"], float)[order], np.asarray(ref["v"], float)[order]
    keep = np.concatenate([[True], np.diff(L) > 0])
    L, u, v = L[keep], u[keep], v[keep]
    lo, hi = min(loads_ref_axis), max(loads_ref_axis)
    on_path = (L >= min(lo, 0.0) - 1e-12) & (L <= hi + 1e-12) & (L * np.sign(hi if hi != 0 else lo) >= -1e-12)
    scale = np.max(np.hypot(u[on_path], v[on_path]))
    x = np.asarray(loads_ref_axis, float)
    inside = (x >= L[0] - 1e-12) & (x <= L[-1] + 1e-12)
    dr = interp_reference(np.clip(x, L[0], L[-1]), L, np.c_[u, v])
    if scale == 0.0:
        # a path that stays below the table's first load beyond 0 (a case run at a load 1e-5 of
        # its table's): the reference's own size along the path, not inf with a NumPy warning
        scale = float(np.max(np.where(inside, np.hypot(dr[:, 0], dr[:, 1]), 0.0), initial=0.0))
    if scale == 0.0 or not np.any(inside):
        return float("nan"), float("nan"), np.full(len(x), np.nan)
    errs = np.where(inside, np.linalg.norm(np.asarray(disps, float) - dr, axis=1) / scale, np.nan)
    k = int(np.nanargmax(errs))
    return float(errs[k]), float(x[k]), errs


def errors_at_table_loads(loads_ref_axis, disps, angles, ref, tol=1e-9):
    """The error measure restricted to the computed steps that lie on the table's own load
    points (where the spline is the table), with the rotation-angle error there.

    loads_ref_axis (k,), disps (k, 2), angles (k,) (unwrapped rotation angles of the probe);
    ref: dict(load, u, v, theta).  Returns dict(error, n_points, theta_error_max, per_load,
    max_reference_displacement) or dict(error=None, n_points=0).
    """
    L = np.asarray(ref["load"], float)
    x = np.asarray(loads_ref_axis, float)
    hit = [np.nonzero(np.abs(x - r) <= tol * max(1.0, abs(r)))[0] for r in L]
    rows = [(i, h[0]) for i, h in enumerate(hit) if len(h)]
    if not rows:
        return dict(error=None, n_points=0)
    ref_d = np.c_[ref["u"], ref["v"]][[i for i, _ in rows]]
    comp = np.asarray(disps, float)[[k for _, k in rows]]
    scale = float(np.linalg.norm(ref_d, axis=1).max())
    if scale == 0.0:
        return dict(error=None, n_points=len(rows))
    errs = np.linalg.norm(comp - ref_d, axis=1) / scale
    th = np.abs(np.asarray(angles, float)[[k for _, k in rows]] - np.asarray(ref["theta"], float)[[i for i, _ in rows]])
    return dict(error=float(errs.max()), n_points=len(rows), max_reference_displacement=scale,
                theta_error_max=float(th.max()),
                per_load=[[float(L[i]), float(e)] for (i, _), e in zip(rows, errs)])


def point_curve_distances(points, curve):
    """Distance of each point (k, 2) to the polyline ``curve`` (m, 2).

    Parameters: points (k, 2), curve (m, 2) (one point: the distance to it).  Returns: (k,).

    Example
    -------
    >>> point_curve_distances([[0.5, 1.0], [2.0, 0.0]], [[0.0, 0.0], [1.0, 0.0]]).tolist()
    [1.0, 1.0]
    """
    P = np.atleast_2d(np.asarray(points, float))
    C = np.atleast_2d(np.asarray(curve, float))
    if len(C) == 1:
        return np.linalg.norm(P - C[0], axis=1)
    A, B = C[:-1], C[1:]
    AB = B - A
    L2 = np.einsum("si,si->s", AB, AB)
    t = np.einsum("ksi,si->ks", P[:, None, :] - A[None], AB) / np.where(L2 > 0, L2, 1.0)
    t = np.clip(np.where(L2 > 0, t, 0.0), 0.0, 1.0)
    Q = A[None] + t[..., None] * AB[None]
    return np.linalg.norm(P[:, None, :] - Q, axis=2).min(1)


def table_curves(case):
    """[(column, P/P_max array, u array in case units)] of the case's literature entry."""
    e = literature_entry(case.extra["literature"])
    out = []
    lam = np.asarray(e["P_over_Pmax"], float)
    for c in curve_columns(case):
        key = c["column"].replace("/", "_")
        u = c["scale"] * np.asarray(e[key], float)
        if lam[0] != 0.0:               # tables that omit the unloaded state: it is (0, 0)
            out.append((c["column"], np.r_[0.0, lam], np.r_[0.0, u]))
        else:
            out.append((c["column"], lam, u))
    return out


def curve_columns(case):
    """The table columns a case is measured on: dicts (column, probe, component, sign, scale)."""
    if "curves" in case.extra:
        return case.extra["curves"]
    x = case.extra                                   # sze-semicylinder (shared with fenicsx_ref)
    return [dict(column=x["column"], probe=case.probe, component=x["probe_component"],
                 sign=x["probe_sign"], scale=x["displacement_scale"])]


def curve_deviation(case, lams, probes):
    """(deviation, per-step deviations, per-curve info) of computed points against the table.

    lams: load factors (P/P_max); probes: per step {probe: u (3,)}.
    """
    lams = np.asarray(lams, float)
    per_step = np.zeros(len(lams))
    info = []
    for (col, tl, tu), c in zip(table_curves(case), curve_columns(case)):
        u = np.array([c["sign"] * pr[c["probe"]][c["component"]] for pr in probes])
        umax = np.abs(tu).max()
        pmax = 1.0
        d = point_curve_distances(np.c_[lams / pmax, u / umax], np.c_[tl / pmax, tu / umax])
        per_step = np.maximum(per_step, d)
        k = int(np.argmax(d))
        info.append(dict(column=col, u_max=float(umax), deviation=float(d.max()),
                         at=dict(P_over_Pmax=float(lams[k]), u=float(u[k])),
                         table_end=dict(P_over_Pmax=float(tl[-1]), u=float(tu[-1])),
                         computed_end=dict(P_over_Pmax=float(lams[-1]), u=float(u[-1]))))
    return float(per_step.max()), per_step, info


def lifted_length_from_gaps(xc, gap, force, window=0.3):
    """Reference position x_d of the detachment line of a strip lifted off a plane, located
    between the nodes from the gap field (``contact-lift``).

    xc (m,) increasing column positions, the lifted end at xc[0]; gap (m,) and force (m,) the
    columns' mean gap and contact force.  Columns carrying force rest on the plane (their median
    gap is the rest level).  Near the detachment the lifted gap of a shear-deformable strip is
    w(s) = a1 s + a3 s^3 + a4 s^4, s = x_d - x (a1 = R / (k G A) the shear angle of the
    detachment reaction R, a3 = R / (6 EI), a4 = -q_l / (24 EI); the a2 s^2 term, a2 / a3 ~
    (h / l)^2, is dropped): the exact Timoshenko shape for small deflections, the leading terms
    of the expansion for large ones.  x_d minimises the least-squares residual of this model
    (linear in the a's; x_d by a bounded 1-D search within three columns of the first touching
    one) over the lifted columns within ``window`` x (that column's distance from the lifted end).

    Returns
    -------
    (float, int)
        x_d [length] (NaN when no column or the first one touches) and the columns fitted.

    Example
    -------
    The exact small-deflection gap (q_l / (24 EI)) s^3 (2 l - s) of l = 0.3137 on 61 columns:

    >>> import numpy as np
    >>> xc = np.linspace(0.0, 1.0, 61); s = 0.3137 - xc
    >>> gap = np.where(s > 0, 0.1 / (24 * 0.005) * s ** 3 * (2 * 0.3137 - s), 0.0)
    >>> xd, k = lifted_length_from_gaps(xc, gap, np.where(s > 0, 0.0, 1.0))
    >>> bool(abs(xd - 0.3137) < 1e-6), k
    (True, 5)
    """
    from scipy.optimize import minimize_scalar
    xc, gap, force = (np.asarray(a, float) for a in (xc, gap, force))
    touching = force > 0
    if not touching.any() or touching[0]:
        return float("nan"), 0
    first = int(np.argmax(touching))
    if first < 3:
        return float("nan"), 0
    rest = float(np.median(gap[touching]))
    dx = xc[first] - xc[first - 1]
    xf = xc[first]
    sel = np.nonzero((xc < xf - 0.5 * dx) & (xc >= xf - window * (xf - xc[0])))[0]
    if len(sel) < 4:
        sel = np.arange(max(0, first - 4), first)
    w = gap[sel] - rest

    def misfit(xd):
        s = xd - xc[sel]
        A = np.stack([s, s ** 3, s ** 4], 1)
        c, *_ = np.linalg.lstsq(A, w, rcond=None)
        return float(np.sum((A @ c - w) ** 2))

    r = minimize_scalar(misfit, bounds=(xf - 3 * dx, xf + 3 * dx), method="bounded",
                        options=dict(xatol=1e-12 * (xc[-1] - xc[0])))
    return float(r.x), len(sel)
