"""Write examples/gripper.msh: a flat cross-shaped gripper (Gmsh 2.2 ASCII, via meshio).

A square palm of side W at the origin and four fingers of length L along +x, -x, +y, -y, in
the x-y plane (normal +z), in mm.  Physical surfaces: ``palm``, ``finger_px``, ``finger_mx``,
``finger_py``, ``finger_my``; physical curves: the finger tips ``tip_px``, ``tip_mx``,
``tip_py``, ``tip_my``.  What a user would get from Gmsh with the same physical groups.

    python examples/gripper_mesh.py [n_along n_across]     (default 8 3)
"""
import os
import sys

import meshio
import numpy as np

L, W = 20.0, 6.0


def gripper(n_along=8, n_across=3):
    w, a = W / 2, W / 2 + L
    t = np.concatenate([np.linspace(-a, -w, n_along + 1)[:-1], np.linspace(-w, w, n_across + 1),
                        np.linspace(w, a, n_along + 1)[1:]])
    k = len(t)
    ids = np.arange(k * k).reshape(k, k)                       # ids[j, i] at (t_i, t_j)
    quads = np.stack([ids[:-1, :-1], ids[:-1, 1:], ids[1:, 1:], ids[1:, :-1]], -1).reshape(-1, 4)
    XX, YY = np.meshgrid(t, t)
    X = np.stack([XX.ravel(), YY.ravel(), np.zeros(XX.size)], -1)
    c = X[quads].mean(1)
    quads = quads[(np.abs(c[:, 0]) < w) | (np.abs(c[:, 1]) < w)]
    used = np.unique(quads)
    new = -np.ones(k * k, np.int64)
    new[used] = np.arange(len(used))
    X, quads = X[used], new[quads]
    c = X[quads].mean(1)
    groups = {"palm": (np.abs(c[:, 0]) < w) & (np.abs(c[:, 1]) < w),
              "finger_px": c[:, 0] > w, "finger_mx": c[:, 0] < -w,
              "finger_py": c[:, 1] > w, "finger_my": c[:, 1] < -w}
    tol = 1e-9 * a
    tips = {"tip_px": (0, a), "tip_mx": (0, -a), "tip_py": (1, a), "tip_my": (1, -a)}
    cells, phys, field_data = [], [], {}
    for tag, (name, (axis, val)) in enumerate(tips.items(), start=1):
        on = np.nonzero(np.abs(X[:, axis] - val) < tol)[0]
        on = on[np.argsort(X[on, 1 - axis])]
        cells.append(("line", np.stack([on[:-1], on[1:]], 1)))
        phys.append(np.full(len(on) - 1, tag))
        field_data[name] = np.array([tag, 1])
    for tag, (name, mask) in enumerate(groups.items(), start=len(tips) + 1):
        cells.append(("quad", quads[mask]))
        phys.append(np.full(mask.sum(), tag))
        field_data[name] = np.array([tag, 2])
    return meshio.Mesh(X, cells, cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                       field_data=field_data)


if __name__ == "__main__":
    na, nw = (int(sys.argv[1]), int(sys.argv[2])) if len(sys.argv) > 2 else (8, 3)
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "gripper.msh")
    meshio.write(path, gripper(na, nw), file_format="gmsh22", binary=False)
    print(f"wrote {path}")
