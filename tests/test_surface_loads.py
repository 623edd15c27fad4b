"""Surface loads (pressure, body force, gravity) against their exact totals."""
import numpy as np
import pytest

from core_se3 import Material, Problem, mesh
from core_se3.errors import LoadError


def _total(problem, loads):
    """Lab total force of ``loads`` at the reference configuration (frames = identity)."""
    return sum(ld.evaluate(problem.mesh.g0, 1.0, tangent=False).f[:, :3].sum(0) for ld in loads)


@pytest.mark.parametrize("direction", [(0.0, 0.0, 2.0), (0.0, 1.0, 1.0), (0.0, 0.0, 1e-3)])
def test_a_dead_pressure_is_p_per_area_whatever_the_length_of_its_direction(direction):
    """A dead pressure p = 1 on a 2 x 1 plate along direction (0, 0, 2) gave a total 4 (twice
    p A), along (0, 1, 1) sqrt(2) p A: the direction was not normalised (rotation axes and lab
    support directions are).  The total is p A along the unit direction."""
    p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    d = np.asarray(direction) / np.linalg.norm(direction)
    assert np.allclose(_total(p, p.add_load("pressure", p=1.0, direction=direction)), 2.0 * d, rtol=1e-14)


def test_gravity_on_zero_mass_warns_naming_rho():
    """Gravity on a shell of density 0 added no load at all, silently (the run solved an unloaded
    shell: every displacement 0).  Zero stays valid (a sweep may start weightless), but the load
    that adds nothing now warns, naming rho: a LoadWarning in Python, a ScenarioWarning at
    material.rho or loads[i].rho in a scenario (an error with strict).  A positive density warns
    not, and its total is rho h g A exactly."""
    import warnings
    from core_se3 import scenario
    from core_se3.errors import LoadWarning, ScenarioError
    p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01, rho=0.0))
    with pytest.warns(LoadWarning, match="zero mass adds nothing: the material's rho") as rec:
        assert p.add_load("gravity") == []
    assert [w.filename for w in rec] == [__file__]                   # the caller's line (was 'sys', beyond it)
    with pytest.warns(LoadWarning, match="the load's rho = 0"):
        p.add_load("gravity", rho=0.0)
    with pytest.warns(LoadWarning, match="the load's rho = 0") as rec:   # the other spelling: it refused
        assert p.add_gravity(rho=0.0) == []                          # (LoadError 'must be positive')
    assert [w.filename for w in rec] == [__file__]                   # said at the caller's line
    for bad in (-1.0, np.nan, np.inf):                               # both spellings refuse these
        for add in (lambda r: p.add_gravity(rho=r), lambda r: p.add_load("gravity", rho=r)):
            with pytest.raises(LoadError, match="density must be non-negative and finite"):
                add(bad)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.allclose(_total(p, p.add_load("gravity", rho=3.0)), (0.0, 0.0, -9.81 * 3.0 * 0.01 * 2.0), rtol=1e-14)
    doc = {"units": "SI", "mesh": {"generator": "rectangle", "L": 1.0, "width": 1.0, "nx": 2, "ny": 1},
           "material": {"E": 1e6, "nu": 0.3, "h": 0.01, "rho": 0.0}, "supports": [{"type": "clamp", "edge": "x0"}],
           "loads": [{"type": "gravity"}, {"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}]}
    with pytest.warns(UserWarning):
        s = scenario.from_dict(doc)
    assert [w.key for w in s.warnings] == ["material.rho"] and "rho" in str(s.warnings[0])
    doc["loads"][0]["rho"] = 0.0
    with pytest.warns(UserWarning):
        assert [w.key for w in scenario.from_dict(doc).warnings] == ["loads[0].rho"]
    with pytest.raises(ScenarioError, match="zero mass adds nothing"):
        scenario.from_dict(doc, strict=True)


@pytest.mark.parametrize("backend_name", ["numpy", "numba"])
def test_area_loads_of_a_far_part_equal_those_of_the_part_at_the_origin(backend_name):
    """Magnet dipoles, a dead pressure and a follower pressure of a plate 1e9 from the origin
    (and a design's magnetisation weights int N_i dA) equal those of the same plate at the origin
    (the far positions an exact translation of a deformed state on a 2^-20 grid) to round-off.
    Before, the tangents a_1, a_2 summed positions of size 1e9 (eps |x| / h of them lost): dipoles
    8.9e-8 off, the residual with a dead / follower pressure 5.5e-8 / 4.5e-8 (both backends)."""
    from core_se3 import backend, lie
    from core_se3.mesh.core import Mesh
    from core_se3.model.magnetics import Magnetisation
    if backend_name == "numba" and not backend.numba_available():
        pytest.skip("no numba")
    mf = mesh.rectangle(4.0, 0.5, 8, 2, x0=1e9)
    g0 = mf.g0.copy()
    g0[:, 0, 3] -= 1e9                                       # exact (Sterbenz): the same plate at 0
    mo = Mesh(g0=g0, quads=mf.quads, edges=mf.edges, shape=mf.shape)
    a, b = Magnetisation(mf, (0.2, 0.05, 0.1), 0.01), Magnetisation(mo, (0.2, 0.05, 0.1), 0.01)
    assert np.abs(a.mu - b.mu).max() <= 1e-14 * np.abs(b.mu).max()
    from core_se3.design.magnetisation import lumping
    Wf, Wo = lumping(mf, np.arange(mf.n_elements)), lumping(mo, np.arange(mo.n_elements))
    assert np.abs(Wf - Wo).max() <= 1e-14 * Wo.max()
    g = mo.g0 @ lie.exp(np.random.default_rng(0).normal(size=(mo.n_nodes, 6)) * 0.01)
    g[:, :3, 3] = np.round(g[:, :3, 3] * 2.0 ** 20) / 2.0 ** 20     # representable at 1e9 too
    gf = g.copy()
    gf[:, 0, 3] += 1e9                                       # exact
    r = []
    for m, gm in ((mf, gf), (mo, g)):
        p = Problem(m, Material(1e3, 0.0, 0.01), backend=backend_name)
        p.add_pressure(2.0)
        p.add_pressure(3.0, follower=True)
        r.append(p.evaluate(gm, 1.0, tangent=False).r)
    assert np.abs(r[0] - r[1]).max() <= 1e-12 * np.abs(r[1]).max()


_BAD_LOAD_ARGUMENTS = [
    # a string where a number, a bool or a vector belongs: NumPy's bare TypeError / ValueError, or
    # follower="yes" taken as True (follower="no" too); now a LoadError naming the argument
    (lambda p: p.add_pressure("x"), "p must be a number"),
    (lambda p: p.add_load("pressure", p="x"), "p must be a number"),
    (lambda p: p.add_pressure(1.0, follower="yes"), "follower must be True or False"),
    (lambda p: p.add_gravity(rho="x"), "rho must be a number"),
    (lambda p: p.add_gravity(g="down"), "g must be a finite 3-vector"),
    (lambda p: p.add_body_force((1.0, 2.0)), "q must be a finite 3-vector"),
    # a bad selection: SupportError ("node ids ...") or a LoadError without the argument before
    (lambda p: p.add_edge_force([1.5], (1.0, 0.0, 0.0)), r"the selection \[1.5\] \(a line or node set name"),
    (lambda p: p.add_nodal_load(None, force=(1.0, 0.0, 0.0)), r"the selection None"),
    (lambda p: p.add_edge_force("nope", (1.0, 0.0, 0.0)), r"the selection 'nope'.*unknown node set 'nope'"),
    (lambda p: p.add_pressure(1.0, elements="x1"), r"the selection 'x1' \(a region name or element ids\)"),
]


@pytest.mark.parametrize("call, match", _BAD_LOAD_ARGUMENTS)
def test_bad_load_arguments_are_load_errors_naming_them(call, match):
    p = Problem(mesh.rectangle(1.0, 0.2, 4, 1), Material(1e6, 0.3, 0.01, rho=1000.0))
    p.clamp("x0")
    with pytest.raises(LoadError, match=match):
        call(p)
    assert not p.loads                                   # nothing half-added
