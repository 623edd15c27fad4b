"""E or h per element region as a design variable (see ``design.variables``: dr/dp by central
differences of the element residual at the fixed state, exact for the polynomial dependence)."""
from __future__ import annotations

import numpy as np

from ..errors import DesignError, did_you_mean
from ..fem import Material, RegionMaterial
from ..fem.material_kinds import ISOTROPIC
from .variables import Variable, region_elements

__all__ = ["MaterialVariable", "MATERIAL_KEYS"]


MATERIAL_KEYS = ISOTROPIC.keys()          # the isotropic law's keys, in Material's order


class MaterialVariable(Variable):
    """Young's modulus E or the thickness h constant over each of a list of element regions.

    dr/dp by central differences of the element residual at the fixed state, Richardson
    extrapolated (module docstring): exact up to round-off for E (linear) and h (cubic).  A
    thickness variable on a region that carries a magnet or gravity is refused: those loads keep
    the thickness they were built with.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (default element; any law, it becomes a RegionMaterial).
    regions : sequence
        Region names or element-id arrays (disjoint).
    prop : str
        'E' or 'h'.
    lower, upper : float, optional
        Bounds (default: positive values).
    name : str, optional
        Its name (default ``prop``).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(2.0, 0.5, 2, 1), Material(1e3, 0.0, 0.1))
    >>> v = MaterialVariable(p, [[0], [1]], "E")
    >>> v.assign([1e3, 3e3]); p.material.per_element("E").tolist()
    [1000.0, 3000.0]
    """

    def __init__(self, problem, regions, prop="E", lower=None, upper=np.inf, name=None):
        name = name or prop
        if prop not in ("E", "h"):
            raise DesignError(f"material variable {name!r}: prop must be 'E' or 'h', got {prop!r}{did_you_mean(prop, ('E', 'h'))}")
        self.problem, self.prop = problem, prop
        self.regions = [region_elements(problem, r, f"material variable {name!r}") for r in regions]
        allel = np.concatenate(self.regions)
        if len(np.unique(allel)) != len(allel):
            raise DesignError(f"material variable {name!r}: the regions overlap")
        if prop == "h":
            touched = np.zeros(problem.mesh.n_elements, bool)
            touched[allel] = True
            for ld in problem.loads:
                el = getattr(getattr(ld, "mag", None), "elements", None)
                if (el is not None and np.any(touched[el])) or getattr(ld, "name", "") == "gravity":
                    raise DesignError(f"material variable {name!r}: the thickness of a region with a magnet or "
                                      "gravity cannot be designed (those loads keep the thickness they were built with)")
        props = self._per_element()
        x0 = np.array([props[prop][r].mean() for r in self.regions])
        self._setup(name, len(self.regions), 0.0 if lower is None else lower, upper, x0,
                    [f"{name}[{j}]" for j in range(len(self.regions))], None)

    def _per_element(self):
        mat, m = self.problem.material, self.problem.mesh.n_elements
        per = getattr(mat, "per_element", None)
        return {k: (per(k) if per is not None else np.full(m, getattr(mat, k), dtype=object if k == "rho" else float))
                for k in MATERIAL_KEYS}

    def value(self):
        props = self._per_element()
        return np.array([float(props[self.prop][r][0]) for r in self.regions])

    def _law(self, x):
        props = self._per_element()                 # the current law (other variables may change it)
        for r, val in zip(self.regions, x):
            props[self.prop][r] = val
        keys = list(zip(*[props[k] for k in MATERIAL_KEYS]))
        uniq = list(dict.fromkeys(keys))
        if len(uniq) == 1:
            return Material(*uniq[0])
        return RegionMaterial([Material(*u) for u in uniq], np.array([uniq.index(t) for t in keys]))

    def assign(self, x):
        x = np.asarray(x, float)
        self.problem.set_material(self._law(x))

    def dr_dp(self, problem, g, lam):
        x = self.value()
        out = np.zeros((problem.mesh.n_nodes, 6, self.size))
        try:
            for j in range(self.size):
                d = 0.02 * x[j]
                D = []
                for step in (d, 2 * d):
                    rs = []
                    for sgn in (1, -1):
                        xx = x.copy()
                        xx[j] += sgn * step
                        problem.set_material(self._law(xx))
                        rs.append(problem.element.evaluate(g, tangent=False).r)
                    D.append((rs[0] - rs[1]) / (2 * step))
                out[:, :, j] = (4 * D[0] - D[1]) / 3
        finally:
            problem.set_material(self._law(x))
        return out
