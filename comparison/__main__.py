"""python -m comparison agreement|locking|pareto|stress|report [--quick] [--no-seed]

Each study prints its Markdown tables and stores its data in reports/data/<study>.json;
``report`` runs all of them and writes reports/REPORT.md with the PNG plots.  ``--quick``
writes ``<study>-quick.json`` / ``REPORT-quick.md`` instead, never over the full study's files.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from . import common

STUDIES = ("agreement", "locking", "pareto", "stress")


def main(argv=None):
    from core_se3.backend import pin_for_timing
    pin_for_timing()          # time the compiled product, not 'auto''s NumPy start
    ap = argparse.ArgumentParser(prog="python -m comparison", description=__doc__.splitlines()[0])
    ap.add_argument("study", choices=STUDIES + ("report",))
    ap.add_argument("--quick", action="store_true", help="a few cases only (development; writes <study>-quick.json, REPORT-quick.md)")
    ap.add_argument("--no-seed", action="store_true", help="skip the seed-element runs")
    ap.add_argument("--reuse", action="store_true",
                    help="report: reuse reports/data/<study>.json where present instead of rerunning")
    a = ap.parse_args(argv)
    from .models import fenicsx_available
    ok, why = fenicsx_available()
    if not ok:
        print(f"fenicsx_ref is not available ({why}): its columns are reported as not run.")
    if a.study == "report":
        from .report import build
        path = build(quick=a.quick, seed=not a.no_seed, reuse=a.reuse)
        print(f"wrote {path}")
        return 0
    mod = importlib.import_module(f".{a.study}", __package__)
    data = mod.run(quick=a.quick, seed=not a.no_seed)
    common.save(a.study, data, quick=a.quick)
    out = mod.markdown(data)
    print(out[0] if isinstance(out, tuple) else out)
    if hasattr(mod, "plot"):
        mod.plot(data, common.figure_path(f"{common.stem(a.study, a.quick)}.png"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
