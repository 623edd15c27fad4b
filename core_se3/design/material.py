"""E or h per element region as a design variable (see ``design.variables``): the partial
derivatives at the fixed state (dr/dp of the element residual, dPi/dp of the energy) by
differences that are exact for the polynomial dependence: E by one difference (the residual is
linear in E), h by central differences Richardson-extrapolated (cubic in h)."""
from __future__ import annotations

import numpy as np

from ..errors import DesignError, did_you_mean
from ..fem import Material, RegionMaterial
from ..fem.material_kinds import ISOTROPIC
from ..model import ContactLoad
from .variables import Variable, named_regions, region_elements, region_label

__all__ = ["MaterialVariable", "MATERIAL_KEYS"]


MATERIAL_KEYS = ISOTROPIC.keys()          # the isotropic law's keys (scenario keys of [material])
_LAW_KEYS = MATERIAL_KEYS + ("classical",)  # what rebuilds a Material (by keyword)


def _check_thickness_loads(problem, elements, name):
    """DesignError when a load of the problem keeps the thickness of ``elements`` it was built
    with: a magnet (its dipoles h B^r / mu0), gravity (rho g h) or a contact (its surface at h/2
    from the mid-surface, its penalty from the shell's stiffness) on a node of those elements --
    a thickness variable there would solve with the old thickness in those loads (a contact:
    0.01 too deep for h 0.02 -> 0.04) while the optimised scenario, built anew, would not."""
    touched = np.zeros(problem.mesh.n_elements, bool)
    touched[elements] = True
    nodes = np.zeros(problem.mesh.n_nodes, bool)
    nodes[problem.mesh.quads[elements].ravel()] = True
    for ld in problem.loads:
        el = getattr(getattr(ld, "mag", None), "elements", None)
        if (el is not None and np.any(touched[el])) or getattr(ld, "name", "") == "gravity":
            raise DesignError(f"material variable {name!r}: the thickness of a region with a magnet or "
                              "gravity cannot be designed (those loads keep the thickness they were built with)")
        if isinstance(ld, ContactLoad) and np.any(nodes[ld.nodes]):
            raise DesignError(f"material variable {name!r}: the thickness of a region in contact (obstacle "
                              f"{ld.name!r}) cannot be designed (the contact keeps the surface offset h/2 and the "
                              "penalty it was built with); design E there, or the thickness of regions off the contact")


def _check_penalty_contacts(problem, elements, name):
    """DesignError when a contact in mode 'penalty' takes its penalty from the shell's stiffness
    (k = beta K_i / A_i, K_i linear in the E of the elements at node i) on a node of ``elements``:
    the answer of a penalty contact depends on k, which keeps the E it was built with -- an E
    variable there would solve with the old penalty (E x 4: the penetration 3.4e-6 instead of
    the 8.6e-7 of the optimised scenario, built anew) and its derivatives would miss dk/dE.
    Mode 'al' (its answer the Signorini one whatever k) and a penalty k given are kept."""
    nodes = np.zeros(problem.mesh.n_nodes, bool)
    nodes[problem.mesh.quads[elements].ravel()] = True
    for ld in problem.loads:
        if isinstance(ld, ContactLoad) and ld.mode == "penalty" and ld.law.k is None and np.any(nodes[ld.nodes]):
            raise DesignError(f"material variable {name!r}: E of a region in contact (obstacle {ld.name!r}) in mode "
                              "'penalty' with its penalty from the shell's stiffness cannot be designed (the penalty, "
                              "and so the penetration, keeps the E it was built with); use mode 'al' (the default: "
                              "its answer does not depend on the penalty), give the penalty k, or design E off the "
                              "contact")


class MaterialVariable(Variable):
    """Young's modulus E or the thickness h constant over each of a list of element regions.

    dr/dp by :meth:`partials` of the element residual at the fixed state (module docstring):
    exact up to round-off for E (linear) and h (cubic).  A
    thickness variable on a region that carries a magnet, gravity or a contact is refused: those
    loads keep the thickness they were built with; so is E on a region in a penalty contact
    whose penalty derives from the shell's stiffness (mode 'penalty' without ``k``).

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (default element; any law, it becomes a RegionMaterial).
    regions : sequence or dict
        Region names or element-id arrays (disjoint), or a dict name -> element ids (a
        scenario's regions: messages name them; ``region_names``).
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
        self.region_names, regions = named_regions(regions)
        self.regions = [region_elements(problem, r, f"material variable {name!r}") for r in regions]
        allel = np.concatenate(self.regions)
        if len(np.unique(allel)) != len(allel):
            raise DesignError(f"material variable {name!r}: the regions overlap")
        if prop == "h":
            _check_thickness_loads(problem, allel, name)
        else:
            _check_penalty_contacts(problem, allel, name)
        props = self._per_element()
        for j, r in enumerate(self.regions):
            lo, hi = float(np.min(props[prop][r])), float(np.max(props[prop][r]))
            if hi > lo:
                # one value per region: the start would set the whole region to its first element's
                raise DesignError(f"material variable {name!r}: {prop} varies over "
                                  f"{region_label(self.region_names, j)} ({lo:g} .. {hi:g}); a "
                                  f"design variable is one {prop} per region: give regions on which it is uniform")
        x0 = np.array([props[prop][r].mean() for r in self.regions])
        self._setup(name, len(self.regions), 0.0 if lower is None else lower, upper, x0,
                    [f"{name}[{j}]" for j in range(len(self.regions))], None)

    def _per_element(self):
        mat, m = self.problem.material, self.problem.mesh.n_elements
        per = getattr(mat, "per_element", None)
        return {k: (per(k) if per is not None else np.full(m, getattr(mat, k), dtype=object if k in ("rho", "classical") else float))
                for k in _LAW_KEYS}

    def controls(self):
        return {("material", self.prop, int(e)) for r in self.regions for e in r}

    def value(self):
        props = self._per_element()
        return np.array([float(props[self.prop][r][0]) for r in self.regions])

    def _law(self, x):
        props = self._per_element()                 # the current law (other variables may change it)
        for r, val in zip(self.regions, x):
            props[self.prop][r] = val
        keys = list(zip(*[props[k] for k in _LAW_KEYS]))
        uniq = list(dict.fromkeys(keys))
        laws = [Material(**dict(zip(_LAW_KEYS, u))) for u in uniq]
        if len(laws) == 1:
            return laws[0]
        return RegionMaterial(laws, np.array([uniq.index(t) for t in keys]))

    def assign(self, x):
        x = np.asarray(x, float)
        self.problem.set_material(self._law(x))

    def dr_dp(self, problem, g, lam):
        return self.partials(lambda: problem.element.evaluate(g, tangent=False).r)

    def partials(self, fn):
        """d fn / d x_j (fn.shape + (size,)) of ``fn()``, a function of the problem's material
        law at a fixed state (the element residual, the energy), the law restored afterwards.

        E: fn(x + E_j e_j) - fn(x), divided by E_j, one law per component -- exact up to
        round-off because the element's stiffnesses (C = E h, D = E h^3 / 12, G) and so its
        residual are linear in E.  h: central differences at d = 0.02 h and 2d, Richardson
        extrapolated (D1 + (D1 - D2) / 3: exact for the cubic dependence), four laws per
        component; with a shear stabilisation (rational in h, with the kink of its floor) d is
        kept off the kink (:meth:`_h_step`).

        Example
        -------
        >>> import numpy as np
        >>> from core_se3 import Problem, Material, mesh
        >>> p = Problem(mesh.rectangle(2.0, 0.5, 2, 1), Material(1e3, 0.0, 0.1))
        >>> v = MaterialVariable(p, [[0], [1]], "E")
        >>> g = p.mesh.g0.copy(); g[:, 0, 3] *= 1.01                   # strain 0.01
        >>> dPi = v.partials(lambda: np.array([p.element.evaluate(g, tangent=False).energy]))
        >>> (dPi / (0.5 * 0.1 * 0.01 ** 2 * 0.5)).round(9).tolist()    # 1/2 h eps^2 x area 0.5
        [[1.0, 1.0]]
        """
        x = self.value()
        f0 = np.asarray(fn(), float) if self.prop == "E" else None
        out = []
        try:
            for j in range(self.size):
                if self.prop == "E":
                    out.append((self._at(x, j, x[j], fn) - f0) / x[j])
                    continue
                d = self._h_step(j, x[j])
                D1, D2 = ((self._at(x, j, s, fn) - self._at(x, j, -s, fn)) / (2 * s) for s in (d, 2 * d))
                out.append((4 * D1 - D2) / 3)
        finally:
            self.problem.set_material(self._law(x))
        return np.stack(out, -1)

    def _h_step(self, j, h):
        """The step d of the thickness differences of region j at thickness h: 0.02 h, or less so
        that [h - 2d, h + 2d] holds no kink of a shear stabilisation's floor (its factor
        max(h^2 / (h^2 + alpha L^2), c) turns at h = L sqrt(c alpha / (1 - c)) on an element of
        size L): across the kink the differences mixed its two slopes (the tip deflection's
        derivative 3.9e-5 off with the kink 3 % above h, 2e-4 at 1 %); at least 1e-6 h."""
        props, r = self._per_element(), self.regions[j]
        a = np.asarray(props["shear_stabilisation"][r], float)
        c = np.asarray(props["shear_stabilisation_floor"][r], float)
        on = (a > 0) & (c > 0) & (c < 1)
        if not on.any():
            return 0.02 * h
        kinks = self.problem.element.size[r][on] * np.sqrt(c[on] * a[on] / (1 - c[on]))
        return max(min(0.02 * h, np.abs(kinks - h).min() / 4), 1e-6 * h)

    def _at(self, x, j, step, fn):
        """fn() with the law at x + step e_j."""
        xx = x.copy()
        xx[j] += step
        self.problem.set_material(self._law(xx))
        return np.asarray(fn(), float)
