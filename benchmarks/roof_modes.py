#!/usr/bin/env python3
"""Why coarse meshes of the thin Scordelis-Lo roof are too flexible (issue 30, item 2): the
mechanism, measured by linear analysis, and the candidate remedies, with OpenSees' ASDShellQ4
and ShellMITC4 on the same meshes and nodal loads where an OpenSeesPy venv is given.

* energy split (membrane normal / symmetric shear / skew / transverse shear / bending /
  drilling) of the linear solution at 2x2, 4x4 and 64x64 (R/h 1e4), and the tied shear's
  retention beta on the roof's elements; the roof with beta = 1 (the tying before
  ``fem/membrane_shear.py``) and beta = 0 (the full element mean);
* the null space of the tied membrane and transverse-shear strains at the Gauss points on the
  free dofs (the deformations resisted at bending order only): its dimension at n x n, with the
  drilling rotations held, and for the tying set of MITC4+ on these flat facets (edge stretches,
  edge transverse shears, the centre's symmetric in-plane shear); where the modes live; the
  h-scaling of the lowest eigenvalues of the 2x2 stiffness;
* candidates (linear, K = G^T Dbar G plus a penalty): the edges' rotation-stretch coupling of the
  helicoidal edge twist removed (``alpha 0``), a Hughes-Brezzi penalty (drilling rotation minus
  the in-plane rotation of the bilinear translations, its variation about the element mean, at
  membrane order G h), the variation of the bilinear facets' in-plane shear at membrane order.

    .venv/bin/python benchmarks/roof_modes.py [--opensees /path/to/ops-venv/bin/python]

Writes ``benchmarks/results/roof_modes.md``.
"""
from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import sys
import types
from pathlib import Path

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp
import scipy.sparse.linalg as spl

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from core_se3 import lie                                        # noqa: E402
from core_se3.catalogue import shell_course as sc               # noqa: E402
from core_se3.fem import element_default as ed                  # noqa: E402
from core_se3.fem.material import strain_operators              # noqa: E402
from core_se3.solvers.linear import linear_state                # noqa: E402
from obstacle_course import peer_solve                          # noqa: E402

MESHES = (2, 3, 4, 6, 8, 16)
RH = (1e2, 1e3, 1e4, 1e5)
GP = np.array([(-1, -1), (1, -1), (1, 1), (-1, 1)]) / np.sqrt(3.0)   # quad node order 0..3


# ------------------------------------------------------------------ linear operators --------
def edge_jacobian(p, alpha=1.0):
    """G (24 m, 6 n): the linearised element edge twists dz = G eta at the reference state,
    dpsi = L(psi) eta_b - L(-psi) eta_a per mesh edge, with the part of the translational rows
    that sees the difference of the end rotations, d = w_b - R_h^T w_a (zero on a straight
    edge: the helicoidal arc's length change with its turn), scaled by alpha."""
    m = p.mesh
    E = m.edge_nodes
    psi = ed.edge_twists(m.g0, E)
    Lp, Lm = lie.dexp_inv(psi, both=True)
    Rh = lie.exp(psi)[:, :3, :3]
    Jb, Ja = Lp[:, :3, 3:].copy(), -Lm[:, :3, 3:]
    C = (1.0 - alpha) * 0.5 * (Jb - Ja @ Rh)
    Lp[:, :3, 3:] = Jb - C
    Lm[:, :3, 3:] = -(Ja + C @ np.swapaxes(Rh, 1, 2))
    nE, n = len(E), m.n_nodes
    rows = np.broadcast_to(np.arange(6 * nE).reshape(nE, 6, 1), (nE, 6, 6))
    cols = lambda a: np.broadcast_to(6 * E[:, a, None, None] + np.arange(6), (nE, 6, 6))
    Psi = sp.csr_matrix((np.r_[Lp.ravel(), -Lm.ravel()], (np.r_[rows.ravel(), rows.ravel()],
                                                          np.r_[cols(1).ravel(), cols(0).ravel()])), (6 * nE, 6 * n))
    me = m.n_elements
    S = sp.csr_matrix((0.5 * np.repeat(m.elem_edge_sign.ravel(), 6),
                       (np.arange(24 * me), (6 * np.repeat(m.elem_edges.ravel(), 6) + np.tile(np.arange(6), 4 * me)))),
                      (24 * me, 6 * nE))
    return (S @ Psi).tocsr()


def stiffness(p, alpha=1.0):
    G = edge_jacobian(p, alpha)
    return (G.T @ sp.block_diag(list(p.element.Dbar), format="csr") @ G).tocsr()


def solve(p, K):
    """A Result-like object of K eta = f on the free dofs (the measures of ``shell_course``)."""
    f = p.external(p.mesh.g0, 1.0, tangent=False)[0].ravel()
    free = ~p.constraint_mask().ravel()
    eta = np.zeros(len(f))
    eta[free] = spl.spsolve(K[free][:, free].tocsc(), f[free])
    res = types.SimpleNamespace(final=types.SimpleNamespace(g=linear_state(p.mesh.g0, eta.reshape(-1, 6))),
                                steps=[types.SimpleNamespace(g=p.mesh.g0)])
    return res, eta.reshape(-1, 6)


def gauss_strains(p, dz):
    """The tied strains at the Gauss points of the edge-twist increments dz (m, 24, d) (d
    columns: dofs or states) per kind (m, q, k, d), weighted by sqrt(j0) (so that |.|^2 summed
    is the area integral), and A^ab (m, q, 2, 2)."""
    el = p.element
    Pm = el.tying()
    zeta0 = np.einsum("mqij,mj->mqi", Pm, el.z0)
    (Mm, Ms, Mb, Md), Ainv, j0 = strain_operators(zeta0[..., 0:3], zeta0[..., 6:9])
    de = np.einsum("mqij,mjd->mqid", Pm, dz) * np.sqrt(j0)[..., None, None]
    return {k: np.einsum("mqki,mqid->mqkd", M, de) for k, M in zip("msbd", (Mm, Ms, Mb, Md))}, Ainv


# ------------------------------------------------------------------ diagnosis ----------------
def energy_split(p, eta):
    """Fractions of the strain energy of eta by kind (the tied strains and the law's blocks)."""
    mat = p.material
    S, Ainv = gauss_strains(p, (edge_jacobian(p) @ eta.ravel()).reshape(-1, 24, 1))
    S = {k: v[..., 0] for k, v in S.items()}
    e = S["m"]
    H = (mat.nu * np.einsum("...ab,...cd->...abcd", Ainv, Ainv)
         + (1 - mat.nu) * np.einsum("...ac,...bd->...abcd", Ainv, Ainv)).reshape(Ainv.shape[:-2] + (4, 4))
    q = lambda x, D: 0.5 * np.einsum("mqi,mqij,mqj->", x, D, x)
    sym = e.copy()
    sym[..., 1] = sym[..., 2] = 0.5 * (e[..., 1] + e[..., 2])
    nrm = e * np.array([1, 0, 0, 1])
    out = {"membrane normal": q(nrm, mat.C * H), "symmetric shear": q(sym - nrm, mat.C * H),
           "skew": q(e - sym, mat.C * H),
           "transverse shear": q(S["s"], mat.shear_factor * mat.G * mat.h * Ainv), "bending": q(S["b"], mat.D * H),
           "drilling": q(S["d"], mat.drilling * mat.D * (1 - mat.nu) * Ainv)}
    tot = sum(out.values())
    return {k: v / tot for k, v in out.items()}


def _null(rows, cols):
    return sl.null_space(rows[:, cols], rcond=1e-10)


def mechanisms(n):
    """Null-space dimensions of the tied membrane + transverse-shear strains on the free dofs of
    the n x n roof: as tied, with the drilling rotations held, for the MITC4+ tying set (drilling
    held, flat-facet translations: the helicoidal coupling removed); and the largest translation
    of the modes per row of nodes (angle from the crown)."""
    p, _ = sc.scordelis_lo(n, h=25e-4)
    free = ~p.constraint_mask().ravel()
    drill = np.arange(free.size) % 6 == 5
    G = edge_jacobian(p)
    S, _ = gauss_strains(p, G.toarray().reshape(p.mesh.n_elements, 24, -1))
    rows = np.concatenate([S["m"].reshape(-1, free.size), S["s"].reshape(-1, free.size)])
    null = _null(rows, free)
    v = np.zeros((free.size, null.shape[1]))
    v[free] = null
    amp = np.sqrt((v.reshape(-1, 6, v.shape[1])[:, :3] ** 2).sum((1, 2)))
    X = p.mesh.X
    ang = np.round(np.degrees(np.arctan2(X[:, 0], X[:, 2])), 1)
    by_row = {float(a): float(amp[ang == a].max()) for a in np.unique(ang)}
    return dict(tied=null.shape[1], drilling_held=_null(rows, free & ~drill).shape[1],
                mitc4plus=_null(_mitc4plus_rows(p, edge_jacobian(p, alpha=0.0)), free & ~drill).shape[1], by_row=by_row,
                load=np.round(p.external(p.mesh.g0, 1.0, tangent=False)[0].ravel()[free] @ null, 1).tolist())


def _mitc4plus_rows(p, G):
    """Per element: the 4 edge stretches, the 4 edge transverse shears (normal to the element's
    centre plane) and the centre's symmetric in-plane shear, as rows on the dofs."""
    z0 = p.element.z0.reshape(-1, 4, 6)
    Gd = G.toarray().reshape(len(z0), 4, 6, -1)[:, :, :3]
    A1, A2 = 0.5 * (z0[:, 0, :3] + z0[:, 1, :3]), 0.5 * (z0[:, 2, :3] + z0[:, 3, :3])
    nc = np.cross(A1, A2)
    nc /= np.linalg.norm(nc, axis=1)[:, None]
    t = z0[..., :3] / np.linalg.norm(z0[..., :3], axis=-1)[..., None]
    stretch = np.einsum("mki,mkid->mkd", t, Gd)
    trans = np.einsum("mi,mkid->mkd", nc, Gd)
    shear = (np.einsum("mi,mid->md", A2, 0.5 * (Gd[:, 0] + Gd[:, 1])) + np.einsum("mi,mid->md", A1, 0.5 * (Gd[:, 2] + Gd[:, 3])))
    return np.concatenate([stretch.reshape(-1, Gd.shape[-1]), trans.reshape(-1, Gd.shape[-1]), shear])


def eigen_orders(n):
    """The lowest 6 eigenvalues' ratios K(h) / K(h / 10) of the free n x n roof stiffness
    (rotations scaled by the element size): 10 for membrane order, 1000 for bending order."""
    ev = []
    for rh in (1e3, 1e4):
        p, _ = sc.scordelis_lo(n, h=25.0 / rh)
        free = ~p.constraint_mask().ravel()
        s = np.tile(np.r_[np.ones(3), np.full(3, 25.0 / n)], p.mesh.n_nodes)[free]
        ev.append(np.linalg.eigh(stiffness(p).toarray()[np.ix_(free, free)] / np.outer(s, s)))
    (w3, V3), (w4, V4) = ev
    match = np.abs(V3.T @ V4).argmax(1)
    return np.round(w3[:6] / w4[match[:6]], 1).tolist()


@contextlib.contextmanager
def retention(beta):
    """The roof built with the tied shear's retention beta set to a constant (1: the tying
    before ``membrane_shear``; 0: the full element mean)."""
    orig = ed.shear_retention
    ed.shear_retention = lambda z0, *a: np.full(len(z0), float(beta))
    try:
        yield
    finally:
        ed.shear_retention = orig


# ------------------------------------------------------------------ candidates ---------------
def _bilinear(Xe, x, y):
    """At (x, y) of the quad Xe (4, 3): N (4,), dN/ds (4, 2) in the orthonormal tangent basis
    (t1 along x_,x), t1, t2, n and the area element."""
    N = 0.25 * np.array([(1 - x) * (1 - y), (1 + x) * (1 - y), (1 + x) * (1 + y), (1 - x) * (1 + y)])
    D = 0.25 * np.array([[-(1 - y), -(1 - x)], [1 - y, -(1 + x)], [1 + y, 1 + x], [-(1 + y), 1 - x]])
    a = Xe.T @ D
    n = np.cross(a[:, 0], a[:, 1])
    j = np.linalg.norm(n)
    n /= j
    t1 = a[:, 0] / np.linalg.norm(a[:, 0])
    t2 = np.cross(n, t1)
    return N, D @ np.linalg.inv(np.stack([t1, t2], 1).T @ a), t1, t2, n, j


def penalty(p, kind, weight=1.0):
    """weight G h times the area integral of the variation about its element mean of
    'hb': theta . n - omega(u) (omega the in-plane rotation of the bilinear translations) or
    'shear': the in-plane shear of the bilinear translations, at the 2x2 Gauss points."""
    m, mat = p.mesh, p.material
    R0, X = m.g0[:, :3, :3], m.X
    I, J, V = [], [], []
    for q in m.quads:
        rows, W = [], []
        for x, y in GP:
            N, dNs, t1, t2, n, j = _bilinear(X[q], x, y)
            r = np.zeros((4, 6))
            if kind == "hb":
                r[:, :3] = -0.5 * (np.outer(dNs[:, 0], t2) - np.outer(dNs[:, 1], t1))
                r[:, 3:] = np.outer(N, n)
            else:
                r[:, :3] = np.outer(dNs[:, 1], t1) + np.outer(dNs[:, 0], t2)
            rows.append(r)
            W.append(j)
        rows, W = np.array(rows), np.array(W)
        rows -= np.einsum("q,qkc->kc", W, rows) / W.sum()
        body = np.concatenate([np.einsum("qki,kij->qkj", rows[..., :3], R0[q]),
                               np.einsum("qki,kij->qkj", rows[..., 3:], R0[q])], -1).reshape(4, 24)
        dofs = (6 * q[:, None] + np.arange(6)).ravel()
        k = weight * mat.G * mat.h * np.einsum("q,qi,qj->ij", W, body, body)
        I.append(np.repeat(dofs, 24))
        J.append(np.tile(dofs, 24))
        V.append(k.ravel())
    return sp.csr_matrix((np.concatenate(V), (np.concatenate(I), np.concatenate(J))), (6 * m.n_nodes,) * 2)


def chord_tie(p, weight=1.0, edges=("x1",)):
    """weight E h times the linearised chord stretch of the mesh edges that run across a free
    edge's element row (one end on the free node set, the other not: the roof's circumferential
    edges of the last row; the hemisphere's meridional ones), as a spring k (t . du)^2 / 2,
    k = weight E h w / |dX| (w the edge's tributary width, the free edge's length over its
    elements): the membrane-order tie of the free-edge row's stretch to its chord that the
    free-edge mechanism breaks (docs/ELEMENTS.md)."""
    m, mat = p.mesh, p.material
    free = np.zeros(m.n_nodes, bool)
    for name in edges:
        free[m.node_set(name)] = True
    E = m.edge_nodes
    sel = free[E[:, 0]] != free[E[:, 1]]
    a, b = E[sel, 0], E[sel, 1]
    dX = m.X[b] - m.X[a]
    ln = np.linalg.norm(dX, axis=1)
    t = dX / ln[:, None]
    fs = np.flatnonzero(free)
    width = np.ptp(m.X[fs], axis=0).max() / max(len(fs) - 1, 1)       # the free edge's spacing
    k = weight * mat.E * mat.h * width / ln
    R0 = m.g0[:, :3, :3]
    ra, rb = np.einsum("ei,eij->ej", t, R0[a]), np.einsum("ei,eij->ej", t, R0[b])   # t . R0 u_body
    rows = np.repeat(np.arange(len(a)), 6)
    cols = np.concatenate([6 * a[:, None] + np.arange(3), 6 * b[:, None] + np.arange(3)], 1).ravel()
    vals = np.concatenate([-ra, rb], 1).ravel()
    B = sp.csr_matrix((vals, (rows, cols)), (len(a), 6 * m.n_nodes))
    return (B.T @ sp.diags(k) @ B).tocsr()


CANDIDATES = {
    "as kept": lambda p: stiffness(p),
    "helicoidal coupling removed (alpha 0)": lambda p: stiffness(p, alpha=0.0),
    "Hughes-Brezzi variation, G h": lambda p: stiffness(p) + penalty(p, "hb"),
    "Hughes-Brezzi variation, 0.01 G h": lambda p: stiffness(p) + penalty(p, "hb", 0.01),
    "facet in-plane shear variation, G h": lambda p: stiffness(p) + penalty(p, "shear"),
}


def sweep(build, R, result_of, conv):
    """{R/h: [ratio at each of MESHES]} of the linear results result_of(p) (candidate or peer),
    divided by conv[R/h]."""
    out = {}
    for rh in RH:
        out[rh] = []
        for n in MESHES:
            p, meas = build(n, h=R / rh)
            out[rh].append(meas(result_of(p)) / conv[rh])
    return out


def opensees_solve(python, p, elem):
    """A Result-like object of OpenSees' linear solution (``opensees_linear.py``)."""
    return peer_solve(python, "opensees_linear.py", p, elem)


# ------------------------------------------------------------------ report -------------------
def converged(build, R):
    return {rh: (lambda pm: pm[1](pm[0].solve_linear()))(build(64, h=R / rh)) for rh in RH}


def diagnosis(conv_roof):
    """The roof's beta, its deflection with beta as kept / 1 / 0, energy splits, mechanisms and
    eigenvalue orders (module docstring)."""
    d = {"beta": {}, "retention": {}, "split": {}, "mechanisms": {}, "orders": {}}
    for n in (2, 4, 64):
        p, meas = sc.scordelis_lo(n, h=25e-4)
        d["beta"][n] = float(p.element.shear_beta.min())
        d["split"][n] = energy_split(p, solve(p, stiffness(p))[1])
    for n in (2, 4):
        for rh in (1e3, 1e4, 1e5):
            row = []
            for beta in (None, 1.0, 0.0):
                with (retention(beta) if beta is not None else contextlib.nullcontext()):
                    p, meas = sc.scordelis_lo(n, h=25.0 / rh)
                    row.append(meas(p.solve_linear()) / conv_roof[rh])
            d["retention"][f"{n}x{n}, R/h {rh:g}"] = row
    for n in (2, 3, 4, 6):
        d["mechanisms"][n] = mechanisms(n)
    for n in (2, 4):
        d["orders"][n] = eigen_orders(n)
    return d


def write(doc):
    d = doc["diagnosis"]
    L = ["# The coarse thin roof's mechanism and the candidate remedies (issue 30, item 2)", "",
         f"`python benchmarks/roof_modes.py` on {doc['date']}; OpenSeesPy {doc['opensees'] or 'not run'}.", "",
         "## Diagnosis (Scordelis-Lo roof, linear)", "",
         "Tied-shear retention beta on the roof's elements at R/h 1e4: "
         + ", ".join(f"{n}x{n} {b:.2g}" for n, b in d["beta"].items()) + ".", "",
         "Free-edge deflection / the 64x64 value, beta as kept (membrane_shear) / 1 (the tying before it) / 0 (the full mean):", "",
         "| mesh, R/h | as kept | beta 1 | beta 0 |", "|---|---:|---:|---:|"]
    L += [f"| {k} | " + " | ".join(f"{v:.3f}" for v in row) + " |" for k, row in d["retention"].items()]
    kinds = list(next(iter(d["split"].values())))
    L += ["", "Energy split of the linear solution at R/h 1e4 (fractions):", "",
          "| mesh | " + " | ".join(kinds) + " |", "|---|" + "---:|" * len(kinds)]
    L += [f"| {n}x{n} | " + " | ".join(f"{s[k]:.4f}" for k in kinds) + " |" for n, s in d["split"].items()]
    L += ["", "Null space of the tied membrane and transverse-shear strains at the Gauss points on the free dofs "
          "(deformations resisted at bending order only), its dimension:", "",
          "| mesh | as tied | drilling rotations held | MITC4+ tying set (edge stretches, edge transverse shears, "
          "centre in-plane shear; drilling held; flat-facet translations) | load on the modes |", "|---|---:|---:|---:|---|"]
    L += [f"| {n}x{n} | {v['tied']} | {v['drilling_held']} | {v['mitc4plus']} | {v['load']} |" for n, v in d["mechanisms"].items()]
    L += ["", "Largest translation of the modes (orthonormal basis) per row of nodes, by angle from the crown (deg):", ""]
    L += [f"* {n}x{n}: " + ", ".join(f"{a:g}: {x:.3f}" for a, x in v["by_row"].items()) for n, v in d["mechanisms"].items()]
    L += ["", "Lowest six eigenvalues of the free stiffness, K(h) / K(h/10) (R/h 1e3 to 1e4; 10: membrane order, "
          "1000: bending order): " + "; ".join(f"{n}x{n} {v}" for n, v in d["orders"].items()) + ".", ""]
    L += ["## Candidates and peers", "",
          "Deflection / the default element's 64x64 value at the same thickness (the converged shell; "
          "a locking candidate's own fine mesh locks too).", ""]
    for case, rows in doc["sweeps"].items():
        L += [f"{case}:", "", "| candidate | R/h | " + " | ".join(f"{n}x{n}" for n in MESHES) + " |",
              "|---|---|" + "---:|" * len(MESHES)]
        for name, sw in rows.items():
            L += [f"| {name} | {float(rh):g} | " + " | ".join(f"{v:.3f}" for v in r) + " |" for rh, r in sw.items()]
        L.append("")
    L += [NOTES, ""]
    (ROOT / "benchmarks" / "results" / "roof_modes.md").write_text("\n".join(L))


NOTES = """## Reading

See docs/ELEMENTS.md, "The coarse thin roof: free-edge mechanisms of the edge tying".
"""


def chord_tie_sweeps(weights=(1.0, 1e-2, 1e-4)):
    """Print the roof and hemisphere sweeps with :func:`chord_tie` at each weight (the free edges:
    the roof's x1, the hemisphere's hole x0 and equator x1), / the default element's 64x64."""
    conv = {"roof": converged(sc.scordelis_lo, 25.0), "hemi": converged(sc.pinched_hemisphere, 10.0)}
    for w in weights:
        for case, build, R, edges in (("roof", sc.scordelis_lo, 25.0, ("x1",)),
                                      ("hemi", sc.pinched_hemisphere, 10.0, ("x0", "x1"))):
            result_of = lambda p, w=w, edges=edges: solve(p, stiffness(p) + chord_tie(p, w, edges))[0]
            for rh, r in sweep(build, R, result_of, conv[case]).items():
                print(f"chord tie {w:g} E h, {case}, R/h {rh:g}: "
                      + " ".join(f"{n}x{n} {v:.3f}" for n, v in zip(MESHES, r)), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--opensees", default=None, help="python of an OpenSeesPy 3.7.1 venv")
    ap.add_argument("--chord-tie", action="store_true",
                    help="only print the sweeps with the free-edge chord tie (docs/ELEMENTS.md)")
    a = ap.parse_args()
    if a.chord_tie:
        return chord_tie_sweeps()
    conv = {"roof": converged(sc.scordelis_lo, 25.0), "hemi": converged(sc.pinched_hemisphere, 10.0)}
    doc = dict(date=datetime.datetime.now().isoformat(timespec="seconds"), opensees="3.7.1" if a.opensees else None)
    doc["diagnosis"] = diagnosis(conv["roof"])
    print(json.dumps(doc["diagnosis"], default=str)[:3000], flush=True)
    sweeps = {"Scordelis-Lo roof": {}, "pinched hemisphere": {}}
    for name, stiff in CANDIDATES.items():
        result_of = lambda p, stiff=stiff: solve(p, stiff(p))[0]
        sweeps["Scordelis-Lo roof"][name] = sweep(sc.scordelis_lo, 25.0, result_of, conv["roof"])
        if "shear variation" not in name:
            sweeps["pinched hemisphere"][name] = sweep(sc.pinched_hemisphere, 10.0, result_of, conv["hemi"])
        print(name, flush=True)
    for elem in (("ASDShellQ4", "ShellMITC4") if a.opensees else ()):
        for case, build, R, key in (("Scordelis-Lo roof", sc.scordelis_lo, 25.0, "roof"),
                                    ("pinched hemisphere", sc.pinched_hemisphere, 10.0, "hemi")):
            result_of = lambda p, elem=elem: opensees_solve(a.opensees, p, elem)
            sweeps[case][f"OpenSees {elem}"] = sweep(build, R, result_of, conv[key])
        print(elem, flush=True)
    doc["sweeps"] = sweeps
    write(doc)


if __name__ == "__main__":
    main()
