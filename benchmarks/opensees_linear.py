"""OpenSeesPy 3.7.1 driver for the linear shell obstacle course (benchmarks only; run in its own
venv: ``pip install openseespy==3.7.1.2``, see /work/shared/peers/README.md).

Own script.  Reads from stdin the JSON model of ``benchmarks/obstacle_course.kratos_model``, or
a list of such models (one OpenSees process for all: ``benchmarks/peer_sweeps.py``):

* ``X`` (nodes), ``quads`` (4-node connectivity) or ``elems`` (connectivity lists of 4 or 9
  nodes; a 9-node list: the corners counter-clockwise, the mid-side nodes from the first edge
  (corner 1-2) on, the centre -- OpenSees' ShellMITC9 order, checked by the patch tests of
  ``peer_sweeps.py``);
* lab-frame ``fixed`` dofs (n, 6), optional ``disp`` (n, 6): the values of the fixed dofs
  (prescribed displacements and rotations, for the patch tests; without it they are held at 0);
* lab-frame nodal ``force`` and ``moment``; E, nu, h;
* ``element``, an OpenSees shell: 'ASDShellQ4' (ANS shear, EAS membrane, drilling; linear
  kinematics without '-corotational'), 'ShellMITC4' (MITC4 with a Hughes-Brezzi drilling
  stiffness), 'ShellDKGQ' / 'ShellNLDKGQ' (DKQ plate bending with the generalized-conforming
  GQ12 membrane with drilling; NL: its updated-Lagrangian version, here one linear step),
  'ShellMITC9' (9 nodes, Bucalem and Bathe's MITC9).

Section ElasticMembranePlateSection, one linear solve per model; prints one line
``RESULT {"ok", "u": nodal displacements (n, 3), "t_solve": seconds of the build and solve}``
per model, in order.
"""
import json
import sys
import time

import openseespy.opensees as ops


def solve(m):
    """Build and solve one model; the RESULT dict."""
    t = time.perf_counter()
    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    for i, x in enumerate(m["X"]):
        ops.node(i + 1, *x)
    ops.section("ElasticMembranePlateSection", 1, m["E"], m["nu"], m["h"], 0.0)
    for e, q in enumerate(m.get("elems", m.get("quads"))):
        ops.element(m["element"], e + 1, *[k + 1 for k in q], 1)
    for i, fixed in enumerate(m["fixed"]):
        if any(fixed) and "disp" not in m:
            ops.fix(i + 1, *[int(b) for b in fixed])
    ops.timeSeries("Linear", 1)
    ops.pattern("Plain", 1, 1)
    for i, (f, mo) in enumerate(zip(m["force"], m["moment"])):
        if any(v != 0.0 for v in f + mo):
            ops.load(i + 1, *f, *mo)
    for i, (fixed, d) in enumerate(zip(m["fixed"], m.get("disp", ()))):   # prescribed values
        for a in range(6):
            if fixed[a]:
                ops.sp(i + 1, a + 1, d[a])
    ops.system("UmfPack")
    ops.numberer("RCM")
    ops.constraints("Transformation" if "disp" in m else "Plain")
    ops.algorithm("Linear")
    ops.integrator("LoadControl", 1.0)
    ops.analysis("Static")
    ok = ops.analyze(1)
    u = [ops.nodeDisp(i + 1) for i in range(len(m["X"]))]
    return {"ok": ok, "u": [d[:3] for d in u], "rot": [d[3:] for d in u], "t_solve": time.perf_counter() - t}


models = json.load(sys.stdin)
for model in (models if isinstance(models, list) else [models]):
    print("RESULT " + json.dumps(solve(model)), flush=True)
