"""OpenSeesPy 3.7.1 driver for the linear shell obstacle course (benchmarks only; run in its own
venv: ``pip install openseespy==3.7.1.2``, see /work/shared/peers/README.md).

Own script.  Reads the JSON model of ``benchmarks/obstacle_course.kratos_model`` (nodes, quads,
lab-frame fixed dofs, lab-frame nodal forces and moments, E, nu, h; ``element``: an OpenSees
4-node shell, 'ASDShellQ4' (ANS shear, EAS membrane, drilling; linear kinematics without
'-corotational') or 'ShellMITC4' (MITC4 with a Hughes-Brezzi drilling stiffness)) from stdin,
section ElasticMembranePlateSection, one linear solve; prints ``RESULT`` and the nodal
displacements (n, 3) as JSON.
"""
import json
import sys

import openseespy.opensees as ops

model_in = json.load(sys.stdin)
ops.wipe()
ops.model("basic", "-ndm", 3, "-ndf", 6)
for i, x in enumerate(model_in["X"]):
    ops.node(i + 1, *x)
ops.section("ElasticMembranePlateSection", 1, model_in["E"], model_in["nu"], model_in["h"], 0.0)
for e, q in enumerate(model_in["quads"]):
    ops.element(model_in["element"], e + 1, *[k + 1 for k in q], 1)
for i, fixed in enumerate(model_in["fixed"]):
    if any(fixed):
        ops.fix(i + 1, *[int(b) for b in fixed])
ops.timeSeries("Linear", 1)
ops.pattern("Plain", 1, 1)
for i, (f, mo) in enumerate(zip(model_in["force"], model_in["moment"])):
    if any(v != 0.0 for v in f + mo):
        ops.load(i + 1, *f, *mo)
ops.system("UmfPack")
ops.numberer("RCM")
ops.constraints("Plain")
ops.algorithm("Linear")
ops.integrator("LoadControl", 1.0)
ops.analysis("Static")
ok = ops.analyze(1)
print("RESULT " + json.dumps({"ok": ok, "u": [ops.nodeDisp(i + 1)[:3] for i in range(len(model_in["X"]))]}))
