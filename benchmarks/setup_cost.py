#!/usr/bin/env python3
"""What a large mesh's set-up and Newton iteration cost against one factorisation of its tangent
(the floor of a Newton iteration), the checks at the element's build included, in one run.

Per mesh (a flat strip, a cylinder panel, the closed cubed sphere read from a file -- its cross
field's cuts --, Gmsh's unstructured dome if gmsh is installed): the mesh's build (a generator,
or the file read: mesh checks, fitted normals, gauge, cross field), the parts of the default
element's build under cProfile (the least-turn gauge, the cuts' matching and side turns, the
frame-turn, warp, vortex and winding checks, the rest: the element's stiffness data), the
compiled pattern and kernels' data, the first compiled tangent (numba's compile or cache load)
and a warm one (the best of 3); then one factorisation + solve of that tangent
(``make_solver('auto')``, the better of two), and with ``--solve`` one load step
(``Problem.solve(steps=1)``: assembly, solves and the rest per Newton iteration, from
``Result.timings``).  Every time is also given over the factorisation.  Each case runs after
the same case at 4 x 4 (imports, numba's compile or cache load, the solvers' start).

    .venv/bin/python benchmarks/setup_cost.py                          # all meshes (~6 min)
    .venv/bin/python benchmarks/setup_cost.py --cases sphere:32 strip:128 --solve
    .venv/bin/python benchmarks/setup_cost.py --solve strip:128 sphere:32   # all meshes, two solved

Writes the section "Set-up and iteration against the factorisation" of
``benchmarks/results/scaling.md`` (``scaling.py`` keeps it).
"""
from __future__ import annotations

import argparse
import cProfile
import datetime
import os
import pstats
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
OUT = ROOT / "benchmarks" / "results" / "scaling.md"
MARK = "## Set-up and iteration against the factorisation"
CASES = ("strip:128", "strip:256", "cylinder:128", "sphere:32", "sphere:64", "dome:64")
# label -> (file, function) of core_se3 whose cumulative time is reported
PARTS = (("file read (readers.from_meshio)", "readers.py", "from_meshio"),
         ("  mesh checks (Mesh.__post_init__)", "core.py", "__post_init__"),
         ("  doubly curved parts' frames", "readers.py", "_curved_part_frames"),
         ("  cross field (edge_aligned_d1)", "cross_field.py", "edge_aligned_d1"),
         ("element build", "element_default.py", "__init__"),
         ("  gauge (element_gauge)", "element_default.py", "element_gauge"),
         ("  cut matching (_matching)", "element_default.py", "_matching"),
         ("  cuts' side turns (side_turns)", "element_default.py", "side_turns"),
         ("  C^T Dbar C (_congruence)", "element_default.py", "_congruence"),
         ("  check_vortices", "element_default.py", "check_vortices"),
         ("  check_frame_turns", "frame_turns.py", "check_frame_turns"),
         ("  check_warp", "warp.py", "check_warp"),
         ("  check_node_windings", "frame_turns.py", "check_node_windings"),
         ("pressure's element area (reference_area)", "element_default.py", "reference_area"))


def build_mesh(kind, n):
    """The mesh of a case: 'strip' n x n (10 x 10), 'cylinder' n x n (R 10, 120 deg, 20 long),
    'sphere' the closed cubed sphere (R 10) n x n per face written without frames and read,
    'dome' Gmsh's unstructured whole hemisphere (element size 25.6 / n) read."""
    from core_se3 import mesh
    if kind == "strip":
        return mesh.rectangle(10.0, 10.0, n, n)
    if kind == "cylinder":
        return mesh.cylinder_panel(10.0, 20.0, -np.pi / 3, np.pi / 3, n, n)
    if kind == "sphere":
        import meshio
        from curved_frames import cubed_sphere
        X, q = cubed_sphere(n)
        return mesh.from_meshio(meshio.Mesh(X, [("quad", q)]))
    import tempfile
    from curved_frames import gmsh_dome
    with tempfile.TemporaryDirectory() as tmp:
        gmsh_dome(25.6 / n, os.path.join(tmp, "dome.msh"))
        return mesh.from_meshio(os.path.join(tmp, "dome.msh"), triangles="split")


def build_problem(kind, m):
    """Strip and cylinder: clamped at x0 / their first edge, an end force; sphere and dome: a
    follower pressure, the sphere held against its rigid motions only, the dome clamped at its rim."""
    from core_se3 import Material, Problem
    p = Problem(m, Material(1e6, 0.3, 0.1), backend="numba")
    if kind in ("sphere", "dome"):
        z = m.X[:, 2]
        if kind == "sphere":
            p.fix([int(np.argmax(z)), int(np.argmin(z)), int(np.argmax(m.X[:, 0]))], (0, 1))
        else:
            p.clamp(np.flatnonzero(z < z.min() + 1e-6))
        p.add_pressure(1.0, follower=True)
    else:
        p.clamp("x0")
        p.add_edge_force("x1", (0.0, 0.0, 1.0))
    return p


def _cumulative(stats, file, func):
    return max((v[3] for (f, _, name), v in stats.stats.items()
                if name == func and os.path.basename(f) == file and "core_se3" in f), default=0.0)


def measure(case, solve):
    """One case's times [s] (dict of label -> seconds) and the factorisation's."""
    from core_se3.solvers.linalg import Factorization, make_solver
    kind, n = case.split(":")
    prof, t = cProfile.Profile(), {}
    prof.enable()
    t0 = time.perf_counter()
    m = build_mesh(kind, int(n))
    t["mesh build"] = time.perf_counter() - t0
    p = build_problem(kind, m)
    t0 = time.perf_counter()
    el = p.element
    t["element (Problem.element)"] = time.perf_counter() - t0
    prof.disable()
    st = pstats.Stats(prof)
    t.update({label: _cumulative(st, f, fn) for label, f, fn in PARTS})
    t0 = time.perf_counter()
    pattern = p.assembler().pattern()
    el.compiled(pattern)
    t["assembler, pattern, kernels' data"] = time.perf_counter() - t0
    data = pattern.new_data()
    t0 = time.perf_counter()
    p.evaluate(m.g0, 1.0, tangent=True, out=data)
    t["first compiled tangent (compile / cache)"] = time.perf_counter() - t0
    t["compiled tangent (warm, best of 3)"] = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        ev = p.evaluate(m.g0, 1.0, tangent=True, out=data)
        t["compiled tangent (warm, best of 3)"] = min(t["compiled tangent (warm, best of 3)"], time.perf_counter() - t0)
    solver, fac = make_solver("auto"), np.inf
    for _ in range(2):                        # the better of two (the first starts MUMPS)
        t0 = time.perf_counter()
        with Factorization(ev.K, solver) as f:
            f.solve(-ev.r)
        fac = min(fac, time.perf_counter() - t0)
    if solve:
        res = p.solve(steps=1)
        its = max(sum(s.iterations for s in res.steps), 1)
        t.update({f"per Newton iteration: {k}": float(res.timings.get(k, 0.0)) / its
                  for k in ("assembly", "solve", "other")})
        t["Newton iterations"] = its
    return dict(case=case, n_el=m.n_elements, n_dof=int(p.assembler().nfree), fac=fac, times=t)


NOTES = """
Read (2026-12-05, speed7; a shared 2-core machine: single timings move by up to 2x between runs, the
ratios of one column are of one run; ranges below over two runs): the set-up is dominated by the
element's stiffness data ("element build" less the rows under it: the laws' matrices, the enhanced
membrane's condensation, the drilling and shear corrections; chunked NumPy, O(m)) -- 0.8 ... 2.7
factorisations, the most on the small and the cheaply factorised meshes.  The checks the recent
stops added are O(m) and vectorised: frame turns <= 0.03, vortices <= 0.034, warp <= 0.007, node
windings <= 0.003 of a factorisation; the cuts' handling (matching <= 0.01, side turns <= 0.15 --
the sphere at 32, 0.058 s since the sides' mean frames round the singular nodes, 0.021 s before --,
C^T Dbar C <= 0.024) and the file read's (mesh checks <= 0.074, doubly curved parts' frames 0.14 ...
0.28, of it the cross field <= 0.089) likewise.  What a scene does not need is skipped: a
generator's flat or developable mesh has no cut (``edge_matching`` is None after one pass over the
edges, <= 0.01), so no side turns, no C^T Dbar C, no node windings (0 s), no cross field and no
fitted normals (only a file's doubly curved parts get them); the gauge stops after one pass of
``normal_turns`` where no edge turns about the normal (strip, cylinder: <= 0.05).  Changed by
speed7: C^T Dbar C across the cuts was a three-operand einsum on every element's (24, 24) (the
sphere at 64 per face: 0.90 s against the new 0.042 s in one process, 21x; at 32: 0.222 against
0.017 s, 13x; ~0.1 of a factorisation before) -- now D itself off the cuts, an indexing across
them, the einsum only round the singular nodes, to the bit; and the frame-turn check takes the
rotation's log only (0.6x its time, the same bits).  Per Newton iteration (strip 128 / sphere 32):
the compiled assembly 0.10 ... 0.15 / 0.38 ... 0.42 of the factorisation, the solves with refinement
0.7 ... 1.6 / 1.1 ... 2.1, the rest 0.16 ... 0.25 / 0.20.  Left as they are: the doubly curved parts'
frames of a file (the least-turn gauge's Laplacian LU, fitted normals, cross field), the follower
pressure's element area recomputed without the element (<= 0.11 per pressure load, by design: a
distributed rank builds only its own elements), and per load-stepped solve the end check's inertia
(one more symmetric factorisation where the stability check runs: conservative loads; strip 128:
5.8 s against 4.8 s for a factorisation in a cProfile run, ~1.2).
"""


def section(rows, argv):
    """The markdown section of the rows."""
    labels = [k for k in rows[0]["times"]]
    for r in rows[1:]:
        labels += [k for k in r["times"] if k not in labels]
    head = "| | " + " | ".join(f"{r['case']} ({r['n_el']} el, {r['n_dof']} dof)" for r in rows) + " |"
    md = [MARK, "", f"`python benchmarks/setup_cost.py {' '.join(argv)}`".replace(" `", "`") +
          f" on {datetime.datetime.now().isoformat(timespec='seconds')}: seconds, and over one factorisation + solve "
          "of the tangent at the reference state (`make_solver('auto')`, the same run).", "", head,
          "|---|" + "---:|" * len(rows),
          "| one factorisation + solve [s] | " + " | ".join(f"{r['fac']:.3f}" for r in rows) + " |"]
    for k in labels:
        cells = []
        for r in rows:
            v = r["times"].get(k)
            cells.append("" if v is None else f"{v:g}" if k == "Newton iterations"
                         else f"{v:.3f} ({v / r['fac']:.3f})")
        md.append(f"| {k} | " + " | ".join(cells) + " |")
    return "\n".join(md) + "\n" + NOTES


def write(text):
    """Replace (or append) the section in scaling.md."""
    old = OUT.read_text() if OUT.exists() else ""
    keep = old.split(MARK)[0].rstrip("\n")
    OUT.write_text((keep + "\n\n" if keep else "") + text)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", nargs="*", default=list(CASES), help="KIND:N, KIND in strip, cylinder, sphere, dome")
    ap.add_argument("--solve", nargs="*", default=None,
                    help="also one load step (the cost per Newton iteration) of these cases (none named: all)")
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    rows = []
    for case in args.cases:
        if case.startswith("dome") and not _have_gmsh():
            print(f"{case}: skipped (no gmsh)")
            continue
        solve = args.solve is not None and (not args.solve or case in args.solve)
        measure(f"{case.split(':')[0]}:4", solve)        # warm-up: imports, numba caches, solvers
        rows.append(measure(case, solve))
        print(f"{case}: {rows[-1]['n_el']} elements, factorisation {rows[-1]['fac']:.3f} s", flush=True)
    text = section(rows, sys.argv[1:] if argv is None else argv)
    print(text)
    if not args.no_write:
        write(text)


def _have_gmsh():
    try:
        import gmsh  # noqa: F401
    except ImportError:
        return False
    return True


if __name__ == "__main__":
    main()
