"""Write the mesh of a flat star gripper as Gmsh writes it (MSH 4.1, physical groups).

The outline is ``core_se3.mesh.star``: a regular polygon palm and N arms (fingers) of length L
and width W, in the x-y plane (normal +z), in mm, meshed into quads by Gmsh.  Physical surfaces:
``palm``, ``finger_0`` ... ``finger_{N-1}``, ``fingers``; physical curves: ``tip_0`` ... and
``tips``.  Needs the gmsh package (pip install gmsh).  The file is not overwritten unless
--force is given.

    python examples/gripper_mesh.py OUT.msh [--arms 4] [--arm-length 20] [--arm-width 6]
                                            [--palm R] [--size 1.5] [--force]

examples/star-gripper.msh was written by ``python examples/gripper_mesh.py
examples/star-gripper.msh`` (examples/star-gripper.toml uses it).  examples/gripper.msh is the
older structured cross (``mesh.cross(20, 6, 8, 3)`` written as MSH 2.2 by meshio), kept because
examples/gripper.toml reproduces the catalogue case magnetic-gripper on it.
"""
import argparse
import os
import sys

from core_se3 import mesh as M


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", help="the .msh file to write")
    ap.add_argument("--arms", type=int, default=4)
    ap.add_argument("--arm-length", type=float, default=20.0, help="mm beyond the palm")
    ap.add_argument("--arm-width", type=float, default=6.0, help="mm")
    ap.add_argument("--palm", type=float, default=None, help="circumradius of the palm polygon, mm")
    ap.add_argument("--size", type=float, default=1.5, help="target element size, mm")
    ap.add_argument("--force", action="store_true", help="overwrite OUT")
    args = ap.parse_args(argv)
    if os.path.exists(args.out) and not args.force:
        print(f"{args.out} exists: give --force to overwrite it", file=sys.stderr)
        return 2
    if M.gmsh_module() is None:
        print("this script needs the gmsh package: pip install gmsh", file=sys.stderr)
        return 2
    m = M.star(args.arms, args.arm_length, args.arm_width, palm=args.palm, size=args.size, backend="gmsh",
               save=args.out)
    print(f"wrote {args.out}: {m.n_elements} quads, regions {', '.join(sorted(m.regions))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
