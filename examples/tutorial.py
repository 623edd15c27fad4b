"""Tutorial: a shell problem in Python, the same problem as a scenario file, and a run that
survives an interruption.  A literate script: read it top to bottom, or run it

    python examples/tutorial.py [OUTDIR]          (default out/tutorial; ~10 s)

(tests/test_tutorial.py runs it and so keeps every statement in it true).
"""
import os
import sys

import numpy as np

from core_se3 import Material, Problem, mesh, scenario
from core_se3.scenario import runner
from core_se3.errors import ScenarioError
from core_se3.catalogue.references import elastica_entry

OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join("out", "tutorial")

# %% 1. A cantilever in Python --------------------------------------------------------------
# A strip 10 long, 1 wide, 0.1 thick (any consistent units), clamped at x = 0 and loaded by a
# dead transverse force P = 4 at x = 10 (Sze et al. 2004, s3.1).  ``mesh.rectangle`` names its
# edges x0, x1 (the ends) and y0, y1 (the sides); a probe records the midpoint of an edge.
strip = mesh.rectangle(10.0, 1.0, 16, 1)
prob = Problem(strip, Material(E=1.2e6, nu=0.0, h=0.1))
prob.clamp("x0")
prob.add_edge_force("x1", (0.0, 0.0, 4.0))           # total force, spread consistently
prob.add_probe("tip", "x1")
result = prob.solve(steps=10)                         # load factor 0 -> 1 in 10 Newton steps
u = result.final.probes["tip"]["u"]
print(f"1. tip displacement at P = 4: ux = {u[0]:.5f}, uz = {u[2]:.5f}")

# The elastica (Kirchhoff rod) master curve, in P L^2 / EI, is packaged with core_se3.  With
# EI = E w h^3 / 12 = 100 the load P = 4 is PL^2/EI = 4; the shell agrees to ~0.1 % (16 elements,
# the README's table: 0.064 % over the whole path).
ref = elastica_entry("1_cantilever_tip_force_kirchhoff")
k = int(np.argmin(np.abs(np.asarray(ref["load"]) - 4.0)))
u_ref = 10.0 * np.array([ref["tip"]["u"][k], ref["tip"]["v"][k]])
err = np.linalg.norm(np.array([u[0], u[2]]) - u_ref) / np.linalg.norm(u_ref)
print(f"   elastica: ux = {u_ref[0]:.5f}, uz = {u_ref[1]:.5f}; difference {100 * err:.3f} %")
assert err < 2e-3

# %% 2. Output for ParaView and a picture -------------------------------------------------
# VTU files live on the reference mesh with a ``displacement`` field: in ParaView open
# series.pvd and apply "Warp By Vector" (displacement, scale 1).
from core_se3 import io  # noqa: E402

io.write_series(os.path.join(OUT, "python-vtu"), strip.X, strip.quads, strip.g0,
                [s.g for s in result.steps], [s.load_factor for s in result.steps])
io.plot_shell(os.path.join(OUT, "python-shell.png"), strip.X, strip.quads, result.final.g,
              title="cantilever, P = 4")

# %% 3. The same problem as a scenario ------------------------------------------------------
# A scenario is a TOML file (docs/SCENARIOS.md); every section is checked before anything runs.
# Here it is written inline; ``scenario.load("file.toml")`` reads a file.
TEXT = """
name = "cantilever"
[mesh]
generator = "rectangle"
L = 10.0
width = 1.0
nx = 16
ny = 1
[material]
E = 1.2e6
nu = 0.0
h = 0.1
[[supports]]
type = "clamp"
edge = "x0"
[[loads]]
type = "edge_force"
edge = "x1"
force = [0.0, 0.0, 4.0]
[[probes]]
name = "tip"
edge = "x1"
[solver]
steps = 10
"""
scn = scenario.loads(TEXT, file="cantilever.toml")
print(f"3. scenario {scn.name!r}: {scn.mesh.n_elements} elements, load factors {scn.load_factors()[:3]} ...")

# ``scn.problem`` is an ordinary Problem, built from the file: solving it gives the same numbers.
same = scn.problem.solve(steps=10).final.probes["tip"]["u"]
assert np.allclose(same, u, rtol=0, atol=1e-12)

# %% 4. Errors name the file, the key and what was expected --------------------------------
try:
    scenario.loads(TEXT.replace("nu = 0.0", "nu = 0.5"), file="cantilever.toml")
except ScenarioError as exc:
    print(f"4. {exc}")
    assert exc.key == "material.nu"
try:
    scenario.loads(TEXT.replace('edge = "x1"\nforce', 'edge = "tip"\nforce'), file="cantilever.toml")
except ScenarioError as exc:
    print(f"   {exc}")
    assert exc.key == "loads[0].edge"

# %% 5. Running a scenario: results, VTU series, plots, checkpoints ------------------------
# ``runner.run`` (and ``core-se3 run cantilever.toml --out DIR`` on the command line) solves one
# load step at a time and after each converged step writes its VTU file, a checkpoint and the
# results JSON, each atomically.  Here the run is stopped after 4 steps, as if it had been
# killed, and then resumed: it continues from step 4 and ends in exactly the same state.
out = os.path.join(OUT, "cantilever")
try:
    runner.run(scn, out=out, stop_after=4, force=True)
except runner.RunInterrupted as exc:
    print(f"5. {exc}")
res = runner.run(scn, out=out, resume=True)
print(f"   resumed to load factor {res.doc['steps'][-1]['load_factor']:g}; files: {sorted(res.files)}")
# the same state as the one-go solve of section 1 to round-off (and bit for bit the state of an
# uninterrupted runner.run: tests/test_cli_run.py)
assert np.allclose(res.g, result.final.g, rtol=0, atol=1e-12)
assert np.allclose(res.doc["steps"][-1]["probes"]["tip"]["u"], u, rtol=0, atol=1e-12)

# The results document (schema core-se3-result v1) has one entry per step: the probes (u,
# rotation), Newton iterations, residuals, balance of reactions and loads.
last = res.doc["steps"][-1]
print(f"   step {last['step']}: {last['iterations']} iterations, residual {last['residual']:.1e}, "
      f"reactions balance the loads to {last['balance_error']:.1e}")
# The VTU files also carry the stress resultants at element centres: N1 (force per unit length
# on the cut normal to d1, lab vector) and M1 (moment per unit length).  Near the clamp, M1 is
# the moment of the tip force about the cut, (phi_tip - phi_c) x P.
import meshio  # noqa: E402

vtu = meshio.read(os.path.join(out, "vtu", "step_0010.vtu"))
M1 = vtu.cell_data["M1"][0][0]
g = res.g
c = g[strip.quads[0], :3, 3].mean(0)
lever = g[strip.edges["x1"], :3, 3].mean(0) - c
print(f"   M1 at the first element: {M1[1]:.4f}; statics (phi_tip - phi_c) x P: {np.cross(lever, [0, 0, 4.0])[1]:.4f}")
assert abs(M1[1] - np.cross(lever, [0, 0, 4.0])[1]) < 5e-3 * abs(M1[1])

# %% 6. A magnetic strip --------------------------------------------------------------------
# Hard-magnetic material (residual flux density Br [T], lab vector in the reference
# configuration) in an applied field (core_se3.fields).  Units N, mm, MPa, T, so mu0 = 4 pi
# 1e-7 * 1e6.  Zhao et al. 2019's beam in a perpendicular field of 5 mT bends toward the field.
from core_se3.model.fields import MU0, UniformField  # noqa: E402

beam = Problem(mesh.rectangle(17.2, 5.0, 10, 1), Material(E=0.8969, nu=0.0, h=0.42))
beam.clamp("x0")
beam.add_magnetic([0.143, 0.0, 0.0], UniformField([0.0, 0.0, 0.005]), mu0=MU0 * 1e6)
beam.add_probe("tip", "x1")
tip = beam.solve(steps=5).final.probes["tip"]
print(f"6. magnetic strip tip: uz = {tip['u'][2]:.3f} mm, rotation {np.degrees(np.linalg.norm(tip['w'])):.1f} deg")
assert tip["u"][2] > 0
# The same with a scenario: [fields.NAME] and [[magnets]] (examples/rotating-field.toml,
# examples/gripper.toml).
print(f"done: outputs in {OUT}")
