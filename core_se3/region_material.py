"""A material that differs per element: one core_se3.Material per element (e.g. per region).

The default element (element.py) asks its material for ``resultant_matrix(A1, A2)`` at the
Gauss points of all elements at once, A1, A2 of shape (m, ..., 3); this class answers with
each element's own law (material.py), grouped by distinct material so the work stays batched:

    W_e = 1/2 eps^T D(E_e, nu_e, h_e, ks_e, drilling_e) eps        on element e.

    mat = RegionMaterial.from_regions(mesh.n_elements, Material(E, nu, h),
                                      {elements_of_tip: Material(E2, nu, h2)})
    Problem(mesh, mat)

Scalar properties (E, nu, h, ...) are available when they are the same on every element;
otherwise reading one raises MaterialError (loads that need h per element, such as gravity or
magnetisation, must then be built per region with that region's h).
"""
from __future__ import annotations

import numpy as np

from .errors import MaterialError
from .material import Material

__all__ = ["RegionMaterial"]


class RegionMaterial:
    """Per-element materials: ``materials`` (k distinct Material), ``index`` (m,) into them."""

    def __init__(self, materials, index):
        self.materials = list(materials)
        self.index = np.asarray(index, np.int64)
        if not self.materials or any(not isinstance(m, Material) for m in self.materials):
            raise MaterialError("RegionMaterial needs a list of core_se3.Material")
        if self.index.ndim != 1 or self.index.min() < 0 or self.index.max() >= len(self.materials):
            raise MaterialError("RegionMaterial index must give one material per element")

    @classmethod
    def from_regions(cls, n_elements, base, regions):
        """``base`` everywhere except on the element sets of ``regions`` {ids: Material}."""
        mats, index = [base], np.zeros(n_elements, np.int64)
        seen = np.zeros(n_elements, bool)
        for ids, mat in regions.items() if isinstance(regions, dict) else regions:
            ids = np.asarray(ids, np.int64)
            if np.any(seen[ids]):
                raise MaterialError("material regions overlap: an element would get two materials")
            seen[ids] = True
            if mat not in mats:
                mats.append(mat)
            index[ids] = mats.index(mat)
        return cls(mats, index)

    def __len__(self):
        return len(self.index)

    def per_element(self, name):
        """Property ``name`` (E, nu, h, ...) of every element, (m,)."""
        return np.array([getattr(m, name) for m in self.materials])[self.index]

    def _uniform(self, name):
        vals = {getattr(m, name) for m in self.materials if np.any(self.index == self.materials.index(m))}
        if len(vals) != 1:
            raise MaterialError(f"{name} differs between regions ({sorted(vals)}); use per_element({name!r})")
        return vals.pop()

    E = property(lambda self: self._uniform("E"))
    nu = property(lambda self: self._uniform("nu"))
    h = property(lambda self: self._uniform("h"))
    shear_factor = property(lambda self: self._uniform("shear_factor"))
    drilling = property(lambda self: self._uniform("drilling"))

    def resultant_matrix(self, A1, A2):
        """(Dmat, j0) as Material.resultant_matrix, each element (leading axis) with its own law."""
        A1 = np.asarray(A1, float)
        A2 = np.asarray(A2, float)
        if A1.shape[0] != len(self.index):
            raise MaterialError(f"RegionMaterial has {len(self.index)} elements, got points of {A1.shape[0]}")
        D = np.empty(A1.shape[:-1] + (12, 12))
        j0 = np.empty(A1.shape[:-1])
        for k, mat in enumerate(self.materials):
            sel = self.index == k
            if np.any(sel):
                D[sel], j0[sel] = mat.resultant_matrix(A1[sel], A2[sel])
        return D, j0
