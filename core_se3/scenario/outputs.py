"""Outputs of a scenario run: the VTU point and cell fields, the physical loads of a step, the
unit system record, the probe plot (probes.png) and the picture of the shell (shell.png)."""
from __future__ import annotations

import os

import numpy as np

from ..io import atomic_path
from .obstacles import obstacles_of
from .units import UNIT_SYSTEMS, describe_units, physical_loads

__all__ = ["physical_record", "unit_system_record", "plot_probes", "picture", "point_fields", "cell_fields"]


def point_fields(prob, g, lam=1.0):
    """Extra VTU point fields of the problem's loads (magnetisation, magnetic couple, ...).

    Parameters: prob (Problem), g (n, 4, 4), lam.  Returns: name -> (n, k) array (empty without
    such loads).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import UniformField
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> _ = p.add_magnetic(Br=(0.1, 0.0, 0.0), field=UniformField((0.0, 0.0, 0.01)))
    >>> sorted(point_fields(p, p.mesh.g0))
    ['magnetic_couple', 'magnetic_force', 'magnetisation_Br']
    """
    return {k: np.asarray(v) for k, v in prob.output_fields(g, lam).items()}


def cell_fields(prob, g):
    """VTU cell fields of the element (stress resultants at the element centres).

    Parameters: prob (Problem), g (n, 4, 4).  Returns: name -> (m, 3) array.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> {k: v.shape for k, v in cell_fields(p, p.mesh.g0).items() if k in ("N1", "M2")}
    {'N1': (2, 3), 'M2': (2, 3)}
    """
    return prob.element.cell_fields(g)


def physical_record(scn, lam):
    """The physical value of every load and field at load factor lam: name -> {value, unit}
    (``scenario.units.physical_loads``), as step records carry it beside the load factor.

    Example
    -------
    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 2, "ny": 1},
    ...     "units": "SI", "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
    ...     "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 2.0]}]})
    >>> physical_record(scn, 0.25)
    {'loads[0].force': {'value': 0.5, 'unit': 'N'}}
    """
    return {k: dict(value=v, unit=u) for k, (v, u) in physical_loads(scn.spec, lam).items()}


def unit_system_record(units):
    """The unit system of a run (results.json ``unit_system``): name, length, force, ... units.

    Example
    -------
    >>> unit_system_record("SI")["length"], unit_system_record("")["name"]
    ('m', '')
    """
    u = UNIT_SYSTEMS.get(units, {})
    return dict(name=units, **{k: u[k] for k in ("length", "force", "stress", "moment", "density",
                                                  "acceleration", "field") if k in u},
                mu0=u.get("mu0"), description=describe_units(units))


def plot_probes(path, doc):
    """Load factor against the displacement components of every probe (one PNG), with the
    physical value of the first field or load (its name and unit) on the right-hand axis.

    Components that stay ~0 along the path are left out.  Parameters: path (written
    atomically), doc (a results document whose steps have probes).  Returns: the path.

    Example
    -------
    >>> import os, tempfile
    >>> doc = {"case": "demo", "steps": [{"load_factor": x, "probes": {"tip": {"u": [0.0, 0.0, x]}}} for x in (0.0, 1.0)]}
    >>> os.path.basename(plot_probes(os.path.join(tempfile.mkdtemp(), "probes.png"), doc))
    'probes.png'
    """
    from ..io import plot_load_deflection
    lam = np.array([s["load_factor"] for s in doc["steps"]])
    disp = {}
    us = {name: np.array([s["probes"][name]["u"] for s in doc["steps"]]) for name in doc["steps"][0]["probes"]}
    big = max([np.abs(u).max() for u in us.values()] + [0.0])
    for name, u in us.items():
        for i, c in enumerate("xyz"):
            if np.abs(u[:, i]).max() > 1e-9 * big:          # leave out components that stay ~0
                disp[f"{name}.u{c}"] = u[:, i]
    length = {"N-mm-MPa": "mm", "SI": "m"}.get(doc.get("units"), "length unit")
    secondary = None
    phys = [s.get("physical") or {} for s in doc["steps"]]
    if phys and phys[-1]:
        name = next(iter(phys[-1]))             # the first field or load
        unit = phys[-1][name]["unit"]
        secondary = (f"{name}" + (f" [{unit}]" if unit else ""),
                     [p.get(name, {}).get("value", np.nan) for p in phys])
    with atomic_path(path) as tmp:
        plot_load_deflection(tmp, lam, disp, axes=(f"probe displacement [{length}]", "load factor"),
                             title=doc["case"], secondary=secondary)
    return path


def picture(path, scn, g, title=None, records=None, vtu_dir=None):
    """PNG of the deformed shell (matplotlib 3-D, reference outline dotted): the final state
    coloured by rotation angle, or, with [output] picture_steps = k > 1, k states of the path
    (read back from the VTU files, so also after a resume) overlaid.

    Parameters: path (written atomically); scn (mesh, [output] view and picture_steps); g
    (n, 4, 4) the final state; title (default the scenario's name); records, vtu_dir (for
    several states).  Returns: the path.

    Example
    -------
    >>> import os, tempfile
    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 1.0, "width": 1.0, "nx": 2, "ny": 1},
    ...     "material": {"E": 1e3, "nu": 0.0, "h": 0.01}, "supports": [{"type": "clamp", "edge": "x0"}]})
    >>> os.path.getsize(picture(os.path.join(tempfile.mkdtemp(), "shell.png"), scn, scn.mesh.g0)) > 0
    True
    """
    from ..io import plot_sequence, plot_shell
    m = scn.mesh
    o = scn.output
    k = o.get("picture_steps", 1)
    view = tuple((list(o.get("view") or (20.0, -60.0)) + [0.0])[:3])       # elev, azim, roll
    with atomic_path(path) as tmp:
        if k > 1 and records and vtu_dir:
            import meshio
            have = [r for r in records
                    if os.path.exists(os.path.join(vtu_dir, f"step_{r['step']:04d}.vtu"))]
            pick = sorted({int(round(i)) for i in np.linspace(0, len(have) - 1, min(k, len(have)))})
            pos, labels = [], []
            for i in pick:
                r = have[i]
                v = meshio.read(os.path.join(vtu_dir, f"step_{r['step']:04d}.vtu"))
                pos.append(v.points + v.point_data["displacement"])
                labels.append(f"load factor {r['load_factor']:.3g}")
            plot_sequence(tmp, m.X, m.quads, pos, labels, title=title or scn.name, view=view)
        else:
            from ..io import obstacle_surfaces
            lam = records[-1]["load_factor"] if records else 1.0
            plot_shell(tmp, m.X, m.quads, g, title=title or scn.name, view=view,
                       surfaces=obstacle_surfaces(obstacles_of(scn.problem), g[:, :3, 3], lam))
    return path
