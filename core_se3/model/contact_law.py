"""The pointwise pieces of the contact law (``model.contact``): how it is enforced
(:class:`ContactLaw`: mode, penalty, band, tolerance, step cap, starts, face samples), the C^1 ramp and its inverse,
the regularised augmented-Lagrangian normal law, the generalised nodal force and tangent of a
contact force acting on the offset face, the nodal areas, the shell's own nodal stiffness (the
penalty scale) and the contact side of each node.  Derivations in docs/CONTACT.md.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import lie
from ..assembly import Assembler
from ..fem.quadrature import shape_functions, surface_jacobian
from ..errors import did_you_mean
from .loads import curved_area
from .obstacles import contact_error

__all__ = ["ContactLaw", "as_contact_law", "MODES", "ramp", "ramp_inverse", "normal_law", "contact_wrench",
           "nodal_areas", "shell_diagonal_stiffness", "reference_sides", "E3"]

E3 = np.array([0.0, 0.0, 1.0])
MODES = ("al", "penalty")


@dataclass(frozen=True)
class ContactLaw:
    """How a contact is enforced: the numerical options of :class:`~core_se3.model.ContactLoad`
    (module docstring of ``model.contact``), one record for every obstacle that shares them.

    Parameters
    ----------
    mode : str
        'al' (augmented Lagrangian: the solver's Uzawa updates drive the gap error to ``tol``;
        default) or 'penalty' (multipliers held at k eps / 8).
    beta : float
        Penalty factor on the shell's nodal diagonal stiffness (default 1); or ``k`` directly
        [force/length^3] (a number or one per contact node).
    eps, tol : float, optional
        Band of the C^1 law and the tolerance on the gap error [length]; default 1e-6 h each.
    cap_depth : float, optional
        The Newton step cap lets a node the linearisation does not see penetrate at most this
        far in one iterate [length]; default 0.05 h.
    cold_start : float
        Start multipliers cold_start k eps / 8 in mode 'al' (a shell resting exactly on an
        obstacle is then restrained at the first iteration).
    soft_start : float
        Mode 'al': a sample that carries no force (and does not rest on the obstacle in the
        reference state) meets the penalty soft_start k; each Uzawa update at which it carries
        force multiplies its penalty by 10, up to k (a first contact of a very flexible shell
        converges; the answer does not depend on the penalty).
    faces : 'auto', True or False
        Face samples (``model.contact_faces``): the obstacle's closest point on each contact face
        carries a constraint too; 'auto': when the obstacle is curved and its inradius is below
        the largest contact element's diameter.

    A bad value is a ContactError naming its key (``param``), at construction or, for the
    defaults that scale with the thickness h, in :meth:`lengths`.

    Example
    -------
    >>> law = ContactLaw(mode="penalty", eps=0.02)
    >>> law.lengths(0.1)          # (eps, tol, cap_depth) for a shell 0.1 thick
    (0.02, 1e-07, 0.005000000000000001)
    >>> ContactLaw(mode="lagrange")
    Traceback (most recent call last):
    ...
    core_se3.errors.ContactError: contact mode must be 'al' or 'penalty', got 'lagrange'
    """
    mode: str = "al"
    beta: float = 1.0
    k: object = None
    eps: float | None = None
    tol: float | None = None
    cap_depth: float | None = None
    cold_start: float = 1e-2
    soft_start: float = 1e-2
    faces: object = "auto"

    def __post_init__(self):
        if self.mode not in MODES:
            raise contact_error(f"contact mode must be 'al' or 'penalty', got {self.mode!r}", "mode")
        soft = 1.0 if self.mode == "penalty" else float(self.soft_start)
        if not 0 < soft <= 1:
            raise contact_error(f"soft_start must lie in (0, 1], got {self.soft_start}", "soft_start")

    def lengths(self, h):
        """(eps, tol, cap_depth) [length] for a contact of thickness h: the given values, or the
        defaults 1e-6 h, 1e-6 h, 0.05 h; a ContactError unless positive and finite."""
        out = (1e-6 * h if self.eps is None else float(self.eps),
               1e-6 * h if self.tol is None else float(self.tol),
               0.05 * h if self.cap_depth is None else float(self.cap_depth))
        for key, v in zip(("eps", "tol", "cap_depth"), out):
            if not (np.isfinite(v) and v > 0):
                raise contact_error(f"contact {key} must be positive and finite, got {v}", key)
        return out

    def starts(self):
        """(multiplier start factor, soft-start factor): (1, 1) in mode 'penalty'."""
        if self.mode == "penalty":
            return 1.0, 1.0
        return float(self.cold_start), float(self.soft_start)


def as_contact_law(law):
    """A :class:`ContactLaw` from None (the defaults), a ContactLaw or a dict of its fields; an
    unknown field is a ContactError naming it (with the closest name).

    Example
    -------
    >>> as_contact_law({"mode": "penalty"}).mode, as_contact_law(None).mode
    ('penalty', 'al')
    >>> as_contact_law({"bta": 2.0})
    Traceback (most recent call last):
    ...
    core_se3.errors.ContactError: unknown contact law option 'bta'; did you mean 'beta'?
    """
    if law is None:
        return ContactLaw()
    if isinstance(law, ContactLaw):
        return law
    if not isinstance(law, dict):
        raise contact_error(f"law must be a ContactLaw or a dict of its fields, got {type(law).__name__}", "law")
    names = list(ContactLaw.__dataclass_fields__)
    for key in law:
        if key not in names:
            raise contact_error(f"unknown contact law option {key!r}{did_you_mean(key, names)}", key)
    return ContactLaw(**law)


def ramp(u, w):
    """The C^1 ramp 0 (u <= 0), u^2 / (2 w) (0 < u < w), u - w/2 (u >= w) and its derivative.

    Example
    -------
    >>> [v.tolist() for v in ramp([-1.0, 0.5, 2.0], 1.0)]
    [[0.0, 0.125, 1.5], [0.0, 0.5, 1.0]]
    """
    u = np.asarray(u, float)
    w = np.broadcast_to(np.asarray(w, float), u.shape)
    ws = np.where(w > 0, w, 1.0)
    val = np.where(u <= 0, 0.0, np.where(u < w, u * u / (2 * ws), u - w / 2))
    der = np.where(u <= 0, 0.0, np.where(u < w, u / ws, 1.0))
    return val, der


def ramp_inverse(p, w):
    """u >= 0 with ramp(u, w) = p >= 0: sqrt(2 w p) (p < w/2), p + w/2 otherwise.

    Example
    -------
    >>> ramp_inverse([0.125, 1.5], 1.0).tolist()
    [0.5, 2.0]
    """
    p = np.maximum(np.asarray(p, float), 0.0)
    w = np.broadcast_to(np.asarray(w, float), p.shape)
    return np.where(p < w / 2, np.sqrt(2 * w * p), p + w / 2)


def normal_law(d, lam, k, eps):
    """Pressure p(d) >= 0 and dp/dd of the regularised augmented-Lagrangian law,
    p = ramp(ramp_inverse(lam) - k d; k eps), so that p(0) = lam (module docstring).

    Parameters: d gaps [length], lam multipliers [force/length^2], k penalties
    [force/length^3], eps band [length] (broadcast).  Returns: (p, dp/dd).

    Example
    -------
    >>> p, dp = normal_law([0.0, -1.0], [2.0, 0.0], 1.0, 0.5)
    >>> p.tolist(), dp.tolist()
    ([2.0, 0.75], [-1.0, -1.0])
    """
    w = np.asarray(k) * eps
    p, dr = ramp(ramp_inverse(lam, w) - np.asarray(k) * np.asarray(d, float), w)
    return p, -np.asarray(k) * dr


def contact_wrench(R, c, A, n, H, p, dp):
    """Generalised nodal forces f (k, 6) and -df/deta (k, 6, 6) of the contact forces A p n acting
    at x = phi + c d3 (R (k, 3, 3) frames, c (k,) offsets [length], A (k,) areas, n (k, 3) lab
    normals, H (k, 3, 3) lab Hessians of the SDF, p (k,) pressures, dp (k,) dp/dd).

    Example
    -------
    >>> import numpy as np
    >>> f, K = contact_wrench(np.eye(3)[None], np.array([-0.5]), np.array([2.0]), np.array([[1.0, 0, 0]]),
    ...                       np.zeros((1, 3, 3)), np.array([3.0]), np.array([0.0]))
    >>> f[0].tolist()                       # 6 along x at -0.5 d3: the moment -0.5 e3 x 6 e1
    [6.0, 0.0, 0.0, 0.0, -3.0, 0.0]
    """
    Rt = np.swapaxes(R, 1, 2)
    nb = np.einsum("kij,kj->ki", Rt, n)
    Hb = Rt @ H @ R
    Fb = (A * p)[:, None] * nb
    k = len(c)
    B = np.zeros((k, 3, 6))
    B[:, :, :3] = np.eye(3)
    B[:, :, 3:] = -c[:, None, None] * lie.hat3(E3)
    Bt = np.swapaxes(B, 1, 2)
    f = np.einsum("kij,kj->ki", Bt, Fb)
    S = (A * dp)[:, None, None] * nb[:, :, None] * nb[:, None, :] + (A * p)[:, None, None] * Hb
    dF = S @ B
    dF[:, :, 3:] += lie.hat3(Fb)
    return f, -Bt @ dF


def nodal_areas(mesh, elements=None, j0=None):
    """A_i = int N_i dA over ``elements`` (default all; 2x2 Gauss, reference area) (n,): with the
    element's own area element ``j0`` (k, 4) of those elements (``loads.element_area``) on
    curved elements, as the area loads take it (``loads.curved_area``; the bilinear chords'
    area was short by sin(a/2)/(a/2) on a cylinder at a rad per element, so a contact pressure
    and a given penalty k's force were off by that), the bilinear quads' on flat ones (to the
    bit) and without ``j0``.

    Example
    -------
    >>> from core_se3 import mesh
    >>> nodal_areas(mesh.rectangle(2.0, 1.0, 2, 1)).round(12).tolist()
    [0.25, 0.5, 0.25, 0.25, 0.5, 0.25]
    """
    el = np.arange(mesh.n_elements) if elements is None else np.asarray(elements, np.int64)
    quads = mesh.quads[el]
    N, dN = shape_functions()
    jw = curved_area(surface_jacobian(mesh.X[quads], dN), j0, "contact")[0]
    w = np.einsum("qi,mq->mi", N, jw)
    return np.bincount(quads.ravel(), weights=w.ravel(), minlength=mesh.n_nodes)


def shell_diagonal_stiffness(problem, g=None):
    """K_i = tr(K_vv,ii) / 3 (n,): the mean translational diagonal of the element tangent at g
    (default the reference), the shell's own stiffness per node [force/length].

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 1, 1), Material(1e3, 0.0, 0.1))
    >>> K = shell_diagonal_stiffness(p)
    >>> K.shape, bool(K.min() > 0)
    ((4,), True)
    """
    m = problem.mesh
    ev = problem.element.evaluate(m.g0 if g is None else g, tangent=True)
    K = Assembler(m, np.ones(6 * m.n_nodes, bool)).matrix(ev.element_blocks, ev.edge_blocks, ev.node_blocks)
    return K.diagonal().reshape(-1, 6)[:, :3].mean(1)


def reference_sides(obstacle, g0, lam_ref=0.0):
    """s_i = -sign(n(X_i, lam_ref) . d3_i) (k,): +1 where the obstacle lies on the node's +d3 side.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3.model import make_obstacle
    >>> floor = make_obstacle("half_space", point=(0, 0, -1.0), normal=(0, 0, 1.0))
    >>> reference_sides(floor, np.eye(4)[None]).tolist()           # below: the -d3 face
    [-1.0]
    """
    _, n, _ = obstacle.evaluate(g0[:, :3, 3], lam_ref)
    return np.where(np.einsum("ki,ki->k", n, g0[:, :3, 2]) > 0, -1.0, 1.0)


