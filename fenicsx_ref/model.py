"""UFL/DOLFINx total-Lagrangian Naghdi (Reissner-Mindlin director) shell.

Independent of ``core_se3``: only the declarative case data are shared.  See README.md for the
equations.  The mesh is the 2-D parameter domain (s, y) in [0, L] x [-w/2, w/2]; the reference
surface phi0(s, y) is an isometric embedding (flat strip or cylinder of radius R), so the
reference metric is the identity and all surface tensors are written in the orthonormal
reference frame (t1, t2, d0) with t1 = d phi0/ds, t2 = d phi0/dy, d0 = t1 x t2.

Unknowns: displacement u (3 lab components) and a rotation vector tangent to the reference
surface, theta = beta_1 t1 + beta_2 t2 (2 unknowns).  Director d = R(theta) d0 (Rodrigues; the
map is singular at |theta| = pi, where every direction of theta gives d = -d0).
"""
from __future__ import annotations


import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

import dolfinx
import dolfinx.fem
import dolfinx.mesh

__all__ = ["ShellModel", "jit_params", "JIT_CACHE_DIR"]

#: One JIT cache for every run and every test (override with FENICSX_REF_JIT_CACHE).
from . import JIT_CACHE_DIR  # noqa: E402

# Below this value of theta.theta the Rodrigues coefficients are evaluated by their Taylor series
# (truncation error < 1e-16 there); above it the closed forms with sqrt(theta.theta).
SERIES_EPS = 1e-4


def jit_params():
    return {"cache_dir": JIT_CACHE_DIR, "cffi_extra_compile_args": ["-O2"]}


def _rodrigues_coeffs(t2):
    """(cos t, sin t / t, (1 - cos t) / t^2) as UFL expressions of t2 = t^2, series branch near 0."""
    t = ufl.sqrt(ufl.max_value(t2, SERIES_EPS))  # keeps the unused branch finite
    small = ufl.lt(t2, SERIES_EPS)
    c = ufl.conditional(small, 1 - t2 / 2 + t2 ** 2 / 24 - t2 ** 3 / 720, ufl.cos(t))
    s = ufl.conditional(small, 1 - t2 / 6 + t2 ** 2 / 120 - t2 ** 3 / 5040, ufl.sin(t) / t)
    q = ufl.conditional(small, 0.5 - t2 / 24 + t2 ** 2 / 720 - t2 ** 3 / 40320, (1 - ufl.cos(t)) / t2)
    return c, s, q


def _skew(a):
    return ufl.as_matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def rotation_matrix_np(theta):
    """NumPy Rodrigues formula (same series branch), for probes."""
    theta = np.asarray(theta, dtype=float)
    t2 = float(theta @ theta)
    if t2 < SERIES_EPS:
        c = 1 - t2 / 2 + t2 ** 2 / 24 - t2 ** 3 / 720
        s = 1 - t2 / 6 + t2 ** 2 / 120 - t2 ** 3 / 5040
        q = 0.5 - t2 / 24 + t2 ** 2 / 720 - t2 ** 3 / 40320
    else:
        t = np.sqrt(t2)
        c, s, q = np.cos(t), np.sin(t) / t, (1 - np.cos(t)) / t2
    K = np.array([[0, -theta[2], theta[1]], [theta[2], 0, -theta[0]], [-theta[1], theta[0], 0]])
    return c * np.eye(3) + s * K + q * np.outer(theta, theta)


class ShellModel:
    """Function spaces, reference geometry, energies and load forms of one run.

    Parameters
    ----------
    geometry : 'strip' | 'arch'
    length, width : parameter-domain size (arc length for the arch)
    nx, ny : elements along s and y
    cell : 'quadrilateral' (Q2) or 'triangle' (P2)
    integration : 'full' | 'psri'
    """

    def __init__(self, geometry, length, width, nx, ny, cell="quadrilateral", integration="psri",
                 degree=2, box=None):
        if geometry not in ("strip", "arch", "semicylinder"):
            raise ValueError("fenicsx_ref supports geometry 'strip', 'arch' and 'semicylinder', "
                             f"not {geometry!r}")
        if integration not in ("full", "psri"):
            raise ValueError(f"integration must be 'full' or 'psri', not {integration!r}")
        self.geometry, self.integration = geometry, integration
        self.length, self.width = float(length), float(width)
        if box is None:  # strip / arch: s in [0, L], y in [-w/2, w/2]
            box = ((0.0, -width / 2), (length, width / 2))
        self.box = tuple(tuple(float(c) for c in corner) for corner in box)
        ct = {"quadrilateral": dolfinx.mesh.CellType.quadrilateral,
              "triangle": dolfinx.mesh.CellType.triangle}[cell]
        self.mesh = dolfinx.mesh.create_rectangle(
            MPI.COMM_WORLD, [np.array(self.box[0]), np.array(self.box[1])], [nx, ny], ct)
        mesh = self.mesh
        cname = mesh.ufl_cell().cellname()
        Ue = ufl.VectorElement("Lagrange", cname, degree, dim=3)
        Be = ufl.VectorElement("Lagrange", cname, degree, dim=2)
        self.V = dolfinx.fem.FunctionSpace(mesh, ufl.MixedElement([Ue, Be]), jit_params=jit_params())
        self.w = dolfinx.fem.Function(self.V)
        self.v = ufl.TestFunction(self.V)
        self.dw = ufl.TrialFunction(self.V)
        self.u, self.beta = ufl.split(self.w)
        self.v_u, self.v_beta = ufl.split(self.v)

        c = lambda val: dolfinx.fem.Constant(mesh, PETSc.ScalarType(val))
        self._const = c
        # material and geometry as Constants: the compiled forms are shared by all parameter values
        self.E, self.nu, self.h, self.ks = c(1.0), c(0.0), c(1.0), c(1.0)
        self.R = c(1.0)
        self.lam = c(0.0)  # load factor

        x = ufl.SpatialCoordinate(mesh)
        if geometry == "strip":
            self.phi0 = ufl.as_vector([x[0], x[1], 0.0])
            self.t1 = ufl.as_vector([1.0, 0.0, 0.0])
            self.d0 = ufl.as_vector([0.0, 0.0, 1.0])
        elif geometry == "arch":  # cylinder bending in the x-z plane, clamp at the origin, centre (0, 0, R)
            a = x[0] / self.R
            self.phi0 = ufl.as_vector([self.R * ufl.sin(a), x[1], self.R * (1 - ufl.cos(a))])
            self.t1 = ufl.as_vector([ufl.cos(a), 0.0, ufl.sin(a)])
            self.d0 = ufl.as_vector([-ufl.sin(a), 0.0, ufl.cos(a)])
        else:  # semicylinder (Sze s3.7): phi0 = (R sin a, y, R cos a), a = s/R, axis = lab y
            a = x[0] / self.R
            self.phi0 = ufl.as_vector([self.R * ufl.sin(a), x[1], self.R * ufl.cos(a)])
            self.t1 = ufl.as_vector([ufl.cos(a), 0.0, -ufl.sin(a)])
            self.d0 = ufl.as_vector([ufl.sin(a), 0.0, ufl.cos(a)])  # outward normal
        self.t2 = ufl.as_vector([0.0, 1.0, 0.0])

        # kinematics
        self.theta = self.beta[0] * self.t1 + self.beta[1] * self.t2
        cth, sth, qth = _rodrigues_coeffs(ufl.dot(self.theta, self.theta))
        self.Rot = cth * ufl.Identity(3) + sth * _skew(self.theta) + qth * ufl.outer(self.theta, self.theta)
        self.d = cth * self.d0 + sth * ufl.cross(self.theta, self.d0)  # theta is orthogonal to d0
        F0 = ufl.grad(self.phi0)
        F = F0 + ufl.grad(self.u)
        self.F = F
        sym = lambda A: 0.5 * (A + A.T)
        self.eps = 0.5 * (F.T * F - F0.T * F0)
        kappa0 = (sym(F0.T * ufl.grad(self.d0)) if geometry != "strip"
                  else ufl.as_matrix([[0.0, 0.0], [0.0, 0.0]]))  # flat: grad d0 = 0
        self.kappa = sym(F.T * ufl.grad(self.d)) - kappa0
        self.gamma = F.T * self.d - F0.T * self.d0

        E, nu, h = self.E, self.nu, self.h
        A = E * h / (1 - nu ** 2)
        D = E * h ** 3 / (12 * (1 - nu ** 2))
        G = E / (2 * (1 + nu))
        tr = ufl.tr
        self.psi_m = 0.5 * A * ((1 - nu) * ufl.inner(self.eps, self.eps) + nu * tr(self.eps) ** 2)
        self.psi_b = 0.5 * D * ((1 - nu) * ufl.inner(self.kappa, self.kappa) + nu * tr(self.kappa) ** 2)
        self.psi_s = 0.5 * self.ks * G * h * ufl.dot(self.gamma, self.gamma)

        md = lambda q: {"quadrature_degree": q}
        self.dx_full = ufl.Measure("dx", domain=mesh, metadata=md(2 * degree))
        self.dx_red = ufl.Measure("dx", domain=mesh, metadata=md(degree))
        if integration == "full":
            self.Pi = (self.psi_m + self.psi_b + self.psi_s) * self.dx_full
        else:
            # PSRI (FEniCS-Shells' semi-cylinder demo): a fraction alpha = (h/h_e)^2 of the membrane
            # and shear energies fully integrated, the rest with the reduced rule.
            he = ufl.CellDiameter(mesh)
            alpha = ufl.min_value((h / he) ** 2, 1.0)
            self.Pi = (self.psi_b * self.dx_full
                       + alpha * (self.psi_m + self.psi_s) * self.dx_full
                       + (1 - alpha) * (self.psi_m + self.psi_s) * self.dx_red)

        # boundaries: x0, x1 (first coordinate at its min / max), y0, y1 (second coordinate)
        fdim = mesh.topology.dim - 1
        (xa, ya), (xb, yb) = self.box
        where = {"x0": (0, xa), "x1": (0, xb), "y0": (1, ya), "y1": (1, yb)}
        self.facets = {e: dolfinx.mesh.locate_entities_boundary(
                           mesh, fdim, lambda X, i=i, v=v: np.isclose(X[i], v))
                       for e, (i, v) in where.items()}
        self.edge_id = {"x0": 1, "x1": 2, "y0": 3, "y1": 4}
        self.edge_length = {"x0": yb - ya, "x1": yb - ya, "y0": xb - xa, "y1": xb - xa}
        self.edge_midpoint = {"x0": (xa, 0.5 * (ya + yb)), "x1": (xb, 0.5 * (ya + yb)),
                              "y0": (0.5 * (xa + xb), ya), "y1": (0.5 * (xa + xb), yb)}
        # a boundary facet lies on one edge only (corner facets are not shared)
        idx = np.hstack([self.facets[e] for e in where]).astype(np.int32)
        mark = np.hstack([np.full(len(self.facets[e]), self.edge_id[e], np.int32) for e in where])
        idx, first = np.unique(idx, return_index=True)
        mt = dolfinx.mesh.meshtags(mesh, fdim, idx, mark[first])
        self.ds = ufl.Measure("ds", domain=mesh, subdomain_data=mt, metadata=md(2 * degree))
        self.ext = []      # UFL external virtual-work terms (already multiplied by lam)
        self.point_loads = []  # (point (s, y), lab vector at lam=1)

    # -- reference geometry in NumPy (probes, prescribed values) ---------------------------------
    def frame_np(self, s):
        """(phi0 offset function, t1, t2, d0) at parameter s (the frame depends on s only)."""
        t2 = np.array([0.0, 1.0, 0.0])
        if self.geometry == "strip":
            return np.array([1.0, 0.0, 0.0]), t2, np.array([0.0, 0.0, 1.0])
        a = s / float(self.R.value)
        if self.geometry == "arch":
            return np.array([np.cos(a), 0.0, np.sin(a)]), t2, np.array([-np.sin(a), 0.0, np.cos(a)])
        return np.array([np.cos(a), 0.0, -np.sin(a)]), t2, np.array([np.sin(a), 0.0, np.cos(a)])

    def phi0_np(self, s, y):
        """Reference position of parameter points (arrays s, y) -> (n, 3)."""
        s, y = np.broadcast_arrays(np.asarray(s, float), np.asarray(y, float))
        if self.geometry == "strip":
            return np.stack([s, y, 0 * s], -1)
        R = float(self.R.value)
        a = s / R
        if self.geometry == "arch":
            return np.stack([R * np.sin(a), y, R * (1 - np.cos(a))], -1)
        return np.stack([R * np.sin(a), y, R * np.cos(a)], -1)

    # -- frames -----------------------------------------------------------------------------
    def current_frame(self):
        """Columns: R(theta) t1, R(theta) t2, d (the body frame of follower loads)."""
        return [self.Rot * self.t1, self.Rot * self.t2, self.d]

    # -- loads --------------------------------------------------------------------------------
    def add_edge_force(self, edge, direction, total, follower=False, length=None):
        """Total force ``total`` (at lam = 1) spread uniformly along ``edge``."""
        q = self._const(total / (length or self.edge_length[edge]))
        if follower:
            fr = self.current_frame()
            vec = sum(float(direction[i]) * fr[i] for i in range(3) if direction[i] != 0)
        else:
            vec = ufl.as_vector([float(a) for a in direction])
        self.ext.append(self.lam * q * ufl.dot(vec, self.v_u) * self.ds(self.edge_id[edge]))

    def add_edge_moment(self, edge, direction, total, follower=False):
        """Total moment ``total`` about lab ``direction``, spread along ``edge``.

        Virtual work m . delta(theta): exact for rotations about a fixed axis (all planar cases);
        the follower flag then changes nothing.  A component of ``direction`` along the surface
        normal (drilling) is refused: this model has no drilling rotation."""
        a = np.asarray(direction, float)
        (xa, _), (xb, _) = self.box
        ss = {"x0": [xa], "x1": [xb]}.get(edge, np.linspace(xa, xb, 65))
        normal = max(abs(a @ self.frame_np(s)[2]) for s in ss)
        if normal > 1e-12 * np.linalg.norm(a):
            raise NotImplementedError(
                f"edge moment on {edge!r} about {tuple(a)} has a component {normal:.3g} along the "
                "surface normal (a drilling moment): this 2-parameter director model has no drilling "
                "rotation and would drop it silently; use core_se3")
        m = self._const(total / self.edge_length[edge])
        vec = ufl.as_vector([float(a) for a in direction])
        dtheta = self.v_beta[0] * self.t1 + self.v_beta[1] * self.t2
        self.ext.append(self.lam * m * ufl.dot(vec, dtheta) * self.ds(self.edge_id[edge]))

    def add_pressure(self, direction, value, follower=False):
        """Pressure per unit reference area along lab ``direction`` (dead) or, if follower, along
        the current normal per unit current area (direction = body components, d3 = normal)."""
        q = self._const(value)
        if follower:
            n_da = ufl.cross(self.F[:, 0], self.F[:, 1])  # current normal * dA / dA0
            sgn = float(direction[2])
            self.ext.append(self.lam * q * sgn * ufl.dot(n_da, self.v_u) * self.dx_full)
        else:
            vec = ufl.as_vector([float(a) for a in direction])
            self.ext.append(self.lam * q * ufl.dot(vec, self.v_u) * self.dx_full)

    def add_point_force(self, point, vector):
        """Dead point force (lab vector at lam = 1) at parameter point (s, y); added to the
        assembled residual (DOLFINx has no point source)."""
        self.point_loads.append((np.asarray(point, float), np.asarray(vector, float)))

    # -- forms ----------------------------------------------------------------------------------
    def residual_and_jacobian(self):
        Fres = ufl.derivative(self.Pi, self.w, self.v)
        for term in self.ext:
            Fres = Fres - term
        J = ufl.derivative(Fres, self.w, self.dw)
        return Fres, J

    def clamp_bcs(self, edge="x0"):
        fdim = self.mesh.topology.dim - 1
        dofs = dolfinx.fem.locate_dofs_topological(self.V, fdim, self.facets[edge])
        zero = dolfinx.fem.Function(self.V)
        return [dolfinx.fem.dirichletbc(zero, dofs)]

    #: component names of ``fix`` supports -> (sub-space indices); 'rot_y' is the rotation about
    #: lab y, which is beta_2 on every geometry here (t2 = e_y).  'rot_x' only on the flat strip.
    _COMPONENTS = {"ux": (0, 0), "uy": (0, 1), "uz": (0, 2), "beta1": (1, 0), "beta2": (1, 1),
                   "rot_y": (1, 1)}

    def component_bc(self, edge, comp):
        """Dirichlet condition on one scalar component along ``edge``.

        Returns (bc, value_function, dofs_in_V, dof_coordinates) so that the caller can set
        prescribed values (value_function lives on the collapsed component space)."""
        if comp == "rot_x":
            if self.geometry != "strip":
                raise NotImplementedError("rot_x supports only on the flat strip (t1 = e_x)")
            comp = "beta1"
        if comp not in self._COMPONENTS:
            raise NotImplementedError(f"support component {comp!r}")
        i, j = self._COMPONENTS[comp]
        Vi = self.V.sub(i).sub(j)
        Vc, _ = Vi.collapse()
        fdim = self.mesh.topology.dim - 1
        dofs_V, dofs_c = dolfinx.fem.locate_dofs_topological([Vi, Vc], fdim, self.facets[edge])
        g = dolfinx.fem.Function(Vc)
        bc = dolfinx.fem.dirichletbc(g, [dofs_V, dofs_c], Vi)
        X = Vc.tabulate_dof_coordinates()[dofs_c, :2]
        return bc, g, np.asarray(dofs_V), np.asarray(dofs_c), X

    def set_params(self, E, nu, h, shear_factor=1.0, R=None):
        self.E.value, self.nu.value, self.h.value, self.ks.value = E, nu, h, shear_factor
        if R is not None:
            self.R.value = R
