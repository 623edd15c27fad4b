"""Record and compare the JSON results of every catalogue case (and every example scenario).

Used to show that a change which must not change the mechanics (a restructuring, a compiled
backend) leaves every result where it was:

    python benchmarks/catalogue_regression.py record out/regression/before      # before the change
    python benchmarks/catalogue_regression.py record out/regression/after       # after it
    python benchmarks/catalogue_regression.py compare out/regression/before out/regression/after

``record`` runs ``core-se3 bench run NAME --json`` for every case of ``core-se3 bench list`` at its
default settings, and ``core-se3 run`` for every ``examples/*.toml``, in subprocesses (``--jobs``
at a time), through the command line only, so that the same script records before and after
any change of the Python API.  Extra environment settings (e.g. a backend switch) are passed
with ``--env KEY=VALUE``.

``compare`` walks both documents and compares every number: load factors, loads, probe
displacements and rotations, errors, critical points, ... to ``--rtol`` relative to the largest
magnitude of the same quantity anywhere on the path (all list indices wildcarded: a displacement
component that passes through zero is compared against the path's scale, not against zero);
iteration counts exactly; the residuals and balance errors to ``--residual-atol`` (they are
relative already, and their converged values are round-off).  Timings, dates and paths are
skipped.  Exit status 1 on any difference.
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import glob
import json
import os
import re
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# "time": the wall time of each design iteration
# "backend": which backend evaluated a step (record --env CORE_SE3_BACKEND=... compares them)
# "provenance": how a result ran (version, backend, ranks, linear solver, peak memory), not what it is
# "residual_force", "residual_moment": the residual's parts in force units, round-off of any scale
# (the relative "residual" they make up is compared)
SKIP_KEYS = {"timings", "time", "scenario", "fingerprint", "file", "error", "monitor_and_perfect_branch",
             "backend", "provenance", "residual_force", "residual_moment"}
EXACT_KEYS = {"iterations", "substeps", "cutbacks", "step", "n_points", "negative_eigenvalues",
              "det_sign", "attempts", "linear_solves"}
ROUNDOFF_KEYS = {"residual", "residual_floor", "residual_history", "balance_error"}


def _cli(python):
    return [python, "-m", "core_se3"]


def _cases(python, env):
    out = subprocess.run(_cli(python) + ["bench", "list"], capture_output=True, text=True, env=env,
                         check=True, cwd=ROOT)
    return [line.split()[0] for line in out.stdout.splitlines() if line.strip()]


def _run(cmd, env, log):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT)
    with open(log, "w") as fh:
        fh.write(" ".join(cmd) + "\n" + p.stdout + p.stderr)
    return p.returncode, time.perf_counter() - t0


def record(args):
    env = dict(os.environ)
    for kv in args.env or []:
        k, v = kv.split("=", 1)
        env[k] = v
    os.makedirs(args.dir, exist_ok=True)
    jobs = []
    for name in args.cases or _cases(args.python, env):
        jobs.append((name, _cli(args.python) + ["bench", "run", name, "--json",
                                                os.path.join(args.dir, f"case_{name}.json")]))
    if not args.cases:
        for toml in sorted(glob.glob(os.path.join(ROOT, "examples", "*.toml"))):
            name = os.path.splitext(os.path.basename(toml))[0]
            out = os.path.join(args.dir, f"scenario_{name}")
            jobs.append((f"scenario:{name}", _cli(args.python) + ["run", toml, "--out", out, "--force",
                                                                  "--quiet"]))
    failed = []
    with cf.ThreadPoolExecutor(args.jobs) as pool:
        futs = {pool.submit(_run, cmd, env, os.path.join(args.dir, name.replace(":", "_") + ".log")): name
                for name, cmd in jobs}
        for f in cf.as_completed(futs):
            rc, dt = f.result()
            print(f"{futs[f]:<32} {'ok' if rc == 0 else f'exit {rc}'}  {dt:7.1f} s", flush=True)
            if rc != 0:
                failed.append(futs[f])
    return 1 if failed else 0


def _wild(path):
    return re.sub(r"\[\d+\]", "[*]", path)


def _scales(doc, path="", out=None):
    """Largest |number| per wildcarded path (every list index replaced by *)."""
    out = {} if out is None else out
    if isinstance(doc, dict):
        for k, v in doc.items():
            _scales(v, f"{path}.{k}" if path else str(k), out)
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            _scales(v, f"{path}[{i}]", out)
    elif isinstance(doc, (int, float)) and not isinstance(doc, bool):
        w = _wild(path)
        out[w] = max(out.get(w, 0.0), abs(doc))
    return out


class _Cmp:
    def __init__(self, rtol, res_atol, scales=None):
        self.rtol, self.res_atol = rtol, res_atol
        self.scales = scales or {}
        self.diffs = []
        self.compared = 0
        self.worst = 0.0

    def walk(self, a, b, path):
        key = path.rsplit(".", 1)[-1].split("[")[0]
        if key in SKIP_KEYS:
            return
        if isinstance(a, dict) and isinstance(b, dict):
            for k in sorted(set(a) | set(b)):
                if k in SKIP_KEYS:
                    continue
                if k not in a or k not in b:
                    if k in a and a[k] is None or k in b and b[k] is None:
                        continue
                    self.diffs.append(f"{path}.{k}: only in {'first' if k in a else 'second'}")
                    continue
                self.walk(a[k], b[k], f"{path}.{k}")
            return
        if isinstance(a, list) and isinstance(b, list):
            if len(a) != len(b):
                self.diffs.append(f"{path}: length {len(a)} vs {len(b)}")
                return
            for i, (x, y) in enumerate(zip(a, b)):
                self.walk(x, y, f"{path}[{i}]")
            return
        if isinstance(a, bool) or isinstance(b, bool) or isinstance(a, str) or a is None or b is None:
            if a != b and key not in ("description", "status"):
                self.diffs.append(f"{path}: {a!r} vs {b!r}")
            return
        if isinstance(a, (int, float)) and isinstance(b, (int, float)):
            self.compared += 1
            if key in EXACT_KEYS:
                if a != b:
                    self.diffs.append(f"{path}: {a!r} vs {b!r} (must be equal)")
                return
            if key in ROUNDOFF_KEYS:
                if abs(a - b) > self.res_atol:
                    self.diffs.append(f"{path}: {a!r} vs {b!r} (absolute {abs(a - b):.1e})")
                return
            scale = self.scales.get(_wild(path.split(".", 1)[1] if "." in path else path), 0.0)
            ref = max(abs(a), abs(b), scale, 1e-300)
            rel = abs(a - b) / ref
            self.worst = max(self.worst, rel)
            if rel > self.rtol and abs(a - b) > 1e-300:
                self.diffs.append(f"{path}: {a!r} vs {b!r} (relative {rel:.2e})")
            return
        if a != b:
            self.diffs.append(f"{path}: {a!r} vs {b!r}")


def _docs(d):
    out = {}
    for f in sorted(glob.glob(os.path.join(d, "case_*.json"))):
        out[os.path.basename(f)[5:-5]] = f
    for f in sorted(glob.glob(os.path.join(d, "scenario_*", "results.json"))):
        out["scenario:" + os.path.basename(os.path.dirname(f))[9:]] = f
    return out


def compare(args):
    A, B = _docs(args.a), _docs(args.b)
    bad = 0
    lines = []
    for name in sorted(set(A) | set(B)):
        if name not in A or name not in B:
            lines.append(f"{name:<32} MISSING in {'second' if name in A else 'first'}")
            bad += 1
            continue
        with open(A[name]) as fa, open(B[name]) as fb:
            da, db = json.load(fa), json.load(fb)
        c = _Cmp(args.rtol, args.residual_atol, _scales(da, ""))
        c.walk(da, db, name)
        status = "same" if not c.diffs else f"{len(c.diffs)} DIFFERENCES"
        lines.append(f"{name:<32} {status:<16} {c.compared:>7} numbers, worst relative {c.worst:.1e}")
        lines += ["    " + d for d in c.diffs[:8]]
        bad += bool(c.diffs)
    lines.append(f"{len(set(A) | set(B))} documents, {bad} with differences (rtol {args.rtol:g}, "
                 f"residual atol {args.residual_atol:g})")
    print("\n".join(lines))
    if args.output:                      # the same lines as a results page
        cmd = " ".join(["python benchmarks/catalogue_regression.py compare", *sys.argv[2:]])
        title = args.title or f"{args.a} against {args.b}"
        with open(args.output, "w") as fh:
            fh.write(f"# Catalogue regression: {title}\n\n`{cmd}` on "
                     f"{time.strftime('%Y-%m-%dT%H:%M:%S')}\n\n```\n" + "\n".join(lines) + "\n```\n")
    return 1 if bad else 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record")
    r.add_argument("dir")
    r.add_argument("--python", default=os.path.join(ROOT, ".venv", "bin", "python"))
    r.add_argument("--jobs", type=int, default=2)
    r.add_argument("--cases", nargs="*", default=None, help="only these catalogue cases")
    r.add_argument("--env", action="append", metavar="KEY=VALUE")
    c = sub.add_parser("compare")
    c.add_argument("a")
    c.add_argument("b")
    c.add_argument("--rtol", type=float, default=1e-12)
    c.add_argument("--residual-atol", type=float, default=1e-12)
    c.add_argument("--output", default=None, help="also write the comparison as a Markdown page")
    c.add_argument("--title", default=None, help="the page's title (default: the two directories)")
    args = ap.parse_args(argv)
    return record(args) if args.cmd == "record" else compare(args)


if __name__ == "__main__":
    sys.exit(main())
