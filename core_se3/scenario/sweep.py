"""Parameter sweeps: one scenario over a grid of values of one or more of its keys, each run
warm-started from the nearest finished one where the problem allows, with one CSV of the probes
against the swept values and a plot.

    from core_se3 import scenario
    res = scenario.sweep(scenario.load("gripper.toml"), {"fields.coil.B[2]": [0.02, 0.04, 0.06]},
                         out="out/sweep")
    res.rows[-1]["tip_0.uz"], res.files["csv"]

The same from the command line: ``core-se3 sweep FILE.toml --set KEY=v1,v2,... [--set ...]`` or
a ``[sweep]`` section in the file (``KEY = [v1, v2, ...]``).

Warm start: when the swept keys are values of loads, fields, magnets, material or solver (the
same mesh and supports), load control without prescribed motion, each run after the first is
one Newton solve at the final load factor starting from the final state of the nearest
finished run (in the swept values, scaled by each key's range); if that fails it runs the
scenario's load steps from the reference state.  Away from limit points (a single equilibrium
branch) both give the same state to the Newton tolerances; ``warm=False`` (``--cold``) always
steps from the reference.  The CSV records which runs were warm-started.
"""
from __future__ import annotations

import csv
import itertools
import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConvergenceError, CoreSE3Error, ScenarioError
from .keys import check_key

__all__ = ["sweep", "SweepResult", "parse_values", "WARM_SECTIONS"]

WARM_SECTIONS = ("loads", "fields", "magnets", "material", "solver")


@dataclass
class SweepResult:
    """What a sweep left: ``keys`` (the swept keys), ``rows`` (one dict per grid point: the swept
    values, status, warm, steps, iterations, every probe's final ux, uy, uz and rotation),
    ``files`` (csv, plot).

    Example
    -------
    >>> SweepResult(["material.E"], [{"material.E": 1.0, "status": "complete"}]).rows[0]["status"]
    'complete'
    """
    keys: list
    rows: list = field(default_factory=list)
    files: dict = field(default_factory=dict)


def parse_values(text, key="--set"):
    """The values of ``KEY=v1,v2,...`` (numbers; ``[a;b;c]`` for a vector value).

    Example
    -------
    >>> parse_values("0.02,0.04"), parse_values("[0;0;0.02],[0;0;0.04]")
    ([0.02, 0.04], [[0.0, 0.0, 0.02], [0.0, 0.0, 0.04]])
    """
    out, depth, cur = [], 0, ""
    for ch in text:
        depth += ch == "["
        depth -= ch == "]"
        if ch == "," and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += ch
    out.append(cur)
    vals = []
    for item in out:
        item = item.strip()
        try:
            if item.startswith("["):
                vals.append([float(x) for x in item.strip("[]").split(";")])
            else:
                vals.append(float(item))
        except ValueError:
            raise ScenarioError(f"cannot read the value {item!r} of {key} (numbers separated by commas, "
                                "a vector as [a;b;c])", key=key) from None
    if not vals or any(v == "" for v in vals):
        raise ScenarioError(f"{key} needs at least one value", key=key)
    return vals


def _nearest(done, point, spans):
    best, dist = None, np.inf
    for pt, g in done:
        d = sum(float((((np.ravel(a) - np.ravel(b)) / s) ** 2).sum()) for a, b, s in zip(pt, point, spans))
        if d < dist:
            best, dist = g, d
    return best


def _span(values):
    arr = np.array([np.ravel(v) for v in values], float)
    r = arr.max(0) - arr.min(0)
    return np.where(r > 0, r, 1.0)


def sweep(scn, grid, out=None, progress=None, warm=True, plot=True):
    """Run ``scn`` at every point of ``grid`` (dotted key -> list of values; several keys: the
    product), warm-starting each run from the nearest finished one.

    Parameters
    ----------
    scn : Scenario
        The base scenario.
    grid : dict
        Dotted key (as for ``Scenario.with_overrides``) -> values.
    out : str, optional
        Directory of ``sweep.csv`` and ``sweep.png`` (default out/NAME-sweep).
    progress : bool, optional
        Progress line (None: only on a terminal).
    warm : bool, optional
        Warm starts (module docstring).
    plot : bool, optional
        Write ``sweep.png``.

    Returns
    -------
    SweepResult

    Example
    -------
    >>> import tempfile
    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
    ...     "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
    ...     "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}],
    ...     "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": 1}})
    >>> res = sweep(scn, {"material.E": [1.2e6, 2.4e6]}, out=tempfile.mkdtemp(), plot=False)
    >>> a, b = (r["tip.uz"] for r in res.rows)
    >>> round(a / b, 6), [r["warm"] for r in res.rows]           # nearly linear: twice E, half the lift
    (2.0, [False, True])
    """
    from ..io import Progress
    import sys
    keys = list(grid)
    for k in keys:
        check_key(scn.raw, k, scn.file)
    points = list(itertools.product(*[grid[k] for k in keys]))
    spans = [_span(grid[k]) for k in keys]
    out = os.fspath(out or os.path.join("out", f"{scn.name}-sweep"))
    os.makedirs(out, exist_ok=True)
    can_warm = warm and all(k.split(".")[0].split("[")[0] in WARM_SECTIONS for k in keys)
    bar = Progress(len(points), sys.stdout.isatty() if progress is None else bool(progress), delay=0.0)
    result = SweepResult(keys)
    done = []
    for i, pt in enumerate(points):
        s = scn.with_overrides(dict(zip(keys, pt)))
        g_start = _nearest(done, pt, spans) if can_warm and done else None
        row = {k: v for k, v in zip(keys, pt)}
        try:
            final, nsteps, its, warm_used = _solve(s, g_start)
            row.update(status="complete", warm=warm_used, steps=nsteps, iterations=its)
            for name, p in final.probes.items():
                for c, x in zip("xyz", p["u"]):
                    row[f"{name}.u{c}"] = float(x)
                row[f"{name}.rotation"] = float(np.linalg.norm(p["w"]))
            done.append((pt, final.g))
        except (ConvergenceError, CoreSE3Error) as exc:
            row.update(status="failed", warm=g_start is not None, error=str(exc).split("\n")[0][:200])
        result.rows.append(row)
        bar.update(i + 1, 0.0, row.get("iterations", 0), 0.0, extra=f"  {', '.join(f'{k}={v}' for k, v in zip(keys, pt))}",
                   label=f"run {i + 1}/{len(points)}")
    bar.close()
    result.files["csv"] = _write_csv(os.path.join(out, "sweep.csv"), result)
    if plot:
        result.files["plot"] = _plot(os.path.join(out, "sweep.png"), result, scn.name)
    return result


def _solve(s, g_start):
    """Solve one grid point: (final StepResult, steps, iterations, warm).  Warm: one Newton
    solve at the final load factor from ``g_start``; cold (and on a failed warm start): the
    scenario's own load steps from the reference state."""
    from ..solvers import NewtonOptions, NewtonState, newton_steps
    sv = s.solver
    if g_start is not None and sv["control"] == "load" and not s.problem.has_prescribed_motion \
            and not s.problem.element.stateful:
        lam = s.load_factors()[-1]
        opts = NewtonOptions(rtol=sv["rtol"], dtol=sv["dtol"], max_iter=sv["max_iter"], max_cutbacks=0,
                             linear_solver=sv["linear_solver"], iteration=sv["iteration"])
        try:
            items = list(newton_steps(s.problem, [lam], opts, start=NewtonState(lam * (1 - 1e-9), g_start)))
            its = sum(e["iterations"] for e in items[-1].tries)
            return items[-1].step, 1, its, True
        except (ConvergenceError, CoreSE3Error):
            pass
    res = s.problem.solve()
    return res.final, len(res.steps) - 1, int(sum(st.iterations for st in res.steps)), False


def _columns(result):
    cols = []
    for r in result.rows:
        for k in r:
            if k not in cols:
                cols.append(k)
    return cols


def _cell(v):
    if isinstance(v, (list, tuple)):
        return ";".join(f"{x:.17g}" for x in v)
    if isinstance(v, float):
        return repr(v)
    return str(v)


def _write_csv(path, result):
    from ..io import atomic_path
    cols = _columns(result)
    with atomic_path(path) as tmp:
        with open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(cols)
            for r in result.rows:
                w.writerow([_cell(r.get(c, "")) for c in cols])
    return path


def _plot(path, result, title):
    """Every probe displacement component against the first swept value (one line per value of
    the other keys)."""
    from ..io import atomic_path, new_figure
    fig = new_figure()
    ax = fig.add_subplot(1, 1, 1)
    key = result.keys[0]
    xs = [r[key] for r in result.rows]
    x = np.array([np.linalg.norm(v) if isinstance(v, (list, tuple)) else v for v in xs], float)
    cols = [c for c in _columns(result) if c.endswith((".ux", ".uy", ".uz"))]
    ys = {c: np.array([r.get(c, np.nan) for r in result.rows], float) for c in cols}
    big = max([np.nanmax(np.abs(y)) for y in ys.values() if np.isfinite(y).any()] + [0.0])
    for i, (c, y) in enumerate(ys.items()):
        if np.isfinite(y).any() and np.nanmax(np.abs(y)) > 1e-9 * big:
            ax.plot(x, y, "o-", ms=4, label=c, color=f"C{i % 10}")
    ax.set_xlabel(key + (" (|vector|)" if isinstance(xs[0], (list, tuple)) else ""))
    ax.set_ylabel("final probe displacement")
    ax.set_title(f"{title}: sweep of {', '.join(result.keys)}")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    return path
