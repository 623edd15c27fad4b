"""Sze, Liu & Lo (2004) nonlinear shell benchmarks (data only; run by ``catalogue.family_sze``).

Each case names its table in ``core_se3/data/literature.json`` (``extra["literature"]``) and
the columns it is measured against (``extra["curves"]``: column, probe, lab component, sign,
scale from table units to case units).  Measure (issue 6): the largest distance from each
computed point to the tabulated polyline in the plane (P/P_max, u/u_max), u_max = the
column's largest |value|; the maximum over the case's curves.

Geometry and supports are built by ``catalogue.family_sze`` from ``extra["shape"]``:

* ``roof`` (s3.8): cylindrical panel phi0 = (R sin t, s, R cos t), crown line t = 0.
  Quarter model (the published solutions use one): t in [0, theta], s in [0, L/2]; t = 0
  and s = 0 are symmetry planes (x = 0: u_x, rotations about y and z fixed; y = 0: u_y,
  rotations about x and z fixed), t = theta the hinged straight edge (translations fixed,
  rotations free), s = L/2 the free curved edge.  Load P/4 at the corner (0, 0, R), -z, dead.
  ``extra["model"] = "full"`` (``--set full=1``) meshes the whole roof instead (checks the
  symmetry supports).
* ``slit-annulus`` (s3.3): annulus 6..10 slit at theta = 0; edge theta = 2 pi clamped; edge
  theta = 0 carries the dead lifting line force P per unit length (total 4 P).
"""
from __future__ import annotations

from .case import Case, CaseLoad, add_case

__all__ = []

_ROOF_UNITS = dict(E="force/length^2", nu="1", h="length", R="length", L="length",
                   theta="rad", load_max="force", full="0=quarter model,1=full roof")


def _roof(name, entry, h, description, notes, mesh=(16, 16)):
    return Case(
        name=name, description=description, geometry="roof",
        params=dict(E=3102.75, nu=0.3, h=h, R=2540.0, L=508.0, theta=0.1, load_max=3000.0, full=0.0),
        units=_ROOF_UNITS, mesh=mesh, steps=60,
        loads=(CaseLoad("point_force", None, (0.0, 0.0, -1.0), lambda p: p["load_max"]),),
        load_name="P", load_unit="force", load_value=lambda p, lam: lam * p["load_max"],
        supports=(), reference=None, probe="C", notes=notes,
        extra=dict(family="sze", shape="roof", literature=entry,
                   curves=[dict(column="minus_W_C", probe="C", component=2, sign=-1.0, scale=1.0)],
                   path="arc_length", stop="table_end_displacement", dlam0=0.05, ds_max_factor=3.0),
    )


add_case(_roof(
    "sze-hinged-roof", "sze3.8a_hinged_roof", 12.7,
    "Sze et al. 2004 s3.8(a): hinged cylindrical roof (h = 12.7, isotropic) under a central point "
    "load; snap-through, traced by arc length to the end of the table (-W_C = 29.374).",
    "Reference: literature.json sze3.8a_hinged_roof (Abaqus S4R), P_max = 3000 (two sources: "
    "PENGoLINS and Kratos). Quarter model 16x16 (= 32x32 on the whole roof)."))

add_case(_roof(
    "sze-hinged-roof-6.35", "sze3.8d_hinged_roof", 6.35,
    "Sze et al. 2004 s3.8(d): the hinged roof at h = 6.35: snap-through and snap-back (the load "
    "and the deflection both reverse), arc length to the end of the table (-W_C = 38.45).",
    "Reference: literature.json sze3.8d_hinged_roof; its P_max is marked unverified there (no "
    "second source found): the curve is plotted on the scale P_max = 3000 of s3.8(a) and reported "
    "without a bar. Quarter model 32x32 (at most 40x40 on the modelled part).",
    mesh=(32, 32)))

add_case(Case(
    name="sze-slit-annular",
    description="Sze et al. 2004 s3.3: slit annular plate (6 <= r <= 10) clamped on one side of the "
                "slit and lifted by a dead line force on the other, P to 0.8 per unit length.",
    geometry="slit-annulus",
    params=dict(E=2.1e7, nu=0.0, h=0.03, r_in=6.0, r_out=10.0, load_max=0.8),
    units=dict(E="force/length^2", nu="1", h="length", r_in="length", r_out="length",
               load_max="force/length"),
    mesh=(10, 80), steps=40,
    loads=(CaseLoad("edge_force", "y0", (0.0, 0.0, 1.0), lambda p: p["load_max"]),),
    load_name="P", load_unit="force/length", load_value=lambda p, lam: lam * p["load_max"],
    supports=(("clamp", "y1"),), reference=None, probe="B",
    notes="Reference: literature.json sze3.3_slit_annular_plate (Abaqus S4R, 10x80), columns W_A "
          "(r = 6) and W_B (r = 10) on the loaded edge. Mesh 10x80 (radial x around) as the table.",
    extra=dict(family="sze", shape="slit-annulus", literature="sze3.3_slit_annular_plate",
               curves=[dict(column="W_A", probe="A", component=2, sign=1.0, scale=1.0),
                       dict(column="W_B", probe="B", component=2, sign=1.0, scale=1.0)],
               path="arc_length", stop="lam_end", dlam0=0.01, ds_max_factor=32.0,
               target_iter=8),
))

add_case(Case(
    name="sze-pullout",
    description="Sze et al. 2004 s3.5: open-ended cylinder pulled apart by two opposite radial point "
                "forces at mid-length, P to 40000 (octant model); snap-through near P/P_max = 0.5.",
    geometry="octant",
    params=dict(E=10.5e6, nu=0.3125, h=0.094, R=4.953, L=10.35, load_max=40000.0),
    units=dict(E="force/length^2", nu="1", h="length", R="length", L="length", load_max="force"),
    mesh=(36, 24), steps=40,
    loads=(CaseLoad("point_force", None, (0.0, 0.0, 1.0), lambda p: p["load_max"]),),
    load_name="P", load_unit="force", load_value=lambda p, lam: lam * p["load_max"],
    supports=(), reference=None, probe="A",
    notes="Reference: literature.json sze3.5_pullout_open_cylinder (Abaqus S4R, 24x36 on the octant). "
          "Octant t in [0, pi/2] (36 elements) x s in [0, L/2] (24): t = 0 (plane x = 0), t = pi/2 "
          "(plane z = 0) and s = L/2 (plane y = L/2) are symmetry planes, s = 0 the free end; "
          "P/4 at A = (0, L/2, R) along +z. W_A = u_z(A), -U_B = -u_x at (R, L/2, 0), "
          "-U_C = -u_x at (R, 0, 0).",
    extra=dict(family="sze", shape="pullout", literature="sze3.5_pullout_open_cylinder",
               curves=[dict(column="W_A", probe="A", component=2, sign=1.0, scale=1.0),
                       dict(column="minus_U_B", probe="B", component=0, sign=-1.0, scale=1.0),
                       dict(column="minus_U_C", probe="C", component=0, sign=-1.0, scale=1.0)],
               path="arc_length", stop="lam_end", dlam0=0.01, ds_max_factor=4.0, target_iter=6,
               psi=1.0),
))

add_case(Case(
    name="sze-pinched-cylinder",
    description="Sze et al. 2004 s3.6: cylinder on rigid end diaphragms pinched by two opposite inward "
                "radial point forces at mid-length, P to 12000 (octant model).",
    geometry="octant",
    params=dict(E=3.0e4, nu=0.3, h=1.0, R=100.0, L=200.0, load_max=12000.0, k_diaphragm=100.0,
                drilling=1.0, diaphragm_theta_axis=1.0, diaphragm_tilt=0.0),
    units=dict(E="force/length^2", nu="1", h="length", R="length", L="length", load_max="force",
               k_diaphragm="1 (diaphragm penalty stiffness / (E h))",
               drilling="1 (factor on the drilling modulus)",
               diaphragm_theta_axis="1 = the rigid diaphragm's theta_y = 0 (MacNeal-Harder; y the axis) "
                                    "as Abaqus applies it: the lab axial component of the total "
                                    "rotation vector held; 0 = rotations free (MBDyn, Elmer inputs)",
               diaphragm_tilt="1 = the normal kept normal to the ring (study; use with "
                              "diaphragm_theta_axis=0)"),
    mesh=(48, 48), steps=40,
    loads=(CaseLoad("point_force", None, (0.0, 0.0, -1.0), lambda p: p["load_max"]),),
    load_name="P", load_unit="force", load_value=lambda p, lam: lam * p["load_max"],
    supports=(), reference=None, probe="A",
    notes="Reference: literature.json sze3.6_pinched_cylinder_diaphragms (Abaqus S4R, 48x48 octant). "
          "Octant t in [0, pi/2] x s in [0, L/2]: s = 0 the rigid diaphragm u_x = u_z = theta_y = 0 "
          "(lab radial and circumferential displacement zero by penalty springs, and the lab axial "
          "component of the total rotation vector zero, core_se3.lab_supports; axial displacement "
          "free), t = 0, t = pi/2, s = L/2 symmetry planes; P/4 at A = (0, L/2, R) along -z. "
          "-W_A = -u_z(A), U_B = u_x at (R, L/2, 0). The rotation condition is the standard "
          "definition, not read in Sze's text: docs/PATHFOLLOWING.md.",
    extra=dict(family="sze", shape="pinched", literature="sze3.6_pinched_cylinder_diaphragms",
               curves=[dict(column="minus_W_A", probe="A", component=2, sign=-1.0, scale=1.0),
                       dict(column="U_B", probe="B", component=0, sign=1.0, scale=1.0)],
               path="arc_length", stop="lam_end", dlam0=0.02, ds_max_factor=4.0, target_iter=6),
))

add_case(Case(
    name="sze-hemisphere",
    description="Sze et al. 2004 s3.4: hemisphere with an 18 deg polar hole under four alternating "
                "radial point forces on the equator (quarter model), P to 400.",
    geometry="hemisphere",
    params=dict(E=6.825e7, nu=0.3, h=0.04, R=10.0, hole_deg=18.0, load_max=400.0, k_pin=100.0),
    units=dict(E="force/length^2", nu="1", h="length", R="length", hole_deg="deg", load_max="force",
               k_pin="1 (z-pin penalty stiffness / (E h))"),
    mesh=(16, 16), steps=40,
    loads=(CaseLoad("point_force", None, (1.0, 0.0, 0.0), lambda p: p["load_max"]),),
    load_name="P", load_unit="force", load_value=lambda p, lam: lam * p["load_max"],
    supports=(), reference=None, probe="A",
    notes="Reference: literature.json sze3.4_hemisphere_18deg_hole (Abaqus S4R; R and the column "
          "signs marked unverified there). Quarter model (core_se3.mesh_shapes.hemisphere_quarter): "
          "symmetry planes y = 0 and x = 0 (u_y resp. u_x and the in-plane rotations fixed), the "
          "equator node on y = 0 pinned in z by a lab-frame spring; P/2 outward (+x) at "
          "A = (R, 0, 0) and P/2 inward (-y) at B = (0, R, 0). u_A = u_x(A), -u_B = -u_y(B).",
    extra=dict(family="sze", shape="hemisphere", literature="sze3.4_hemisphere_18deg_hole",
               curves=[dict(column="u_A_outward", probe="A", component=0, sign=1.0, scale=1.0),
                       dict(column="minus_u_B_inward", probe="B", component=1, sign=-1.0, scale=1.0)],
               path="arc_length", stop="lam_end", dlam0=0.02, ds_max_factor=4.0, target_iter=6),
))
