"""Write examples/gripper.msh: a flat cross-shaped gripper (Gmsh 2.2 ASCII, via meshio).

The mesh is ``core_se3.mesh.cross``: a square palm of side W at the origin and four fingers of
length L along +x, -x, +y, -y, in the x-y plane (normal +z), in mm.  Physical surfaces: ``palm``,
``finger_px``, ``finger_mx``, ``finger_py``, ``finger_my``; physical curves: the finger tips
``tip_px``, ``tip_mx``, ``tip_py``, ``tip_my``.  What a user would get from Gmsh with the same
physical groups.

    python examples/gripper_mesh.py [n_along n_across]     (default 8 3)
"""
import os
import sys

import meshio
import numpy as np

from core_se3 import mesh as M

L, W = 20.0, 6.0


def gripper(n_along=8, n_across=3):
    m = M.cross(L, W, n_along, n_across)
    tips = [k for k in m.edges if k.startswith("tip_")]
    cells, phys, field_data = [], [], {}
    for tag, name in enumerate(tips, start=1):
        on = m.edges[name]
        cells.append(("line", np.stack([on[:-1], on[1:]], 1)))
        phys.append(np.full(len(on) - 1, tag))
        field_data[name] = np.array([tag, 1])
    for tag, name in enumerate(m.regions, start=len(tips) + 1):
        cells.append(("quad", m.quads[m.regions[name]]))
        phys.append(np.full(len(m.regions[name]), tag))
        field_data[name] = np.array([tag, 2])
    return meshio.Mesh(m.X, cells, cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                       field_data=field_data)


if __name__ == "__main__":
    na, nw = (int(sys.argv[1]), int(sys.argv[2])) if len(sys.argv) > 2 else (8, 3)
    path = sys.argv[3] if len(sys.argv) > 3 else os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                              "gripper.msh")
    meshio.write(path, gripper(na, nw), file_format="gmsh22", binary=False)
    print(f"wrote {path}")
