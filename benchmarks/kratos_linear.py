"""Kratos Multiphysics 10.4.0 driver for the linear shell obstacle course (benchmarks only; run
in its own venv: ``pip install KratosMultiphysics==10.4.0 KratosStructuralMechanicsApplication==10.4.0
KratosLinearSolversApplication==10.4.0``, see /work/shared/peers/README.md).

Own script.  Reads a JSON model written by ``benchmarks/obstacle_course.py`` (nodes, quads,
lab-frame fixed dofs, lab-frame nodal forces and moments -- the same nodal loads core_se3 applies
--, E, nu, h, element 'thick' or 'thin') from stdin, builds the model part, solves once with
ResidualBasedLinearStrategy (the corotational quads' tangent at the reference state is their
linear stiffness) and prints ``RESULT`` and the nodal displacements (n, 3) as JSON.
"""
import json
import sys

import KratosMultiphysics as KM
import KratosMultiphysics.StructuralMechanicsApplication as SMA
import KratosMultiphysics.LinearSolversApplication  # noqa: F401  (Eigen sparse_lu)
from KratosMultiphysics import python_linear_solver_factory as lsf

KM.Logger.GetDefaultOutput().SetSeverity(KM.Logger.Severity.WARNING)
model_in = json.load(sys.stdin)
name = {"thick": "ShellThickElementCorotational3D4N", "thin": "ShellThinElementCorotational3D4N"}[model_in["element"]]

model = KM.Model()
mp = model.CreateModelPart("Structure")
mp.SetBufferSize(2)
mp.ProcessInfo[KM.DOMAIN_SIZE] = 3
for v in (KM.DISPLACEMENT, KM.ROTATION, KM.REACTION, KM.REACTION_MOMENT, KM.VOLUME_ACCELERATION,
          SMA.POINT_LOAD, SMA.POINT_MOMENT):
    mp.AddNodalSolutionStepVariable(v)
props = mp.GetProperties()[1]
props.SetValue(KM.YOUNG_MODULUS, model_in["E"])
props.SetValue(KM.POISSON_RATIO, model_in["nu"])
props.SetValue(KM.THICKNESS, model_in["h"])
props.SetValue(KM.DENSITY, 1.0)
props.SetValue(KM.CONSTITUTIVE_LAW, SMA.LinearElasticPlaneStress2DLaw())
X = model_in["X"]
for i, x in enumerate(X):
    mp.CreateNewNode(i + 1, *x)
dofs = [(KM.DISPLACEMENT_X, KM.REACTION_X), (KM.DISPLACEMENT_Y, KM.REACTION_Y), (KM.DISPLACEMENT_Z, KM.REACTION_Z),
        (KM.ROTATION_X, KM.REACTION_MOMENT_X), (KM.ROTATION_Y, KM.REACTION_MOMENT_Y), (KM.ROTATION_Z, KM.REACTION_MOMENT_Z)]
for var, reac in dofs:
    KM.VariableUtils().AddDof(var, reac, mp)
for e, q in enumerate(model_in["quads"]):
    mp.CreateNewElement(name, e + 1, [k + 1 for k in q], props)
for i, fixed in enumerate(model_in["fixed"]):
    node = mp.GetNode(i + 1)
    for k, f in enumerate(fixed):
        if f:
            node.Fix(dofs[k][0])
c = 0
for i, (f, mo) in enumerate(zip(model_in["force"], model_in["moment"])):
    if any(abs(v) > 0 for v in f + mo):
        c += 1
        mp.CreateNewCondition("PointLoadCondition3D1N", c, [i + 1], props)
        mp.GetNode(i + 1).SetSolutionStepValue(SMA.POINT_LOAD, 0, f)
        if any(abs(v) > 0 for v in mo):
            c += 1
            mp.CreateNewCondition("PointMomentCondition3D1N", c, [i + 1], props)
            mp.GetNode(i + 1).SetSolutionStepValue(SMA.POINT_MOMENT, 0, mo)
linsol = lsf.ConstructSolver(KM.Parameters('{"solver_type": "sparse_lu"}'))
scheme = KM.ResidualBasedIncrementalUpdateStaticScheme()
bs = KM.ResidualBasedBlockBuilderAndSolver(linsol)
strategy = KM.ResidualBasedLinearStrategy(mp, scheme, bs, False, False, False, False)
strategy.Initialize()
mp.CloneTimeStep(1.0)
mp.ProcessInfo[KM.STEP] = 1
strategy.Solve()
u = [list(mp.GetNode(i + 1).GetSolutionStepValue(KM.DISPLACEMENT)) for i in range(len(X))]
print("RESULT " + json.dumps(dict(element=name, kratos_version=KM.KratosGlobals.Kernel.Version(), u=u)))
