"""The magnetisation of element regions as a design variable (see ``design.variables`` for the
contract and how dr/dp is computed: here analytically, the magnetic load being linear in the
dipoles)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import lie
from ..errors import DesignError
from ..fem.quadrature import shape_functions, surface_jacobian
from ..model import MU0, MagneticLoad, Magnetisation
from ..model.loads import curved_area, element_area
from .variables import (Variable, field_at, free_index, magnetic_loads, named_regions, plane_axes, polar_vector,
                        region_elements, region_label)

__all__ = ["RegionMagnetisation", "Parametrisation"]


@dataclass(frozen=True)
class Parametrisation:
    """How a :class:`RegionMagnetisation` parametrises B^r in each region.

    Parameters
    ----------
    form : str
        'vector' (3 per region) or 'polar' (magnitude and angle [rad] from e1 toward e2).
    planes : (e1, e2) or a sequence of them, optional
        The plane(s) of the polar form (default x and z).
    free : sequence of str, optional
        The free components of every region ('x', 'y', 'z' or 'magnitude', 'angle'; default all).
    Br_max : float, optional
        |B^r| <= Br_max [T] per region (norm bound, or the magnitude's upper bound).

    Example
    -------
    >>> Parametrisation.of({"form": "polar", "Br_max": 0.1}).planes
    ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    """
    form: str = "vector"
    planes: object = ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    free: object = None
    Br_max: float | None = None

    @classmethod
    def of(cls, spec):
        """A Parametrisation from itself, a form name ('vector', 'polar') or a dict of its fields."""
        if isinstance(spec, cls):
            return spec
        if isinstance(spec, str):
            return cls(spec)
        if isinstance(spec, dict):
            unknown = sorted(set(spec) - set(cls.__dataclass_fields__))
            if unknown:
                raise DesignError(f"magnetisation: unknown parametrisation key(s) {unknown}; the keys are "
                                  f"{list(cls.__dataclass_fields__)}")
            return cls(**spec)
        raise DesignError(f"magnetisation: form must be 'vector', 'polar', a dict or a Parametrisation, got {spec!r}")


def lumping(mesh, elements, j0=None):
    """(n, m) weights int_e N_i dA of the nodes i of the elements (reference area shares), with
    the element's own area element ``j0`` (m, 4) on curved elements, as ``Magnetisation``."""
    N, dN = shape_functions()
    quads = mesh.quads[elements]
    w = np.einsum("qi,mq->mi", N, curved_area(surface_jacobian(mesh.X[quads], dN), j0, "magnetisation")[0])
    W = np.zeros((mesh.n_nodes, len(elements)))
    np.add.at(W, (quads, np.broadcast_to(np.arange(len(elements))[:, None], quads.shape)), w)
    return W


def _covered_magnets(problem, elements, name):
    """The problem's magnetic loads on the design regions' ``elements``; a magnet partly inside
    them is a DesignError."""
    inside = np.zeros(problem.mesh.n_elements, bool)
    inside[elements] = True
    old = [ld for ld in magnetic_loads(problem) if np.any(inside[ld.mag.elements])]
    for ld in old:
        if not np.all(inside[ld.mag.elements]):
            raise DesignError(f"magnetisation {name!r}: a magnet covers elements inside and outside the design "
                              "regions; make the regions cover each magnet entirely")
    return old


def _fields_of(old, field, name):
    """The applied fields of a RegionMagnetisation: those of the replaced magnets ``old`` (one
    material put in several fields by a magnet per field, as examples/walker.toml), ``field``
    first when given (it must be one of them: before, the magnets of the other fields were
    dropped and their B^r added into the fitted start); [field] without magnets."""
    fields = []
    for ld in old:
        if not any(ld.field is f for f in fields):
            fields.append(ld.field)
    if field is None:
        if not fields:
            raise DesignError(f"magnetisation {name!r}: no magnet on these regions: give the applied field")
        return fields
    if fields and not any(field is f for f in fields):
        raise DesignError(f"magnetisation {name!r}: the magnets on these regions are in {len(fields)} other "
                          "field(s) than the one given: the variable replaces them in their own fields; give one "
                          "of them or none")
    return [field] + [f for f in fields if f is not field]


class RegionMagnetisation(Variable):
    """The residual flux density B^r [T] (lab, reference configuration) constant over each of a
    list of element regions -- what can be fabricated -- as a design variable: form 'vector'
    (3 per region) or 'polar' (magnitude and angle [rad] from e1 toward e2 in each region's
    plane); ``free`` picks the components ('x', 'y', 'z' or 'magnitude', 'angle').

    The magnets of the problem on these regions (``Problem.add_magnetic``) are replaced by this
    variable's own magnetic loads (one per thickness); their magnetisation, fitted per region
    (least squares of the nodal moments), is the start: a DesignError naming the region when it
    is not constant per region (a fit misfit above 1e-8, where it would change the shell).
    The dipoles are mu_i = (h/mu0) R0_i^T sum_j C_ij B^r_j with C_ij = int_(region j) N_i dA.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem.
    regions : sequence or dict
        Region names or element-id arrays (disjoint), or a dict name -> element ids (a
        scenario's regions: messages name them; ``region_names``).
    form : Parametrisation, str or dict, optional
        The form with its planes, free components and bound (:class:`Parametrisation`; a
        form name or a dict of its fields; default 'vector', all free, unbounded).
    field : Field, optional
        The applied field: needed without magnets on the regions; with them, one of their fields
        or None.  The variable acts in every field of the replaced magnets (one material put
        in several fields by a magnet per field, ``examples/walker.toml``: its B^r, fitted to
        each field's magnets, is one); ``fields`` lists them, ``field`` is the first.
    mu0 : float, optional
        Vacuum permeability (default that of the replaced magnets -- a DesignError when they
        differ -- else MU0).
    start : (k, 3) array, optional
        The starting B^r per region (lab vectors) instead of the fitted one.
    name : str
        Its name.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import UniformField
    >>> p = Problem(mesh.rectangle(4.0, 0.5, 4, 1), Material(1e3, 0.0, 0.1))
    >>> _ = p.add_magnetic((0.2, 0.0, 0.0), UniformField((0.0, 0.0, 1.0)), mu0=1.0)
    >>> v = RegionMagnetisation(p, [[0, 1], [2, 3]])
    >>> v.value().round(12).tolist(), len(p.loads)
    ([0.2, 0.0, 0.0, 0.2, 0.0, 0.0], 1)
    >>> q = Problem(mesh.rectangle(4.0, 0.5, 4, 1), Material(1e3, 0.0, 0.1))      # no magnet: a field given
    >>> RegionMagnetisation(q, [[0, 1]], dict(free=("x", "z")), UniformField((0.0, 0.0, 1.0)), name="Br").labels
    ['Br[0].x', 'Br[0].z']
    """

    def __init__(self, problem, regions, form="vector", field=None, mu0=None, start=None, name="magnetisation"):
        mesh = problem.mesh
        spec = Parametrisation.of(form)
        form, planes, free, Br_max = spec.form, spec.planes, spec.free, spec.Br_max
        self.problem, self.form = problem, form
        if form not in ("vector", "polar"):
            raise DesignError(f"magnetisation {name!r}: form must be 'vector' or 'polar', got {form!r}")
        self.region_names, regions = named_regions(regions)
        self.regions = [region_elements(problem, r, f"magnetisation {name!r}") for r in regions]
        if not self.regions:
            raise DesignError(f"magnetisation {name!r}: no regions")
        allel = np.concatenate(self.regions)
        if len(np.unique(allel)) != len(allel):
            raise DesignError(f"magnetisation {name!r}: the regions overlap")
        k = len(self.regions)
        old = _covered_magnets(problem, allel, name)
        self.fields = _fields_of(old, field, name)
        field = self.fields[0]
        mu0s = {ld.mag.mu0 for ld in old}
        if mu0 is None and len(mu0s) > 1:
            # one mu0 for all the regions: SI's in its place would scale the loads by mu0 / MU0
            raise DesignError(f"magnetisation {name!r}: the magnets on these regions have different mu0 "
                              f"({', '.join(f'{m:g}' for m in sorted(mu0s))}); the units of a model have one: "
                              "give mu0 (or make the magnets' mu0 agree)")
        self.mu0 = float(mu0 if mu0 is not None else (mu0s.pop() if mu0s else MU0))
        self.field = field
        self.j0 = element_area(problem, allel)                              # None: the bilinear quads'
        W = lumping(mesh, allel, self.j0)                                   # (n, m_all)
        owner = np.repeat(np.arange(k), [len(r) for r in self.regions])
        self.Wr = np.stack([W[:, owner == j].sum(1) for j in range(k)], 1)  # (n, k)
        if start is None:
            Br, self.start_misfit = self._fitted(old)
            self._check_uniform(name)
        else:
            Br = np.array(np.broadcast_to(np.asarray(start, float), (k, 3)))
            self.start_misfit = 0.0
        problem.loads[:] = [ld for ld in problem.loads if not any(ld is o for o in old)]
        self.loads = self._own_loads(W, allel, owner, name)
        lo, hi, sc = self._parametrise(Br, planes, Br_max, start is None and bool(old), name)
        self.free = free_index(self.parts, free, f"magnetisation {name!r}")
        if form == "polar" and 1 not in self.free and np.any(self.full[:, 0] == 0):
            raise DesignError(f"magnetisation {name!r}: a polar form with its angles fixed needs a non-zero start B^r "
                              f"in every region (its direction): "
                              f"{region_label(self.region_names, int(np.argmin(self.full[:, 0])))} has none")
        nf = len(self.free)
        self.norm_bounds, self.Br_max = [], Br_max
        if Br_max is not None and form == "vector":
            if nf != 3:
                raise DesignError(f"magnetisation {name!r}: a norm bound Br_max needs all three components free")
            self.norm_bounds = [(np.arange(3 * j, 3 * j + 3), float(Br_max)) for j in range(k)]
        labels = [f"{name}[{j}].{'Br' if p == 'magnitude' else p}" for j in range(k) for p in np.array(self.parts)[self.free]]
        self._setup(name, k * nf, np.tile(lo[self.free], k), np.tile(hi[self.free], k), np.tile(sc[self.free], k),
                    labels, None)
        self.assign(self.value())

    def start_excess(self):
        """The first region whose start |B^r| lies above Br_max (its magnitude held fixed there:
        before, a polar form with free = ['angle'] kept 0.143 T with Br_max = 0.1 and wrote it)."""
        m = np.linalg.norm(self.Br(), axis=1)
        over = np.nonzero(m > self.Br_max * (1 + 1e-12))[0] if self.Br_max is not None else []
        if len(over):
            j = int(over[0])
            return (f"the start B^r of {region_label(self.region_names, j)} has magnitude {m[j]:g} above Br_max = "
                    f"{self.Br_max:g} (its fixed components keep it there); lower the magnets' B^r or raise Br_max")
        return None

    def _fitted(self, old):
        """B^r per region (k, 3) fitted to the replaced magnets' nodal moments (least squares of
        lab int B^r N dA), and its relative misfit (0 when B^r was constant per region)."""
        k = len(self.regions)
        # one material in several fields (a magnet per field): each field's moments, fitted by one B^r
        moms = np.stack([mom_f for mom_f in (self._moments([ld for ld in old if ld.field is f]) for f in self.fields)])
        Br = np.linalg.lstsq(self.Wr, moms.mean(0), rcond=None)[0] if old else np.zeros((k, 3))
        err = np.sqrt(np.sum((self.Wr @ Br - moms) ** 2, axis=(0, 2)))   # per node
        mom = np.sqrt(np.sum(moms ** 2, axis=0))
        on = self.Wr > 0                                                 # (n, k): the nodes of each region
        own = on & (on.sum(1) == 1)[:, None]                             # ... and of it alone
        own[:, ~own.any(0)] = on[:, ~own.any(0)]
        self.region_misfit = np.array([np.linalg.norm(err[own[:, j]]) / max(np.linalg.norm(mom[own[:, j]]), 1e-300)
                                       for j in range(k)])
        return Br, float(np.linalg.norm(err) / max(np.linalg.norm(mom), 1e-300))

    def _moments(self, old):
        """(n, 3) the lab nodal moments int B^r N dA of the magnets ``old``."""
        mesh = self.problem.mesh
        R0 = mesh.g0[:, :3, :3]
        mom = np.zeros((mesh.n_nodes, 3))
        for ld in old:
            mom[ld.mag.nodes] += np.einsum("kij,kj->ki", R0[ld.mag.nodes], ld.mag.mu) * ld.mag.mu0 / ld.mag.h
        return mom

    def _check_uniform(self, name, rtol=1e-8):
        """DesignError when the replaced magnets' B^r is not constant over each region (the fit's
        relative misfit of the nodal moments above ``rtol``; round-off when it is), naming the region
        worst fitted on the nodes that are its alone: the design would start from, and its
        optimised scenario describe, another magnetisation than the problem's."""
        if self.start_misfit > rtol:
            j = int(np.argmax(self.region_misfit))
            where = region_label(self.region_names, j)
            raise DesignError(f"magnetisation {name!r}: the magnets' B^r varies over {where} (one B^r per region "
                              f"fits their nodal moments to a relative misfit of {self.start_misfit:.3g} > {rtol:g}, "
                              f"{self.region_misfit[j]:.3g} on {where}'s own nodes"
                              + (f"; or differs between the {len(self.fields)} fields the magnets put it in"
                                 if len(self.fields) > 1 else "") +
                              "); a design variable is one B^r per region: give regions on which B^r is uniform "
                              "(or a start B^r)")

    def _own_loads(self, W, allel, owner, name):
        """The variable's magnetic loads, one per thickness t over the regions, each with its
        C (nodes, k) * t / mu0 and its nodes' R0: mu_i = R0_i^T sum_j C_ij B^r_j."""
        problem, mesh, k = self.problem, self.problem.mesh, len(self.regions)
        R0 = mesh.g0[:, :3, :3]
        per = getattr(problem.material, "per_element", None)
        h_el = per("h") if per is not None else np.full(mesh.n_elements, float(problem.material.h))
        loads = []
        for t in np.unique(h_el[allel]):
            el = allel[h_el[allel] == t]
            Wt = W[:, np.isin(allel, el)]
            for i, field in enumerate(self.fields):                   # the material in each of its fields
                mag = Magnetisation(mesh, np.tile([1.0, 0.0, 0.0], (len(el), 1)), float(t), el, self.mu0, "element",
                                    None if self.j0 is None else self.j0[np.isin(allel, el)])
                C = np.stack([Wt[:, owner[np.isin(allel, el)] == j].sum(1) for j in range(k)], 1)[mag.nodes]
                label = f"{name} (h = {t:g})" + (f" field {i}" if len(self.fields) > 1 else "")
                loads.append((problem.add(MagneticLoad(mag, field, name=label)), C * (t / self.mu0), R0[mag.nodes]))
        return loads

    def _parametrise(self, Br, planes, Br_max, fitted, name):
        """The full parameters (``parts``, ``full``) of B^r in the variable's form and their
        lower, upper bounds and scales; a fitted B^r off the polar form's planes is refused."""
        k = len(self.regions)
        scale0 = max(float(np.abs(Br).max()), float(Br_max or 0.0)) or 1.0       # 1 T from zero (FieldVariable)
        if self.form == "vector":
            self.parts = ["x", "y", "z"]
            self.full = Br.copy()
            return np.full(3, -np.inf), np.full(3, np.inf), np.full(3, scale0)
        pl = np.asarray(planes, float)
        pl = np.broadcast_to(pl, (k, 2, 3)) if pl.shape == (2, 3) else pl
        if pl.shape != (k, 2, 3):
            raise DesignError(f"magnetisation {name!r}: planes must be one (e1, e2) or one per region ({k})")
        self.e = np.array([plane_axes(a, b, f"magnetisation {name!r}") for a, b in pl])    # (k, 2, 3)
        b1, b2 = np.einsum("ki,ki->k", Br, self.e[:, 0]), np.einsum("ki,ki->k", Br, self.e[:, 1])
        off = np.linalg.norm(Br - b1[:, None] * self.e[:, 0] - b2[:, None] * self.e[:, 1], axis=1)
        if fitted and np.any(off > 1e-9 * scale0):
            raise DesignError(f"magnetisation {name!r}: the magnets' B^r is not in the planes of the polar form")
        self.parts = ["magnitude", "angle"]
        self.full = np.stack([np.hypot(b1, b2), np.arctan2(b2, b1)], 1)
        lo, hi, sc = np.array([0.0, -np.inf]), np.array([np.inf, np.inf]), np.array([scale0, 1.0])
        if Br_max is not None:
            hi[0] = Br_max
        return lo, hi, sc

    def Br(self, full=None):
        """B^r per region (k, 3) [T] of the full parameters (default the current ones)."""
        full = self.full if full is None else full
        if self.form == "vector":
            return np.array(full, float)
        return polar_vector(full[:, 0], full[:, 1], self.e[:, 0], self.e[:, 1])[0]

    def _dBr(self):
        """dBr_j/d(full parameters of j) (k, 3, nfull)."""
        k = len(self.regions)
        if self.form == "vector":
            return np.broadcast_to(np.eye(3), (k, 3, 3))
        _, db, da = polar_vector(self.full[:, 0], self.full[:, 1], self.e[:, 0], self.e[:, 1])
        return np.stack([db, da], 2)

    def controls(self):
        return {("magnetisation", int(e)) for r in self.regions for e in r}

    def value(self):
        return self.full[:, self.free].ravel().copy()

    def assign(self, x):
        self.full = self.full.copy()
        self.full[:, self.free] = np.asarray(x, float).reshape(len(self.regions), len(self.free))
        Br = self.Br()
        for ld, C, R0 in self.loads:
            ld.mag.mu[...] = np.einsum("kji,kj->ki", R0, C @ Br)       # in place: compiled loads share it
            ld.mag.total_lab = (C @ Br).sum(0) * self.mu0

    def _blocks(self, g, lam):
        """Per load: d f / d(lab B^r contribution) blocks M_i = [A_i; -hat(a_i)] R0_i^T (k, 6, 3)."""
        out = []
        for ld, C, R0 in self.loads:
            R, a, A = field_at(ld, g, lam)
            M = np.zeros((len(ld.mag.nodes), 6, 3))
            if A is not None:
                M[:, :3] = A @ np.swapaxes(R0, 1, 2)
            M[:, 3:] = -lie.hat3(a) @ np.swapaxes(R0, 1, 2)
            out.append((ld, C, M))
        return out

    def dr_dBr(self, problem, g, lam):
        """d(r_int - f_ext)/dB^r_j (n, 6, k, 3)."""
        out = np.zeros((problem.mesh.n_nodes, 6, len(self.regions), 3))
        for ld, C, M in self._blocks(g, lam):
            out[ld.mag.nodes] -= np.einsum("ij,iab->iajb", C, M)
        return out

    def dr_dp(self, problem, g, lam):
        J = np.einsum("najb,jbc->najc", self.dr_dBr(problem, g, lam), self._dBr()[:, :, self.free])
        return J.reshape(problem.mesh.n_nodes, 6, -1)

    def vjp(self, problem, g, lam, mu):
        mu = np.asarray(mu)
        grad = np.zeros(mu.shape[:-2] + (len(self.regions), 3))
        for ld, C, M in self._blocks(g, lam):
            grad -= np.einsum("ij,iab,...ia->...jb", C, M, mu[..., ld.mag.nodes, :])
        out = np.einsum("...jb,jbc->...jc", grad, self._dBr()[:, :, self.free])
        return out.reshape(mu.shape[:-2] + (-1,))
