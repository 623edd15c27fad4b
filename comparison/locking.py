"""Study 2 -- locking: normalised tip error against the thickness ratio L/h = 10 ... 1e4.

Loads are scaled with the bending stiffness so that the nondimensional load stays fixed:
* cantilever-shear: P L²/EI = 2 (4 steps).  Reference: the shear-deformable rod with k_s = 1 at
  L/h = 10 and 100 (``1_cantilever_tip_force_reissner_ks1_L_over_h_*``), the Kirchhoff elastica
  (``1_cantilever_tip_force_kirchhoff``) thinner;
* rollup: M = (1/4) 2π EI/L (2 steps; tip rotation π/2): the exact circle of curvature M/EI;
* arch-follower: tangential follower force to P = 900 N with EI = 360 N m² held fixed (E scaled
  by 1/h³; tip rotation ≈ π/2; 5 steps), L = πR the arc length.  Reference: the Kirchhoff
  curve ``4_arch_halfcircle_follower_tangential_plus`` (no shear-deformable entry for the
  other sections: at L/h = 10 its floor is the rod-model difference, common to both models);
* torsion: a small end twist α = 1e-3 h/L (one step) of the w = 0.25, L = 1 strip, so that the
  Wagner stiffening (E/G) w⁴ τ²/(120 h²) stays 1e-10 of the linear torque at every L/h (at a fixed
  α = 0.01 it is 85 % at L/h = 1e4: the response would not be linear);
  J = T L/(G angle) against the Reissner-Mindlin strip constant J_M(w, h) (``metrics.mindlin_strip_J``,
  equal to ``5_strip_torsion_seed_strip`` at h = 0.1).  J/J_M is reported: the clamp and the rigid
  end edge restrain warping (≈ +8 % in fenicsx_ref at h = 0.1), core_se3's Cosserat law adds its
  skew-curvature stiffness; locking shows as J/J_M growing with L/h on a fixed mesh.

Every variant runs on a sequence of meshes; the core_se3 mesh has 2nx elements along the
fenicsx_ref Q2 mesh's nx (the same nodes along the length), and 2ny across it for torsion; the
ν = 0 strips and the arch are uniform across the width, so there core_se3 uses ny = 1.  The seed element runs on one mesh, with the Newton cap
``models.SEED_CAP``; its failures are listed as such.
"""
from __future__ import annotations

from math import pi

import numpy as np

from . import common
from .metrics import circle_tip, mindlin_strip_J, path_distance
from .models import run_core, run_fenicsx
from .tables import fmt, markdown_table, pct

__all__ = ["RATIOS", "SETUPS", "run", "markdown", "plot"]

RATIOS = (10.0, 1e2, 1e3, 1e4)
VARIANTS = (("core_se3", "default"), ("fenicsx_ref", "psri"), ("fenicsx_ref", "full"),
            ("core_se3", "seed"))


def _cantilever(r):
    L, w, E = 10.0, 1.0, 1.2e6
    h = L / r
    EI = E * w * h ** 3 / 12
    return dict(h=h, load_max=2.0 * EI / L ** 2)


def _rollup(r):
    return dict(h=10.0 / r, k=0.25)


def _arch(r):
    R, w = 0.5, 4.0825e-3
    h = pi * R / r
    return dict(h=h, E=360.0 * 12 / (w * h ** 3), load_max=900.0)


def _torsion(r):
    # linear: the Wagner term / Saint-Venant term ~ (E/G) w^4 tau^2 / (120 h^2) is held at 1e-10
    h = 1.0 / r
    return dict(h=h, angle=1e-3 * h)


# name: (overrides(L/h), steps, fenicsx meshes, seed fenicsx-equivalent mesh index)
SETUPS = {
    "cantilever-shear": (_cantilever, 4, [(4, 1), (8, 1), (16, 1)]),
    "rollup": (_rollup, 2, [(2, 1), (4, 1), (8, 1)]),
    "arch-follower": (_arch, 5, [(10, 1), (20, 1), (40, 1)]),
    "torsion": (_torsion, 1, [(5, 2), (10, 3), (20, 6)]),
}
SEED_MESH = 0


def _error(name, r, ov, steps, rec):
    """Normalised error of a record (None if the path is incomplete); torsion: J/J_M."""
    lams = [k / steps for k in range(1, steps + 1)]
    if len(rec["u"]) != len(lams):
        return None
    from core_se3.catalogue import get_case
    case = get_case(name)
    if name == "torsion":
        p = dict(case.params, **ov)
        G = p["E"] / (2 * (1 + p["nu"]))
        J = abs(rec["torque"][-1]) * p["L"] / (G * p["angle"])
        return J / mindlin_strip_J(p["width"], p["h"])
    if name == "rollup":
        u, v, _ = circle_tip(10.0, np.asarray(lams) * 0.25 * 2 * pi / 10.0)
        ref = np.column_stack([u, v])
    elif name == "cantilever-shear":
        entry = {10.0: "1_cantilever_tip_force_reissner_ks1_L_over_h_10",
                 100.0: "1_cantilever_tip_force_reissner_ks1_L_over_h_100"}.get(r)
        ref = common.reference_path(name, ov, lams, entry=entry)
    else:
        ref = common.reference_path(name, ov, lams, entry="4_arch_halfcircle_follower_tangential_plus")
    scale = float(np.linalg.norm(ref, axis=1).max())
    return path_distance(common.planar(case, rec["u"]), ref, scale)[0]


def reference_name(name, r):
    if name == "cantilever-shear":
        return {10.0: "Reissner rod k_s = 1, L/h = 10", 100.0: "Reissner rod k_s = 1, L/h = 100"}.get(
            r, "Kirchhoff elastica")
    return {"rollup": "exact circle", "arch-follower": "Kirchhoff arch (EI = 360)",
            "torsion": "J_M(w, h) (ratio)"}[name]


def run(quick=False, seed=True):
    out = []
    names = ["cantilever-shear", "torsion"] if quick else list(SETUPS)
    ratios = (10.0, 1e4) if quick else RATIOS
    for name in names:
        ovf, steps, meshes = SETUPS[name]
        for r in ratios:
            ov = ovf(r)
            for model, variant in VARIANTS:
                if variant == "seed" and not seed:
                    continue
                ms = [meshes[SEED_MESH]] if variant == "seed" else meshes
                for m in ms:
                    mesh = m if model != "core_se3" else \
                        ((2 * m[0], 2 * m[1]) if name == "torsion" else (2 * m[0], 1))
                    common.progress(f"locking {name} L/h={r:g} {model}/{variant} {mesh}")
                    if model == "core_se3":
                        rec = run_core(name, mesh, ov, steps, element=variant)
                    else:
                        rec = run_fenicsx(name, mesh, ov, steps, integration=variant)
                    out.append(dict(case=name, L_over_h=r, model=model, variant=variant,
                                    mesh=list(mesh), grid=list(m), n_dofs=rec["n_dofs"],
                                    status=rec["status"], warning=rec.get("warning"), wall=rec["wall"],
                                    iterations=rec["iterations"], attempts=rec.get("attempts"),
                                    jit=rec["timings"]["jit"],
                                    error=_error(name, r, ov, steps, rec) if rec["status"] == "ok" else None))
    return dict(runs=out)


def _label(model, variant):
    return {"default": "core default", "seed": "core seed", "psri": "fx PSRI", "full": "fx full"}[variant]


def markdown(data):
    md = []
    runs = data["runs"]
    for name in dict.fromkeys(r["case"] for r in runs):
        sub = [r for r in runs if r["case"] == name]
        ratios = sorted(set(r["L_over_h"] for r in sub))
        header = ["variant", "mesh (Q1 / Q2)"] + [f"L/h = {r:g}" for r in ratios]
        rows = []
        for model, variant in VARIANTS:
            grids = sorted({tuple(r["grid"]) for r in sub if r["variant"] == variant})
            for g in grids:
                cells = [_label(model, variant), "×".join(map(str, next(
                    r["mesh"] for r in sub if r["variant"] == variant and tuple(r["grid"]) == g)))]
                for rr in ratios:
                    hit = [r for r in sub if r["variant"] == variant and tuple(r["grid"]) == g
                           and r["L_over_h"] == rr]
                    if not hit:
                        cells.append("–")
                    elif hit[0]["status"] != "ok":
                        cells.append("fails")
                    else:
                        cells.append(fmt(hit[0]["error"], 4) if name == "torsion" else pct(hit[0]["error"]))
                rows.append(cells)
        what = "J / J_M(w, h)" if name == "torsion" else "max tip error / max tip displacement"
        refs = "; ".join(f"L/h = {r:g}: {reference_name(name, r)}" for r in ratios) \
            if name == "cantilever-shear" else reference_name(name, ratios[0])
        md.append(f"\n**{name}** ({what}; reference: {refs})\n")
        md.append(markdown_table(header, rows))
        fails = [r for r in sub if r["status"] != "ok"]
        if fails:
            md.append("\nFailures: " + "; ".join(
                f"{_label(r['model'], r['variant'])} {r['mesh'][0]}×{r['mesh'][1]} at L/h = {r['L_over_h']:g}: "
                f"{r['status'].replace('failed: ', '')[:110]}" for r in fails[:6])
                + (f"; … ({len(fails)} in all)" if len(fails) > 6 else ""))
    # cost of thinness: wall time (and Newton attempts) on each variant's finest grid
    rows = []
    ratios = sorted(set(r["L_over_h"] for r in runs))
    for name in dict.fromkeys(r["case"] for r in runs):
        sub = [r for r in runs if r["case"] == name]
        for model, variant in VARIANTS[:3]:
            grids = sorted({tuple(r["grid"]) for r in sub if r["variant"] == variant})
            if not grids:
                continue
            cells = [name, _label(model, variant)]
            for rr in ratios:
                hit = [r for r in sub if r["variant"] == variant and tuple(r["grid"]) == grids[-1]
                       and r["L_over_h"] == rr]
                cells.append("–" if not hit else f"{hit[0]['wall'] - hit[0].get('jit', 0.0):.2g} s"
                             + (f" ({hit[0]['attempts']})" if hit[0].get("attempts") else ""))
            rows.append(cells)
    md.append("\nWall time without JIT on the finest grid (Newton solves including cut-back failures in "
              "brackets), measured in the same run:\n")
    md.append(markdown_table(["case", "variant"] + [f"L/h = {r:g}" for r in ratios], rows))
    return "\n".join(md)


def plot(data, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    runs = data["runs"]
    names = list(dict.fromkeys(r["case"] for r in runs))
    fig, axes = plt.subplots(1, len(names), figsize=(3.0 * len(names), 2.9), dpi=80, squeeze=False)
    for ax, name in zip(axes[0], names):
        sub = [r for r in runs if r["case"] == name]
        grids = sorted({tuple(r["grid"]) for r in sub})
        for j, (model, variant) in enumerate(VARIANTS):
            for g, ls in ((grids[SEED_MESH if len(grids) > 1 else 0], "-"), (grids[-1], ":")):
                pts = sorted((r["L_over_h"], r["error"]) for r in sub if r["variant"] == variant
                             and tuple(r["grid"]) == g and r["error"] is not None)
                if not pts:
                    continue
                x, y = zip(*pts)
                y = np.abs(np.asarray(y) - 1.0) if name == "torsion" else np.asarray(y)
                ax.loglog(x, np.maximum(y, 1e-9), ls, marker="os^v"[j], ms=3, color=f"C{j}",
                          label=f"{_label(model, variant)} {g[0]}×{g[1]}" if ls == "-" else None)
        ax.set_title(name, fontsize=8)
        ax.set_xlabel("L/h", fontsize=7)
        ax.set_ylabel("|J/J_M − 1|" if name == "torsion" else "tip error", fontsize=7)
        ax.tick_params(labelsize=6)
    axes[0][0].legend(fontsize=5)
    fig.text(0.01, 0.01, "solid: coarse grid (Q2 mesh shown), dotted: finest grid", fontsize=6)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
