"""The seed's own scheme (``--element seed``), kept for comparison with the default element.

As in the seed (sec. 5, eqs. E71-E75 and Algorithm 1):

* one strain twist per element, at the centroid, zeta_a^c, updated *incrementally* after every
  Newton correction eta (nodal values interpolated bilinearly):

      zeta_a^c <- Ad_{exp(-eta_c)} zeta_a^c + dexp(eta_c) d eta/d xi^a (centroid),

* stress resultants S^a = D^{ab} (zeta_b^c - zeta0_b^c) (the material law of ``material``, so the
  two elements differ only in kinematics), constant over the element,
* internal force and tangent with 2x2 Gauss points and K^i_a = dN^i/dxi^a I + N^i ad(zeta_a^c):

      r_i = sum_gp j0 sum_a (K^i_a)^T S^a                                  (E74, sign: r = int - ext)
      K_ij = sum_gp j0 [ sum_ab (K^i_a)^T D^{ab} K^j_b + sum_a N^i adt(S^a) K^j_a ]   (E75)

Consequences (measured in ``benchmarks/elements.py`` and ``docs/ELEMENTS.md``): the strain is a
state variable, not a function of the current frames, so results depend on the load path and
on superposed rigid motions applied between updates; a single strain point per element leaves
hourglass modes.
"""
from __future__ import annotations

import warnings

import numpy as np

from .. import lie
from ..errors import ElementTooDistortedError, ElementWarning
from .element import Element, ElementEvaluation, register_element
from .element_default import DefaultElement
from .material import law_matrix
from .quadrature import GAUSS_2x2, shape_functions

__all__ = ["SeedElement", "SEED_THIN"]

# element size / thickness above which the seed's scheme locks (ElementWarning): it converges
# and is right at 1.25 (the locking study's L/h = 10 cantilever and arch), fails at 12.5, and
# converged 130 times too stiff in torsion at 1000 (reports/REPORT.md, stress study)
SEED_THIN = 10.0


@register_element
class SeedElement(Element):
    """The seed's element (module docstring): centroid strain twists updated incrementally.

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The reference mesh.
    material : core_se3.fem.ResultantLaw
        The resultant law (the same as the default element's).

    Attributes
    ----------
    zeta0, zeta : (m, 2, 6) ndarray
        Reference and current centroid strain twists (zeta_1, zeta_2) of every element; ``zeta``
        is the state that :meth:`update` advances and :meth:`save`/:meth:`restore` keep.

    Example
    -------
    >>> from core_se3 import mesh, Material
    >>> el = SeedElement(mesh.rectangle(1.0, 1.0, 2, 1), Material(1.0e3, 0.3, 0.01))
    >>> el.stateful, el.zeta.shape
    (True, (2, 2, 6))
    """

    name = "seed"
    stateful = True

    def __init__(self, mesh, material):
        super().__init__(mesh, material)
        _warn_if_thin(mesh, material)
        base = DefaultElement(mesh, material)
        _refuse_cuts(mesh, base.matching)
        # reference centroid twists = mean of the opposite edge twists (exact for the commuting
        # reference states of the catalogue: flat plates and cylinders)
        z0 = base.z0.reshape(-1, 4, 6)
        self.zeta0 = np.stack([0.5 * (z0[:, 0] + z0[:, 1]), 0.5 * (z0[:, 2] + z0[:, 3])], 1)  # (m,2,6)
        A1, A2 = self.zeta0[:, 0, :3], self.zeta0[:, 1, :3]
        self.Dc, self.j0c = law_matrix(material, A1, A2, self.size)       # (m,12,12), (m,)
        self.N, dN = shape_functions(GAUSS_2x2)                          # (4gp,4), (4gp,2,4)
        self.dN = dN
        self.Nc, dNc = shape_functions(np.zeros((1, 2)))
        self.dNc = dNc[0]                                                # (2,4)
        self.zeta = self.zeta0.copy()
        self._saved = self.zeta.copy()

    # ----------------------------------------------------------------- state -------------
    def save(self):
        self._saved = self.zeta.copy()

    def restore(self):
        self.zeta = self._saved.copy()

    def update(self, eta):
        """Algorithm 1's incremental twist update for nodal increments eta (n, 6)."""
        e = eta[self.mesh.quads]                                         # (m,4,6)
        ec = np.einsum("i,mik->mk", self.Nc[0], e)
        de = np.einsum("ai,mik->mak", self.dNc, e)                       # (m,2,6)
        Adm = lie.Ad(lie.exp(-ec))
        T = lie.dexp(ec)
        self.zeta = np.einsum("mij,maj->mai", Adm, self.zeta) + np.einsum("mij,maj->mai", T, de)

    # ----------------------------------------------------------------- kernels -----------
    def energy(self, g=None):
        eps = (self.zeta - self.zeta0).reshape(-1, 12)
        return 0.5 * np.einsum("mi,mij,mj,m->", eps, self.Dc, eps, 4 * self.j0c)

    def evaluate(self, g=None, tangent=True):
        m = self.mesh
        eps = (self.zeta - self.zeta0).reshape(-1, 12)
        S = np.einsum("mij,mj->mi", self.Dc, eps).reshape(-1, 2, 6)       # (m,2,6)
        adz = lie.ad(self.zeta)                                          # (m,2,6,6)
        # K[m, q, a, i] = dN_i/dxi_a(q) I + N_i(q) ad(zeta_a): (m,q,a,i,6,6)
        K = (self.dN[None, :, :, :, None, None] * np.eye(6)
             + self.N[None, :, None, :, None, None] * adz[:, None, :, None])
        w = self.j0c                                                     # weight 1 per gp
        r_el = np.einsum("m,mqaikl,mak->mil", w, K, S)                   # (m,4,6)
        n = m.n_nodes
        r = np.stack([np.bincount(m.quads.ravel(), weights=r_el[..., k].ravel(), minlength=n)
                      for k in range(6)], -1)
        fscale = np.linalg.norm(np.einsum("mij,mj->mi", self.Dc, self.zeta.reshape(-1, 12)))
        if not tangent:
            return ElementEvaluation(self.energy(), r, fscale)
        D = self.Dc.reshape(-1, 2, 6, 2, 6)
        Km = np.einsum("m,mqaikl,makbp,mqbjpr->mijlr", w, K, D, K)
        adtS = lie.adt(S)                                                # (m,2,6,6)
        Kg = np.einsum("m,qi,makp,mqajpr->mijkr", w, self.N, adtS, K)
        return ElementEvaluation(self.energy(), r, fscale, element_blocks=Km + Kg)


def _refuse_cuts(mesh, matching):
    """ElementTooDistortedError where neighbouring frames' d1 turn by more than 45 deg about the
    normal (a cross field's cuts, ``mesh.gauge.edge_matching``): the default element matches such
    edges by quarter turns (``element_default``, "Cuts"), the seed's scheme interpolates the nodal
    increments in the nodes' own frames and cannot.  On the closed cubed sphere read from a file
    (R/h 100, pressurised) it came out 0.14 ... 3.6 times the exact displacement on 16 x 16 per face,
    silent, once the default element it builds on took the cuts (before, that refused them)."""
    if matching is None:
        return
    e = np.flatnonzero(np.asarray(matching) % 4)
    a, b = mesh.edge_nodes[e[0]]
    raise ElementTooDistortedError(
        f"element 'seed' (the paper's scheme, kept for comparison): the nodes' d1 turn by more than 45 deg about the "
        f"normal across {len(e)} mesh edge(s) (e.g. nodes {int(a)} and {int(b)}: a cross field's quarter-turn cuts, "
        "a mesh file's default frames on a closed surface), which the seed's scheme, interpolating the nodal "
        "increments in each node's own frame, cannot take (a pressurised closed sphere: 0.14 ... 3.6 times the "
        "exact displacement) -- use element = 'default', which matches them, or frames whose d1 turns little "
        "from node to node (a d1_hint along the shell)")


def _warn_if_thin(mesh, material):
    """An ElementWarning when the median element size exceeds SEED_THIN thicknesses."""
    x = mesh.X[mesh.edge_nodes]
    size = float(np.median(np.linalg.norm(x[:, 1] - x[:, 0], axis=1)))
    h = float(np.median(np.atleast_1d(getattr(material, "h", np.nan))))
    if np.isfinite(h) and h > 0 and size > SEED_THIN * h:
        warnings.warn(ElementWarning(
            f"element 'seed' (the paper's scheme, kept for comparison) on a thin mesh: element size / thickness "
            f"= {size / h:.3g} > {SEED_THIN:g}, where it locks -- it may converge to a state far too stiff (torsion "
            f"at 1000: 130 times the torsion constant) or not converge. Use element = 'default'"), stacklevel=4)
