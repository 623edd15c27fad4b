"""Why thin doubly curved coarse meshes lock unless the frames are the meridians (issue 30, research).

    .venv/bin/python benchmarks/curved_locking.py      -> benchmarks/results/curved_locking.md

Follows ``benchmarks/curved_frames.py`` (the measurements of the locking) and asks what the
meridian frames of a lat-long mesh have that turned frames lack.  Everything is the linear
analysis of the NumPy element; the element's frames are turned through ``Mesh.gauge_angles``
(the user's frames, the supports and the load stay the meridian ones), so only the element sees
the turn.

1. Hypotheses on the frames.  The quarter hemisphere (R 10, 18 deg hole) on the meridian frames
   turned by: a constant (exactly invariant), +b / -b on the two node colours (zero corner
   defects), A sin 2 theta on every node (a function of the longitude only: every meridian edge
   keeps a zero turn about the normal, H2), A lat (a function of the latitude only), A sin 2
   theta on the interior nodes (``curved_frames``' 'turned').  Counted: the bending-order
   eigenvalues of the free-dof stiffness (falling > 300-fold from h = 1e-3 to 1e-4); measured: the
   deflection at R/h 1e4 over the meridian frames'.  And the edge helices: on a sphere every edge
   geodesic exp(t log(g_a^-1 g_b)) is a circular arc (zero pitch) tangent to both nodal planes
   (no normal component of its translation), whatever the turns, so the edge curves lie on the
   sphere in every case and differ only in their geodesic curvature.
2. The mechanism.  The same counts and deflections with each of the element's three reference
   corrections switched off (``membrane_drilling``, ``membrane_shear``'s retention,
   ``membrane_enhanced``; 'none': all three), and one element of a sphere per variant.  The
   membrane-drilling correction carries most of the assembled frame dependence (it adds the
   element-constant membrane strain -Ebar, Ebar = sum_k Ek d_k, d_k the edge twists' drilling
   components: three more constraints per element on an inextensional mode, which one element
   meets with its own drilling rotations and an assembly does not); what is left (alternating
   turns, a file's projected hint, one element's lost modes) is the tying itself.
3. The cubed-sphere cap (free edges) and the whole hemisphere with a file's projected hint, with
   and without the correction.
4. Changes of the element (prototypes, monkey-patched here, not in the package): 'drilling
   share', the correction applied to the drilling columns' share of d_k only (D S pinv(G0) z,
   identical on flat elements) -- worse; 'drilling x beta', the correction kept with the factor
   beta that ``membrane_shear`` keeps of the tied shear's variation (P + beta dP: the same
   physics, bending rotations times the element's curvature at membrane order; beta = 1 on flat
   elements, so the patch tests and Cook's membrane are unchanged) -- removes most of the
   locking of smoothly turned frames and moved nodes, not that of alternating turns or a
   file's projected hint, and makes the coarsest free-edge caps too flexible at R/h 1e5.
"""
from __future__ import annotations

import datetime
import os
import warnings
from pathlib import Path

import numpy as np

os.environ.setdefault("CORE_SE3_BACKEND", "numpy")

import curved_frames as cf                                              # noqa: E402
import core_se3.fem.element_default as ED                               # noqa: E402
import core_se3.fem.membrane_drilling as MD                             # noqa: E402
from core_se3 import Material, Problem, lie, mesh                       # noqa: E402
from core_se3.catalogue import shell_course as sc                       # noqa: E402
from core_se3.fem.element_default import DefaultElement, edge_twists    # noqa: E402
from core_se3.mesh.gauge import turned_about_normal                     # noqa: E402

OUT = Path(__file__).parent / "results" / "curved_locking.md"
R = 10.0
ORIGINAL = dict(drilling_correction=ED.drilling_correction, tying_correction=ED.tying_correction,
                shear_retention=ED.shear_retention, condensed_stiffness=ED.condensed_stiffness,
                shear_tying=ED.shear_tying)
_EK = {}                           # the drilling corrections Ek of the elements built, by their z0


# ---------------------------------------------------------------- switches of the element
def _no_drilling(P, z0, G0):
    return np.zeros((len(z0), 3, 3, 4))


def _drill_share(P, z0, Ek):
    """dP of the prototype (section 4): Ek applied to d_k^drill = D S pinv(G0) z, the drilling
    columns' share of the edge twists' drilling components (G0 of the last ``_keep_G0`` call)."""
    G0 = _keep_G0.G0
    A = MD._bases(P, z0)[0]
    S = np.linalg.pinv(G0)[:, 5::6, :]                                 # nodal drilling rotations (m, 4, 24)
    d = np.einsum("mkt,mtz->mkz", G0[:, 5::6, 5::6], S)                # d^drill (m, 4, 24)
    corr = -np.einsum("mijk,mqaj->mqaik", Ek, A)                       # (m, q, 2, 3, 4)
    dP = np.zeros((len(z0), P.shape[0], 12, 24))
    dP[:, :, 0:3] = np.einsum("mqik,mkz->mqiz", corr[:, :, 0], d)
    dP[:, :, 6:9] = np.einsum("mqik,mkz->mqiz", corr[:, :, 1], d)
    return dP


def _keep_G0(P, z0, G0):
    _keep_G0.G0 = G0
    return ORIGINAL["drilling_correction"](P, z0, G0)


def _stash_Ek(P, z0, G0):
    Ek = ORIGINAL["drilling_correction"](P, z0, G0)
    _EK[hash(np.ascontiguousarray(z0).tobytes())] = Ek
    return Ek


def _shear_tying_beta(Pm, P, z0, beta, gauss=None):
    """The tying with the drilling correction kept with the shear's factor beta, P + beta dP
    (the prototype 'drilling x beta', section 4): (1 - beta) dP taken off before the shear's."""
    Ek = _EK.get(hash(np.ascontiguousarray(z0).tobytes()))
    if Ek is not None and Ek.any():
        off = (1.0 - beta)[:, None, None, None]
        Pm = Pm - off * ORIGINAL["tying_correction"](P, z0, Ek)
        if gauss is not None:
            gauss = (gauss[0] - off * ORIGINAL["tying_correction"](gauss[1], z0, Ek), gauss[1])
    return ORIGINAL["shear_tying"](Pm, P, z0, beta, gauss)


def element_variant(name):
    """Set the element's reference corrections: 'default', 'no drilling', 'no shear retention',
    'no enhanced', 'none' (all three off), 'drilling share', 'drilling x beta' (section 4)."""
    for k, v in ORIGINAL.items():
        setattr(ED, k, v)
    if name in ("no drilling", "none"):
        ED.drilling_correction = _no_drilling
    if name in ("no shear retention", "none"):
        ED.shear_retention = lambda z0, zeta0, D, j0: np.ones(len(z0))
    if name in ("no enhanced", "none"):
        ED.condensed_stiffness = lambda Db, Pm, Gam, Dj: Db
    if name == "drilling share":
        ED.drilling_correction, ED.tying_correction = _keep_G0, _drill_share
    if name == "drilling x beta":
        ED.drilling_correction, ED.shear_tying = _stash_Ek, _shear_tying_beta


# ---------------------------------------------------------------- the quarter hemisphere
def lat(m):
    return np.arcsin(np.clip(m.X[:, 2] / R, -1.0, 1.0))


def lon(m):
    return np.arctan2(m.X[:, 1], m.X[:, 0])


PATTERNS = {
    "meridian": None,
    "constant 0.1": lambda m: 0.1 + 0.0 * lat(m),
    "alternating +-0.03": lambda m: 0.03 * cf.two_colouring(m),
    "0.1 sin 2 theta, every node (H2 holds)": lambda m: 0.1 * np.sin(2.0 * lon(m)),
    "0.1 lat, every node": lambda m: 0.1 * lat(m),
    "0.1 sin 2 theta, interior nodes": lambda m: 0.1 * np.sin(2.0 * lon(m)) * cf._interior(m),
}


def quarter_mesh(n, turns=None, transform=None):
    """The quarter hemisphere n x n (``transform`` of curved_frames applied), the element's frames
    turned by ``turns(mesh)`` through ``Mesh.gauge_angles`` (the user's frames kept)."""
    m = mesh.hemisphere_quarter(R, 18.0, n, n)
    if transform is not None:
        m = transform(m)
    if turns is not None:
        m = mesh.Mesh(m.g0, m.quads, edges=m.edges)
        m.gauge_angles = turns(m)
    return m


def _free(m):
    fixed = np.zeros((m.n_nodes, 6), bool)
    for s in ("y0", "y1"):
        fixed[np.asarray(m.node_set(s)), [[1], [3], [5]]] = True
    fixed[np.asarray(m.node_set("y0"))[-1], 0] = True                 # as pinched_hemisphere
    return ~fixed.ravel()


def stiffness(m, h):
    """The assembled linear stiffness on the pinched quarter's free dofs (user's frames)."""
    B = DefaultElement(m, Material(1.0, 0.3, h)).evaluate(m.g0).element_blocks     # (e, 4, 4, 6, 6)
    n = m.n_nodes
    K = np.zeros((n, n, 6, 6))
    for a in range(4):
        for b in range(4):
            np.add.at(K, (m.quads[:, a], m.quads[:, b]), B[:, a, b])
    K = np.transpose(K, (0, 2, 1, 3))
    K = K.reshape(6 * n, 6 * n)
    free = _free(m)
    return K[np.ix_(free, free)]


def bending_count(m, h=1e-3):
    e1 = np.linalg.eigvalsh(stiffness(m, h))
    e2 = np.linalg.eigvalsh(stiffness(m, h / 10))
    return int((e1 / e2 > 300.0).sum())


def deflection(n, h, turns=None, transform=None):
    p, measure = sc.pinched_hemisphere(n, h=h, transform=lambda m: quarter_mesh(n, turns, transform))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return measure(p.solve_linear())


def helix_shape(m):
    """Largest |v . n| / |v| and |v . w| / (|v| |w|) over the edges (v, w the translation and rotation
    of log(g_a^-1 g_b) on the element's frames): the normal component and the pitch of the edge helices."""
    g = turned_about_normal(m.g0, m.gauge_angles)
    psi = lie.log(lie.relative(g[m.edge_nodes[:, 0]], g[m.edge_nodes[:, 1]]))
    v, w = psi[:, :3], psi[:, 3:]
    nv = np.linalg.norm(v, axis=1)
    return float(np.abs(v[:, 2] / nv).max()), float(np.abs(np.einsum("ei,ei->e", v, w) / nv / np.linalg.norm(w, axis=1)).max())


def hypothesis_rows(meshes=(3, 4, 5), h=1e-3):
    rows = []
    base = {n: deflection(n, h) for n in meshes}
    for name, turns in PATTERNS.items():
        counts = [bending_count(quarter_mesh(n, turns)) for n in meshes[:2]]
        ratios = [deflection(n, h, turns) / base[n] for n in meshes]
        shape = helix_shape(quarter_mesh(4, turns))
        rows.append((name, counts, ratios, shape))
        print("hypothesis", rows[-1], flush=True)
    return rows


def ablation_rows(meshes=(3, 4), h=1e-3):
    """Bending-order counts and R/h 1e4 deflections (over the same variant's meridian value) with
    the element's corrections switched off one at a time."""
    rows = []
    pats = ["meridian", "alternating +-0.03", "0.1 sin 2 theta, every node (H2 holds)", "0.1 lat, every node"]
    for variant in ("default", "no drilling", "no shear retention", "no enhanced", "none"):
        element_variant(variant)
        counts = [[bending_count(quarter_mesh(n, PATTERNS[p])) for p in pats] for n in meshes]
        rows.append((variant, pats, counts))
        print("ablation", rows[-1][0], counts, flush=True)
    element_variant("default")
    return rows


def drilling_rows(meshes=(3, 4, 5), thicknesses=(1e-3, 1e-4),
                  variants=("default", "no drilling", "drilling share", "drilling x beta")):
    """Deflections: meridian over the default 16x16; the turned / moved over the variant's own meridian."""
    rows = []
    cols = [("alternating +-0.03", PATTERNS["alternating +-0.03"], None),
            ("0.1 sin 2 theta, every node", PATTERNS["0.1 sin 2 theta, every node (H2 holds)"], None),
            ("0.1 lat, every node", PATTERNS["0.1 lat, every node"], None),
            ("moved 0.1", None, "jitter")]
    for h in thicknesses:
        element_variant("default")
        ref = deflection(16, h)
        for n in meshes:
            for variant in variants:
                element_variant(variant)
                base = deflection(n, h)
                cells = [deflection(n, h, t, cf.jittered(0.1, n) if tr else None) / base for _, t, tr in cols]
                rows.append((R / h, n, variant, base / ref, cells))
                print("drilling", rows[-1], flush=True)
    element_variant("default")
    return rows, [c[0] for c in cols]


# ---------------------------------------------------------------- one element
ONE_PATTERNS = (("meridian", (0, 0, 0, 0)), ("alternating", (1, -1, 1, -1)), ("one node", (1, 0, 0, 0)),
                ("bottom vs top", (1, 1, -1, -1)), ("left vs right", (1, -1, -1, 1)))


def one_element_rows(turn=0.05):
    """One element of a sphere (curved_frames.sphere_element): its bending-order eigenvalues
    (curved_frames.bending_order_count) on the meridian frames turned by ``turn`` x the pattern,
    on a file's projected hint and on the cubed cap's corner element (4x4, half-angle 1), per
    element variant."""
    X, d3, merid = cf.sphere_element()
    g0 = mesh.frames_from(X, merid, d3)
    g, quads = cf.cubed_cap(4, half=1.0)
    frames = [turned_about_normal(g0, turn * np.array(p, float)) for _, p in ONE_PATTERNS]
    frames += [mesh.frames_from(X, np.tile([1.0, 0.3, 0.2], (4, 1)), d3), g[quads[0]]]
    names = [n for n, _ in ONE_PATTERNS] + ["projected hint", "cubed-cap corner"]
    rows = []
    for variant in ("default", "no drilling", "no enhanced", "none"):
        element_variant(variant)
        rows.append((variant, [cf.bending_order_count(f) for f in frames]))
        print("one element", rows[-1], flush=True)
    element_variant("default")
    return rows, names


# ---------------------------------------------------------------- the edge helices under a mode
def edge_rows(n=4, h=1e-4):
    """The meridian frames' bending-order modes of the element without the drilling correction
    (free-dof eigenvectors, 4x4), on other element frames: the largest translational variations
    of the edge twists over the largest rotational one, by component -- the stretch along the
    edge, its in-plane turn (the Allman-type term) and its normal (transverse shear) component,
    for the meridian edges (local bottom / top, the mesh's x) and the parallels (left / right)."""
    element_variant("no drilling")
    m0 = quarter_mesh(n)
    k = bending_count(m0)
    V = np.linalg.eigh(stiffness(m0, h))[1][:, :k]
    free = _free(m0)
    rows = []
    for name in ("meridian", "alternating +-0.03", "0.1 sin 2 theta, every node (H2 holds)"):
        m = quarter_mesh(n, PATTERNS[name])
        el = DefaultElement(m, Material(1.0, 0.3, h))
        G0 = MD.reference_G(m, edge_twists(el.frames(m.g0), m.edge_nodes))
        worst = np.zeros(6)
        for j in range(k):
            eta = np.zeros(6 * m.n_nodes)
            eta[free] = V[:, j]
            et = el.to_element_frames(eta.reshape(-1, 6))[m.quads].reshape(len(m.quads), 24)
            dz = np.einsum("mij,mj->mi", G0, et).reshape(-1, 4, 6)
            mer, par = np.abs(dz[:, :2, :3]), np.abs(dz[:, 2:, :3])
            got = [mer[..., 0].max(), par[..., 1].max(), mer[..., 1].max(), par[..., 0].max(),
                   mer[..., 2].max(), par[..., 2].max()] / np.abs(dz[..., 3:]).max()
            worst = np.maximum(worst, got)
        rows.append((name, k, worst))
        print("edges", rows[-1], flush=True)
    element_variant("default")
    return rows


# ---------------------------------------------------------------- the cap and the whole hemisphere
def cap(n, h):
    """The cubed-sphere cap (curved_frames.cubed_cap, half-angle 0.6), one side clamped, three free,
    a radial unit load at the middle of the opposite side: its deflection (``cap_solve`` on the
    generator's frames)."""
    return cf.cap_solve(mesh.Mesh(*cf.cubed_cap(n)), n, h)


def cap_rows(meshes=(2, 4, 8, 16, 32), thicknesses=(1e-2, 1e-3, 1e-4),
             variants=("default", "no drilling", "drilling x beta")):
    rows = []
    for h in thicknesses:
        element_variant("default")
        ref = cap(meshes[-1], h)
        for variant in variants:
            element_variant(variant)
            rows.append((R / h, variant, [cap(n, h) / ref for n in meshes]))
            print("cap", rows[-1], flush=True)
    element_variant("default")
    return rows, meshes


def whole_rows(meshes=(4, 8, 16), thicknesses=(0.04, 1e-3), variants=("default", "no drilling", "drilling x beta")):
    rows = []
    for h in thicknesses:
        for variant in variants:
            element_variant(variant)
            for n in meshes:
                base, _ = cf.whole(n, h)
                hint, _ = cf.whole(n, h, hint=(1.0, 0.3, 0.2))
                rows.append((R / h, variant, n, base, hint / base))
                print("whole", rows[-1], flush=True)
    element_variant("default")
    return rows


def beta_rows(meshes=(3, 4, 5, 8, 16), thicknesses=(1.0, 0.04, 1e-3, 1e-4)):
    """The quarter hemisphere, default element against 'drilling x beta': the meridian frames over
    the default element's 16x16, and over the same element's meridian value: interior nodes moved
    by 0.1 / 0.3 of the spacing, interior frames turned by 0.3 sin 2 theta (curved_frames)."""
    rows = []
    for h in thicknesses:
        element_variant("default")
        ref = deflection(16, h)
        for n in meshes:
            for variant in ("default", "drilling x beta"):
                element_variant(variant)
                base = deflection(n, h)
                cells = [deflection(n, h, transform=t) / base
                         for t in (cf.jittered(0.1, n), cf.jittered(0.3, n), cf.turned_smoothly(0.3))]
                rows.append((R / h, n, variant, base / ref, cells))
                print("beta", rows[-1], flush=True)
    element_variant("default")
    return rows


# ---------------------------------------------------------------- report
def report(hyp, abl, drill, one, edges, caps, whole, beta):
    lines = [
        "# Why thin doubly curved coarse meshes lock: the frames and the membrane-drilling correction (issue 30)", "",
        f"`python benchmarks/curved_locking.py` on {datetime.datetime.now().isoformat(timespec='seconds')} "
        "(linear analysis, NumPy backend; follows `benchmarks/results/curved_frames.md`). The pinched quarter "
        "hemisphere (R 10, 18 deg hole, `shell_course.pinched_hemisphere`), the element's frames turned through "
        "`Mesh.gauge_angles` (the user's frames, supports and load the meridian ones). Bending-order: "
        "eigenvalues of the free-dof stiffness falling > 300-fold from h = 1e-3 to 1e-4.", "",
        "## 1. Which frames keep the inextensional modes (hypotheses H2 / H3)", "",
        "Deflection at R/h 1e4 over the meridian frames' on the same mesh. Helices: the largest normal component "
        "|v.n|/|v| and pitch |v.w|/(|v||w|) of the edge twists' log (4x4): zero means every edge geodesic is a "
        "circular arc on the sphere tangent to both nodal planes.", "",
        "| element frames: meridian turned by | bending-order 3x3 | 4x4 | deflection 3x3 | 4x4 | 5x5 "
        "| helix normal comp. | helix pitch |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
    lines += [f"| {name} | {c[0]} | {c[1]} | " + " | ".join(f"{r:.4f}" for r in rat) + f" | {s[0]:.0e} | {s[1]:.0e} |"
              for name, c, rat, s in hyp]
    lines += ["", "## 2. Ablation: the element's reference corrections switched off", "",
              "Bending-order eigenvalues of the assembled free-dof stiffness (3x3 / 4x4).", "",
              "| element | " + " | ".join(abl[0][1]) + " |", "|---|" + "---:|" * len(abl[0][1])]
    lines += [f"| {v} | " + " | ".join(f"{c3} / {c4}" for c3, c4 in zip(counts[0], counts[1])) + " |"
              for v, _, counts in abl]
    rows, cols = drill
    lines += ["", "Deflections: 'meridian' over the default element's 16x16; the others over the same element "
              "variant's meridian value on the same mesh. 'drilling share': the prototype of section 4.", "",
              "| R/h | mesh | element | meridian / 16x16 | " + " | ".join(cols) + " |",
              "|---:|---|---|---:|" + "---:|" * len(cols)]
    lines += [f"| {rh:g} | {n}x{n} | {v} | {b:.4f} | " + " | ".join(f"{c:.4f}" for c in cells) + " |"
              for rh, n, v, b, cells in rows]
    rows1, names = one
    lines += ["", "One element of a sphere (`curved_frames.sphere_element`, turns 0.05 x the pattern): its "
              "bending-order eigenvalues per element variant (8 on the meridian frames).", "",
              "| element | " + " | ".join(names) + " |", "|---|" + "---:|" * len(names)]
    lines += [f"| {v} | " + " | ".join(str(c) for c in counts) + " |" for v, counts in rows1]
    lines += ["", "What the tying sees of an inextensional motion: the meridian frames' bending-order modes of the "
              "element without the drilling correction (4x4), on the element frames of the row, their edge twists' "
              "translational variations over the largest rotational one (stretch, in-plane turn, normal component; "
              "meridian edges / parallels). The tied e11, e22 and transverse shear at the Gauss points are the "
              "stretches and normal components of opposite edges interpolated linearly.", "",
              "| frames | modes | stretch, meridians | stretch, parallels | in-plane, meridians | in-plane, parallels "
              "| normal, meridians | normal, parallels |", "|---|---:|" + "---:|" * 6]
    lines += [f"| {name} | {k} | " + " | ".join(f"{x:.1e}" for x in worst) + " |" for name, k, worst in edges]
    crow, cm = caps
    lines += ["", "## 3. Cubed-sphere cap (free edges) and the whole hemisphere", "",
              "Cap (half-angle 0.6, d1 along the grid, one side clamped, a radial load at the middle of the "
              "opposite free side): deflection over the default element's "
              f"{cm[-1]}x{cm[-1]}.", "",
              "| R/h | element | " + " | ".join(f"{n}x{n}" for n in cm) + " |", "|---:|---|" + "---:|" * len(cm)]
    lines += [f"| {rh:g} | {v} | " + " | ".join(f"{c:.4f}" for c in cells) + " |" for rh, v, cells in crow]
    lines += ["", "Whole hemisphere (hole clamped, equator free, four alternating loads): the meridian "
              "frames' deflection and a file's projected hint (1, 0.3, 0.2) over it.", "",
              "| R/h | element | mesh per quarter | meridian | hint / meridian |", "|---:|---|---|---:|---:|"]
    lines += [f"| {rh:g} | {v} | {n}x{n} | {b:.5g} | {r:.4f} |" for rh, v, n, b, r in whole]
    lines += ["", "## 4. The prototype 'drilling x beta' on the quarter hemisphere", "",
              "The membrane-drilling correction kept with the shear retention beta of `membrane_shear` "
              "(P + beta dP; beta = 1 on flat elements: the patch tests unchanged). Meridian: over the default "
              "element's 16x16 at the same thickness; moved / turned (`curved_frames.jittered`, `turned_smoothly`): "
              "over the same element's meridian value on the same mesh.", "",
              "| R/h | mesh | element | meridian / default 16x16 | moved 0.1 | moved 0.3 | turned 0.3 sin 2 theta |",
              "|---:|---|---|---:|---:|---:|---:|"]
    lines += [f"| {rh:g} | {n}x{n} | {v} | {b:.4f} | " + " | ".join(f"{c:.4f}" for c in cells) + " |"
              for rh, n, v, b, cells in beta]
    return "\n".join(lines) + "\n"


def main():
    hyp = hypothesis_rows()
    abl = ablation_rows()
    drill = drilling_rows()
    one = one_element_rows()
    edges = edge_rows()
    caps = cap_rows()
    whole = whole_rows()
    beta = beta_rows()
    OUT.write_text(report(hyp, abl, drill, one, edges, caps, whole, beta))
    print("wrote", OUT)


if __name__ == "__main__":
    main()
