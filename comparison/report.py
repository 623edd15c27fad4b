"""``python -m comparison report``: run every study and write reports/REPORT.md.

The report's numbers are all computed here from the studies' data (reports/data/*.json);
nothing in it is typed in by hand.
"""
from __future__ import annotations

import os
import platform
import subprocess
import sys
import time

import numpy as np

from . import agreement, common, locking, pareto, stress
from .models import fenicsx_available
from .tables import markdown_table, pct

__all__ = ["build", "environment"]


def _version(mod):
    try:
        m = __import__(mod)
        return getattr(m, "__version__", "?")
    except Exception as exc:
        return f"not available ({type(exc).__name__})"


def environment():
    cpu = "?"
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            cpu = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                cwd=os.path.dirname(__file__)).stdout.strip()
    except OSError:
        commit = "?"
    return dict(cpu=cpu, cores=os.cpu_count(), platform=platform.platform(), python=sys.version.split()[0],
                numpy=_version("numpy"), scipy=_version("scipy"), dolfinx=_version("dolfinx"),
                petsc4py=_version("petsc4py"), matplotlib=_version("matplotlib"), commit=commit,
                load=os.getloadavg())


def _run_or_load(study, mod, quick, seed, reuse, **kw):
    if reuse:
        try:
            data = common.load(study, quick)
            return data, data.get("wall_time")
        except OSError:
            pass
    t0 = time.perf_counter()
    env = environment()
    data = mod.run(quick=quick, seed=seed, **kw)
    dt = time.perf_counter() - t0
    data["wall_time"] = dt
    data["commit"] = env["commit"]  # the code the study ran (others may commit while it runs)
    # the machine the study's times were measured on (a --reuse render may run elsewhere)
    data["machine"] = dict(cpu=env["cpu"], cores=env["cores"], load_start=env["load"][0],
                           load_end=os.getloadavg()[0])
    common.save(study, data, quick)
    return data, dt


def build(quick=False, seed=True, reuse=False):
    t0 = time.perf_counter()
    env0 = environment()
    fx_ok, fx_why = fenicsx_available()
    data, walls = {}, {}
    for study, mod in (("agreement", agreement), ("locking", locking), ("pareto", pareto)):
        data[study], walls[study] = _run_or_load(study, mod, quick, seed, reuse)
    data["stress"], walls["stress"] = _run_or_load("stress", stress, quick, seed, reuse, locking=data["locking"])
    figs = {}
    for study, mod in (("agreement", agreement), ("locking", locking), ("pareto", pareto)):
        p = common.figure_path(f"{common.stem(study, quick)}.png")
        mod.plot(data[study], p)
        figs[study] = os.path.relpath(p, common.OUT)
    total = time.perf_counter() - t0
    if reuse:  # the studies' own wall times, measured when they ran
        total = sum(v for v in walls.values() if v) + total
    env1 = environment()
    text = render(data, walls, total, env0, env1, fx_ok, fx_why, figs, quick, reuse)
    path = os.path.normpath(os.path.join(common.OUT, f"{common.stem('REPORT', quick)}.md"))
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return path


def summary_rows(data):
    """The summary table: (question, answer) rows with the measured numbers."""
    rows = []
    ag = data["agreement"]["cases"]
    for nu in (0.0, 0.3):
        sub = [r for r in ag if r["nu"] == nu and r["levels"][-1].get("dist_core_psri") is not None]
        non_t = [r for r in sub if r["case"] != "torsion"]
        if non_t:
            worst = max(non_t, key=lambda r: r["levels"][-1]["dist_core_psri"])
            d = worst["levels"][-1]["dist_core_psri"]
            rows.append([f"agreement core_se3 vs fenicsx_ref (PSRI), ν = {nu:g}, {len(non_t)} cases without torsion",
                         f"worst {pct(d)} ({worst['label']}); 1 % bar {'met' if d < 0.01 else 'MISSED'}"])
        tor = [r for r in sub if r["case"] == "torsion"]
        for r in tor:
            lv = r["levels"][-1]
            tr = lv.get("torque_ratio", [np.nan])[-1]
            rows.append([f"agreement, torsion to π/2, ν = {nu:g}",
                         f"probe (end shortening) {pct(lv['dist_core_psri'])}, torque core/fx {tr:.3f}: "
                         "a constitutive difference (see Findings)"])
    # locking: per variant, the finest grid's worst error at L/h = 100 and 1e4, and the largest
    # growth error(1e4) / error(100) on any one mesh (a locking element grows like (L/h)^2)
    lk = data["locking"]["runs"]
    for variant, label in (("default", "core default"), ("psri", "fx PSRI"), ("full", "fx full"),
                           ("seed", "core seed")):
        sub = [r for r in lk if r["variant"] == variant and r["case"] != "torsion"]
        if not sub:
            continue
        thin = [r for r in sub if r["L_over_h"] == 1e4]
        nf = sum(r["status"] != "ok" for r in thin)
        growth = []
        for r in thin:
            twin = [q for q in sub if q["L_over_h"] == 1e2 and q["case"] == r["case"] and q["mesh"] == r["mesh"]]
            # errors at round-off (exact models) have no meaningful ratio
            if r["error"] is not None and twin and twin[0]["error"] and min(r["error"], twin[0]["error"]) > 1e-10:
                growth.append((r["error"] / twin[0]["error"], r))
        fin = {}
        for r in sub:
            if r["error"] is not None and (r["case"] not in fin or r["n_dofs"] > fin[r["case"]]["n_dofs"]):
                fin[r["case"]] = r
        worst = {}
        for ratio in (1e2, 1e4):
            errs = [(r["error"], r["case"]) for r in sub if r["L_over_h"] == ratio and r["error"] is not None
                    and r["mesh"] == next((q["mesh"] for q in sub if q["case"] == r["case"]
                                           and q["n_dofs"] == max(x["n_dofs"] or 0 for x in sub
                                                                  if x["case"] == r["case"])), None)]
            worst[ratio] = max(errs) if errs else None
        txt = []
        if worst[1e4]:
            txt.append(f"finest grids: worst {pct(worst[1e4][0])} at L/h = 1e4 ({worst[1e4][1]})"
                       + (f" vs {pct(worst[1e2][0])} at L/h = 100" if worst[1e2] else ""))
        if growth:
            g, r = max(growth, key=lambda t: t[0])
            txt.append(f"largest growth error(1e4)/error(100) on one mesh {g:.3g}× "
                       f"({r['case']} {r['mesh'][0]}×{r['mesh'][1]})")
        if nf:
            txt.append(f"{nf} of {len(thin)} runs at L/h = 1e4 failed")
        rows.append([f"locking (cantilever, roll-up, arch), {label}", "; ".join(txt) or "no run converged"])
    # pareto: time to 0.1 %
    s = pareto.summarize(data["pareto"])
    for name in dict.fromkeys(r["case"] for r in data["pareto"]["runs"]):
        cells = []
        tt = {}
        for model in ("core_se3", "fenicsx_ref"):
            v = s.get((name, model))
            if not v:
                continue
            t, how = v["times"][1e-3]
            tt[model] = t
            cells.append(f"{model} " + ("not reached (floor " + pct(v["min_error"]) + ")" if how == "not reached"
                                         else f"{t:.2g} s" + (" extrapolated" if how == "extrapolated" else "")))
        if len(tt) == 2 and all(np.isfinite(list(tt.values()))):
            cells.append(f"ratio fx/core {tt['fenicsx_ref'] / tt['core_se3']:.2g}")
        rows.append([f"time to 0.1 % error, {pareto.CASES[name][0]}", "; ".join(cells)])
    pr = stress.pass_rates(data["stress"])
    if data["pareto"]["runs"]:
        nd = max(r["n_dofs"] or 0 for r in data["pareto"]["runs"])
        rows.append(["problem sizes of the run-time study", f"up to {nd} dofs (1-D strips): per-iteration "
                     "overheads dominate; see benchmarks/results/scaling.md for core_se3 at 1e4-1e5 elements"])
    for (model, kind), c in sorted(pr.items()):
        n = c["pass_"] + c["fail"] + c["WRONG"]
        rows.append([f"stress {('runs' if kind == 'run' else 'tangent checks')}, {model}",
                     f"{c['pass_']}/{n} pass, {c['fail']} reported failures, {c['WRONG']} silent wrong answers"])
    return rows


def _torsion_thin(data):
    """Sentence: the two models' finest-grid J/J_M at the thickest and thinnest strip."""
    lk = [r for r in data["locking"]["runs"] if r["case"] == "torsion" and r["error"] is not None
          and r["variant"] in ("default", "psri")]
    if not lk:
        return ""
    parts = []
    for ratio in (min(r["L_over_h"] for r in lk), max(r["L_over_h"] for r in lk)):
        fin = {}
        for r in lk:
            if r["L_over_h"] == ratio and (r["model"] not in fin or r["n_dofs"] > fin[r["model"]]["n_dofs"]):
                fin[r["model"]] = r
        if len(fin) == 2:
            c, f = fin["core_se3"]["error"], fin["fenicsx_ref"]["error"]
            parts.append(f"L/h = {ratio:g} (w/h = {0.25 * ratio:g}): J/J_M = {c:.4f} (core_se3) and "
                         f"{f:.4f} (fenicsx_ref), ratio {c / f:.4f}")
    if not parts:
        return ""
    return (" The difference is a thick-strip effect: in the locking study's small-twist runs, "
            + "; ".join(parts) + ". The common excess over J_M at small h is the end restraint "
            "(clamp and rigid end edge hold the warping), the same in both models.")


def _psri_alpha_note(row):
    """': the same scheme there' when PSRI's full-rule fraction alpha = min(1, (h/h_e)^2) is 1
    on the row's fine grid (cells smaller than the thickness), so full = PSRI by construction."""
    from math import hypot
    from core_se3.catalogue import case_params, get_case
    case = get_case(row["case"])
    p = case_params(case, row["overrides"])
    nx, ny = row["levels"][-1]["mesh_fx"]
    if case.geometry != "strip":
        return ""
    he = hypot(p["L"] / nx, p["width"] / ny)  # Q2 cell diameter (rectangles)
    if p["h"] < he:
        return ""
    return (f": the same scheme on the {nx}×{ny} grid, whose cells (diameter {he:.3g}) are smaller "
            f"than the thickness {p['h']:g}, so PSRI's α = min(1, (h/h_e)²) = 1 -- their agreement "
            "does not test locking")


def _findings(data):
    """Explanations attached to measured disagreements (text conditioned on the data)."""
    out = []
    ag = data["agreement"]["cases"]
    tor = [r for r in ag if r["case"] == "torsion" and r["levels"][-1].get("torque_ratio")]
    if tor:
        ratios = ", ".join(f"{r['levels'][-1]['torque_ratio'][-1]:.3f} at ν = {r['nu']:g}" for r in tor)
        coarse = ", ".join(f"{r['levels'][0]['torque_ratio'][-1]:.3f}" for r in tor if r["levels"][0].get("torque_ratio"))
        full = ", ".join(pct(r["levels"][-1].get("dist_full_psri")) for r in tor)
        out.append(
            f"* **torsion** is the case that disagrees: core_se3's end torque at π/2 is {ratios} times "
            f"fenicsx_ref's (coarse grids: {coarse}), unchanged by refinement, so it is not discretisation "
            f"error. (fenicsx_ref's full and PSRI runs differ by {full}{_psri_alpha_note(tor[-1])}.) core_se3 "
            "applies the plate bending law to the unsymmetrised Cosserat curvature K_αβ = (d₃ × Γ_α)·A_β "
            "(docs/CONVENTIONS, core_se3/fem/material.py), which penalises its skew part; a Reissner–Mindlin "
            "director shell (fenicsx_ref) leaves it free. On this narrow, thick strip (w/h = 2.5) that "
            "stiffens the twist (README: J = 7.62e-5 on 20×6 vs 6.94e-5 with the skew part symmetrised). "
            "The probe of this case is the axial end shortening, a second-order (Wagner) effect of the "
            "twist, so it inherits the stiffness difference amplified." + _torsion_thin(data))
    # stress: silent wrong answers and the largest single steps
    st = data["stress"]["tests"]
    wrong = [t for t in st if t["outcome"] == "WRONG"]
    if wrong:
        groups = {}
        for t in wrong:
            groups.setdefault((t["group"], t["model"]), []).append(t["what"])
        out.append("* **silent wrong answers in the stress runs**: " + "; ".join(
            f"{m}, {g}: {', '.join(w[:4])}{' …' if len(w) > 4 else ''}" for (g, m), w in groups.items())
            + ".")
        if any("full" in t["what"] for t in wrong):
            out.append("  Full integration at L/h = 1e4 is membrane/shear locking: Newton converges to a "
                       "far too stiff answer and nothing in the run says so.")
        if any(t["group"] == "largest step: torsion" for t in wrong):
            out.append("  A one-step prescribed rotation by a multiple of 2π is the identity frame, so a "
                       "solver that only sees frames (core_se3) solves the unloaded problem: such rotations "
                       "must be stepped (the stepped path is right; core_se3 cannot tell from the end state).")
        if any("seed" in t["what"] for t in wrong):
            out.append("  The seed element 'converges' (its residual test passes) to a wrong state where "
                       "it does not fail outright: its residual is not the derivative of an energy "
                       "consistent with its tangent (docs/ELEMENTS.md).")
    for group in ("largest step: rollup", "largest step: torsion"):
        for model in ("core_se3", "fenicsx_ref"):
            ok = [t["what"] for t in st if t["group"] == group and t["model"] == model and t["outcome"] == "pass"]
            bad = [t for t in st if t["group"] == group and t["model"] == model and t["outcome"] == "fail"]
            if ok or bad:
                out.append(f"* {group}, {model}: largest single step that passes: "
                           f"{ok[-1] if ok else 'none'}"
                           + (f"; first reported failure: {bad[0]['what']} ({bad[0]['status'][:120]})" if bad else ""))
    lk = data["locking"]["runs"]
    slow = sorted((r for r in lk if r["variant"] == "default" and r["L_over_h"] == 1e4),
                  key=lambda r: -r["wall"])[:1]
    if slow:
        r = slow[0]
        fx = [q for q in lk if q["variant"] == "psri" and q["L_over_h"] == 1e4 and q["case"] == r["case"]]
        fxt = max((q["wall"] - q.get("jit", 0.0) for q in fx), default=float("nan"))
        thick = [q for q in lk if q["variant"] == "default" and q["L_over_h"] == 100 and q["case"] == r["case"]
                 and tuple(q["mesh"]) == tuple(r["mesh"])]
        a, a0 = r.get("attempts"), (thick[0].get("attempts") if thick else None)
        if a and a0:
            why = (f"{a} Newton solves against {a0} at L/h = 100: the time goes into cut-backs of steps that "
                   "do not converge on the very thin shell" if a > 2 * a0 else
                   f"{a} Newton solves against {a0} at L/h = 100: thinness costs no extra iterations")
        else:
            why = f"{a} Newton solves" if a else "Newton solves not recorded"
        out.append(f"* **cost of thinness in core_se3**: its slowest L/h = 1e4 run ({r['case']} "
                   f"{r['mesh'][0]}×{r['mesh'][1]}) took {r['wall']:.2g} s ({why}); fenicsx_ref PSRI at most "
                   f"{fxt:.2g} s on that case.")
    for r in ag:
        lv = r["levels"][-1]
        d = lv.get("dist_core_psri")
        if r["case"] != "torsion" and d is not None and d >= 0.01:
            out.append(f"* {r['label']} at ν = {r['nu']:g}: {pct(d)} between the models on the fine grids "
                       f"(coarse {pct(r['levels'][0].get('dist_core_psri'))}).")
    return out


def jit_total(data):
    """Seconds of fenicsx_ref JIT compilation recorded by the studies (0 on a warm cache)."""
    t = 0.0
    for row in data["agreement"]["cases"]:
        for lv in row["levels"]:
            t += sum(r["timings"].get("jit", 0.0) for r in lv["records"].values())
    t += sum(r.get("jit", 0.0) for r in data["locking"]["runs"])
    t += sum(r.get("jit", 0.0) for r in data["pareto"]["runs"])
    return t


def _machines(data, walls):
    """Per study: the CPU and load its times were measured with ('not recorded' for data
    written before the studies stored it: then the CPU row above need not be theirs)."""
    out = []
    for k in walls:
        m = data[k].get("machine")
        out.append(f"{k}: not recorded" if not m else
                   f"{k}: {m['cpu']} ({m['cores']} cores), {m['load_start']:.1f} / {m['load_end']:.1f}")
    return "; ".join(out)


def render(data, walls, total, env0, env1, fx_ok, fx_why, figs, quick, reuse=False):
    L = []
    L.append("# core_se3 against fenicsx_ref: agreement, locking, cost of accuracy, stability\n")
    if reuse:
        L.append(f"Studies run by `python -m comparison report` in {total / 60:.1f} min (sum of the studies' "
                 f"wall times); this page rendered again from their data with `--reuse` (commit "
                 f"{env0['commit']}). The raw data is in `reports/data/*.json`.\n")
    else:
        L.append(f"Generated by `python -m comparison report`{' --quick' if quick else ''} in {total / 60:.1f} min "
                 f"(commit {env0['commit']}). All numbers below were computed by that run; the raw data is in "
                 "`reports/data/*.json`.\n")
    if not fx_ok:
        L.append(f"**fenicsx_ref was not available** ({fx_why}): its columns are empty / 'not available'.\n")
    L.append("## Machine and libraries\n")
    L.append(markdown_table(["item", "value"], [
        ["CPU " + ("when rendered" if reuse else "of this run"),
         f"{env0['cpu']} ({env0['cores']} logical cores, shared with other jobs)"],
        ["load average " + ("when rendered (not during the studies)" if reuse else "at start / end"),
         f"{env0['load'][0]:.2f} / {env1['load'][0]:.2f}"],
        ["platform", env0["platform"]], ["Python", env0["python"]], ["NumPy", env0["numpy"]],
        ["SciPy", env0["scipy"]], ["DOLFINx", env0["dolfinx"]], ["petsc4py", env0["petsc4py"]],
        ["matplotlib", env0["matplotlib"]],
        ["fenicsx_ref JIT compile (inside the study times, reported apart)",
         f"{jit_total(data):.0f} s (cache: FENICSX_REF_JIT_CACHE = "
         f"{os.environ.get('FENICSX_REF_JIT_CACHE', '~/.cache/fenicsx_ref/jit')})"],
        ["commit at the start of each study", ", ".join(f"{k} {data[k].get('commit', '?')}" for k in walls)],
        ["machine of each study's times (CPU, load average at start / end)", _machines(data, walls)],
        ["study wall times", ", ".join(f"{k} {v / 60:.1f} min" if v else f"{k} (?)"
                                       for k, v in walls.items())]]))
    L.append("\n## Summary\n")
    L.append(markdown_table(["question", "measured answer"], summary_rows(data)))
    f = _findings(data)
    if f:
        L.append("\n### Findings\n")
        L.extend(f)
    L.append("\n## 1. Agreement at rotations up to π/2 (`python -m comparison agreement`)\n")
    L.append(agreement.__doc__.split("\n", 1)[1].strip() + "\n")
    L.append(f"![agreement]({figs['agreement']})\n")
    L.append(agreement.markdown(data["agreement"])[0])
    L.append("\n## 2. Locking (`python -m comparison locking`)\n")
    L.append(locking.__doc__.split("\n", 1)[1].strip() + "\n")
    L.append(f"![locking]({figs['locking']})\n")
    L.append(locking.markdown(data["locking"]))
    L.append("\n## 3. Run time against error (`python -m comparison pareto`)\n")
    L.append(pareto.__doc__.split("\n", 1)[1].strip() + "\n")
    L.append(f"![pareto]({figs['pareto']})\n")
    L.append(pareto.markdown(data["pareto"]))
    L.append("\n## 4. Stress runs (`python -m comparison stress`)\n")
    L.append(stress.__doc__.split("\n", 1)[1].strip() + "\n")
    L.append(stress.markdown(data["stress"]))
    L.append("")
    return "\n".join(L)
