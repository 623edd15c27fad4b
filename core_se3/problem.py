"""A shell problem: mesh + material + supports + loads, solved by load-stepped Newton.

    p = Problem(mesh, Material(E, nu, h))
    p.clamp("x0")
    p.add_edge_force("x1", (0, 0, P))
    result = p.solve(steps=10)

Newton (solver.py) works on the free degrees of freedom with exponential updates
g_i <- g_i exp(eta_i) (seed Algorithm 1, without its incremental strain update: strains are
recomputed from the current frames).
"""
from __future__ import annotations

import numpy as np

from . import se3
from .assembly import Assembler
from .element import DefaultElement
from .errors import LoadError, SupportError
from .loads import NodalLoad, SurfaceLoad, edge_weights
from .results import Probe

__all__ = ["Problem"]


class _Prescribed:
    """Nodes whose frames follow target(lam) on the fixed components (body-frame dofs)."""

    def __init__(self, nodes, fixed, target=None):
        self.nodes = np.asarray(nodes, np.int64)
        self.fixed = np.asarray(fixed, bool)
        self.target = target


class Problem:
    def __init__(self, mesh, material, element="default", linear_solver="auto"):
        self.mesh = mesh
        self.material = material
        if element == "default":
            self.element = DefaultElement(mesh, material)
        elif element == "seed":
            from .element_seed import SeedElement
            self.element = SeedElement(mesh, material)
        else:
            raise ValueError(f"unknown element {element!r}; choose 'default' or 'seed'")
        self.element_name = element
        self.linear_solver = linear_solver
        self.loads = []
        self.supports = []
        self.probes = {}
        self._assembler = None
        X = mesh.X
        self.length_scale = float(np.linalg.norm(X.max(0) - X.min(0))) or 1.0

    # ---------------------------------------------------------------- supports ---------
    def _nodes(self, where):
        if isinstance(where, str) or callable(where):
            nodes = self.mesh.node_set(where)
        else:
            nodes = np.atleast_1d(np.asarray(where, np.int64))
        if len(nodes) == 0:
            raise SupportError(f"node selection {where!r} is empty")
        if nodes.min() < 0 or nodes.max() >= self.mesh.n_nodes:
            raise SupportError(f"node selection {where!r} refers to nodes that do not exist")
        return nodes

    def clamp(self, where):
        """Fix position and rotation of the selected nodes at their reference values."""
        self.supports.append(_Prescribed(self._nodes(where), np.ones(6, bool)))
        self._assembler = None

    def fix(self, where, dofs):
        """Fix selected body-frame dofs (0-2 translations along d1..d3, 3-5 rotations)."""
        fixed = np.zeros(6, bool)
        fixed[list(dofs)] = True
        self.supports.append(_Prescribed(self._nodes(where), fixed))
        self._assembler = None

    def rotate_edge(self, where, axis, angle, point=(0.0, 0.0, 0.0), free=(), scale=None):
        """Rigidly rotate the selected nodes about ``axis`` through ``point`` by angle*scale(lam).

        ``free``: lab translation directions (0 = x, 1 = y, 2 = z) left free; each must stay
        aligned with a body axis of every selected node (true for rotations about a frame
        axis, e.g. a strip end twisted about the strip axis).
        """
        nodes = self._nodes(where)
        axis = np.asarray(axis, float)
        if axis.shape != (3,) or not np.all(np.isfinite(axis)) or np.linalg.norm(axis) == 0:
            raise SupportError(f"rotation axis must be a non-zero finite 3-vector, got {axis!r}")
        axis = axis / np.linalg.norm(axis)
        point = np.asarray(point, float)
        scale = scale or (lambda lam: lam)
        g0 = self.mesh.g0[nodes]
        fixed = np.ones(6, bool)
        for d in free:
            lab = np.zeros(3)
            lab[d] = 1.0
            body = np.swapaxes(g0[:, :3, :3], 1, 2) @ lab
            k = np.argmax(np.abs(body), axis=1)
            if not np.all(k == k[0]) or np.abs(body[np.arange(len(k)), k]).min() < 1 - 1e-12 \
                    or abs(abs(axis @ lab) - 1) > 1e-12 and abs(axis @ lab) > 1e-12:
                raise SupportError("a free direction must coincide with a body axis of every node "
                                   "and be parallel or perpendicular to the rotation axis")
            fixed[k[0]] = False

        def target(lam):
            Q = se3.exp_so3(angle * scale(lam) * axis)
            h = np.eye(4)
            h[:3, :3] = Q
            h[:3, 3] = point - Q @ point
            return h @ g0

        self.supports.append(_Prescribed(nodes, fixed, target))
        self._assembler = None

    def prescribe(self, where, target, fixed=(True,) * 6):
        """Selected nodes follow ``target(lam) -> (k, 4, 4)`` frames on the fixed dofs."""
        self.supports.append(_Prescribed(self._nodes(where), np.asarray(fixed, bool), target))
        self._assembler = None

    # ---------------------------------------------------------------- loads ------------
    def add_edge_force(self, where, total_force, follower=False, scale=None):
        """Total force distributed consistently along an edge (lab vector if dead; components
        in each node's frame d1, d2, d3 if follower)."""
        nodes = self._nodes(where)
        self.loads.append(NodalLoad(nodes, edge_weights(self.mesh, nodes), force=total_force,
                                    follower=follower, scale=scale, name=f"edge force {where}"))

    def add_edge_moment(self, where, total_moment, follower=False, scale=None):
        nodes = self._nodes(where)
        self.loads.append(NodalLoad(nodes, edge_weights(self.mesh, nodes), moment=total_moment,
                                    follower=follower, scale=scale, name=f"edge moment {where}"))

    def add_nodal_load(self, where, force=(0, 0, 0), moment=(0, 0, 0), follower=False, scale=None):
        """The same force and moment on each selected node."""
        nodes = self._nodes(where)
        self.loads.append(NodalLoad(nodes, np.ones(len(nodes)), force=force, moment=moment,
                                    follower=follower, scale=scale, name="nodal"))

    def add_pressure(self, p, direction=None, follower=False, scale=None, elements=None):
        """Pressure p [force/length^2]: follower -> along the current normal per current area;
        dead -> along the lab ``direction`` (default +z) per reference area."""
        if not np.isfinite(p):
            raise LoadError(f"pressure must be finite, got {p}")
        if follower:
            self.loads.append(SurfaceLoad(self.mesh, p, True, elements, scale, "follower pressure"))
        else:
            d = np.array([0, 0, 1.0]) if direction is None else np.asarray(direction, float)
            self.loads.append(SurfaceLoad(self.mesh, p * d, False, elements, scale, "dead pressure"))

    def add_body_force(self, q, scale=None, elements=None):
        """Dead force per unit reference area (e.g. gravity rho h g), lab vector."""
        self.loads.append(SurfaceLoad(self.mesh, q, False, elements, scale, "body force"))

    def add_gravity(self, rho, g=(0.0, 0.0, -9.81), elements=None, scale=None):
        """Self-weight: dead body force rho h g per unit reference area (rho [mass/length^3],
        g [length/time^2] lab vector; default SI, -z)."""
        if not (np.isfinite(rho) and rho > 0):
            raise LoadError(f"density must be positive and finite, got {rho}")
        g = np.asarray(g, float)
        self.loads.append(SurfaceLoad(self.mesh, rho * self.material.h * g, False, elements, scale, "gravity"))

    def add_magnetic(self, Br, field, elements=None, mu0=None):
        """Hard-magnetic material of residual flux density ``Br`` [T] (lab, reference
        configuration; 3-vector, per selected element, per node, or function of position) on
        ``elements`` (default all) in the applied field ``field`` (core_se3.fields): body couple
        h/mu0 B^r_t x B^a and body force h/mu0 (B^r_t . grad) B^a per unit reference area, with
        B^r_t = R_t R_0^T B^r_0 (seed E48-E50).  ``mu0`` must match the units (fields.MU0 for
        Pa; MU0 * 1e6 for N-mm-MPa).  Returns the load (its ``mag.nodes`` are the magnetised
        nodes)."""
        from .fields import MU0
        from .magnetics import Magnetisation, MagneticLoad
        mag = Magnetisation(self.mesh, Br, self.material.h, elements, MU0 if mu0 is None else mu0)
        load = MagneticLoad(mag, field)
        self.loads.append(load)
        return load

    def output_fields(self, g, lam=1.0):
        """Extra point fields for output (name -> (n, k)): magnetisation and magnetic couple and
        force per unit area, summed over the magnetic loads (empty without magnetic loads)."""
        out = {}
        for load in self.loads:
            if hasattr(load, "output_fields"):
                for k, v in load.output_fields(g, lam, self.mesh.n_nodes).items():
                    out[k] = out[k] + v if k in out else v
        return out

    def add_probe(self, name, where="x1"):
        """Record the midpoint of an edge (or a node) at every step."""
        nodes = self._nodes(where)
        self.probes[name] = Probe.edge_midpoint(name, nodes)

    # ---------------------------------------------------------------- internals --------
    def constraint_mask(self):
        fixed = np.zeros((self.mesh.n_nodes, 6), bool)
        for s in self.supports:
            fixed[s.nodes] |= s.fixed
        return fixed

    def assembler(self):
        if self._assembler is None:
            self._assembler = Assembler(self.mesh, ~self.constraint_mask().ravel())
        return self._assembler

    def prescribed_rotation(self, lam0, lam1, samples=16):
        """Largest rotation angle [rad] that a prescribed motion turns any node through between
        load factors lam0 and lam1 (path length of its rotation, sampled at ``samples``
        sub-steps): a step whose prescribed rotation nears pi is ambiguous for the exponential
        update (a turn of 2 pi lands on the same frame)."""
        worst = 0.0
        for s in self.supports:
            if s.target is None:
                continue
            prev = s.target(lam0)
            total = np.zeros(len(s.nodes))
            for t in np.linspace(lam0, lam1, samples + 1)[1:]:
                cur = s.target(t)
                total += se3.skew_rotation_angle(np.swapaxes(prev[:, :3, :3], 1, 2) @ cur[:, :3, :3])
                prev = cur
            worst = max(worst, float(total.max()))
        return worst

    def apply_prescribed(self, g, lam):
        for s in self.supports:
            if s.target is not None:
                g[s.nodes] = s.target(lam)
        return g

    def external(self, g, lam, tangent=True):
        n = self.mesh.n_nodes
        f = np.zeros((n, 6))
        Kn = np.zeros((n, 6, 6)) if tangent else None
        Ke = np.zeros((self.mesh.n_elements, 4, 4, 6, 6)) if tangent else None
        any_Ke = False
        for load in self.loads:
            fl, kn, ke = load.evaluate(g, lam, n)
            f += fl
            if tangent and kn is not None:
                Kn += kn
            if tangent and ke is not None:
                Ke[ke[0]] += ke[1]
                any_Ke = True
        return f, Kn, (Ke if any_Ke else None)

    def solve(self, steps=10, **kw):
        from .solver import newton_solve
        return newton_solve(self, steps=steps, **kw)
