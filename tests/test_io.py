"""core_se3.io: VTU/PVD writing and PNG plots on a 2x1 quad mesh."""
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

from core_se3 import io, lie


def _rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


@pytest.fixture
def mesh():
    # 2x1 quads on [0,2]x[0,1]: nodes 0..5 row-major (3 per row)
    X = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]], float)
    quads = np.array([[0, 1, 4, 3], [1, 2, 5, 4]])
    n = len(X)
    g0 = np.tile(np.eye(4), (n, 1, 1))
    g0[:, :3, 3] = X
    a = 0.3
    R = _rot_x(a)
    t = np.array([0.1, -0.2, 0.5])
    g = np.tile(np.eye(4), (n, 1, 1))
    g[:, :3, :3] = R
    g[:, :3, 3] = X @ R.T + t
    return X, quads, g0, g, R, t, a


def test_write_vtu_roundtrip(tmp_path, mesh):
    X, quads, g0, g, R, t, a = mesh
    p = io.write_vtu(tmp_path / "sub" / "s.vtu", X, quads, g0, g, point_data={"w": X[:, 0] ** 2})
    m = meshio.read(p)
    np.testing.assert_allclose(m.points, X)
    assert len(m.cells) == 1 and m.cells[0].type == "quad"
    np.testing.assert_array_equal(m.cells[0].data, quads)
    np.testing.assert_allclose(m.point_data["displacement"], X @ R.T + t - X, atol=1e-14)
    np.testing.assert_allclose(m.point_data["d3"], np.tile(R[:, 2], (6, 1)), atol=1e-14)
    np.testing.assert_allclose(m.point_data["d1"], np.tile([1.0, 0, 0], (6, 1)), atol=1e-14)
    np.testing.assert_allclose(m.point_data["rotation_angle"], a, atol=1e-12)
    np.testing.assert_allclose(m.point_data["w"], X[:, 0] ** 2)


def test_rotation_angle_range():
    Rs = np.stack([np.eye(3), _rot_x(1e-9), _rot_x(np.pi / 2), _rot_x(np.pi), _rot_x(-2.0)])
    np.testing.assert_allclose(lie.rotation_angle(Rs), [0, 1e-9, np.pi / 2, np.pi, 2.0], atol=1e-12)


def test_write_vtu_shape_errors(tmp_path, mesh):
    X, quads, g0, g, *_ = mesh
    with pytest.raises(ValueError):
        io.write_vtu(tmp_path / "x.vtu", X, quads, g0, g[:3])
    with pytest.raises(ValueError):
        io.write_vtu(tmp_path / "x.vtu", X, quads + 10, g0, g)


def test_series_and_pvd(tmp_path, mesh):
    X, quads, g0, g, *_ = mesh
    paths = io.write_series(tmp_path / "series", X, quads, g0, [g0, g], [0.0, 1.0])
    assert [p.rsplit("/", 1)[-1] for p in paths] == ["step_0000.vtu", "step_0001.vtu", "series.pvd"]
    root = ET.parse(paths[-1]).getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    ds = root.findall("./Collection/DataSet")
    assert [d.get("file") for d in ds] == ["step_0000.vtu", "step_0001.vtu"]
    assert [float(d.get("timestep")) for d in ds] == [0.0, 1.0]
    m0 = meshio.read(paths[0])
    np.testing.assert_allclose(m0.point_data["displacement"], 0.0)


def test_series_written_again_shorter_leaves_no_old_steps(tmp_path, mesh):
    """A series of 5 steps written where one of 10 was kept step_0005 ... step_0009.vtu of the
    old run beside the new files: ParaView groups step_*.vtu as one series and showed the old
    steps as part of the new run.  They go; a file of another name stays."""
    X, quads, g0, g, *_ = mesh
    d = tmp_path / "series"
    io.write_series(d, X, quads, g0, [g] * 10, np.arange(10.0))
    (d / "notes.txt").write_text("mine")
    (d / "other_0007.vtu").write_text("mine")
    io.write_series(d, X, quads, g0, [g0] * 5, np.arange(5.0))
    assert sorted(p.name for p in d.iterdir()) == ["notes.txt", "other_0007.vtu", "series.pvd"] + [
        f"step_{k:04d}.vtu" for k in range(5)]


def test_a_series_into_a_file_is_refused_and_the_file_kept(tmp_path, mesh):
    """write_series into a path that is a user's file failed with a bare FileExistsError from
    os.makedirs; now an OptionError that names the path, the file untouched."""
    from core_se3.errors import OptionError
    X, quads, g0, g, *_ = mesh
    f = tmp_path / "results"
    f.write_text("mine")
    with pytest.raises(OptionError, match="is a file, not a directory"):
        io.write_series(f, X, quads, g0, [g], [0.0])
    assert f.read_text() == "mine"


def test_pvd_times_increase_strictly_for_paraview(tmp_path):
    """ParaView sorts a collection by its times (vtkPVDReader) and shows one data set per time:
    load factors that turn back (an arc-length path past a limit point), go negative or repeat
    were written as the times, so the states played out of order or were hidden.  Such times
    become the entries' positions; increasing ones stay the load factors."""
    def times(entries):
        p = io.write_pvd(tmp_path / "s.pvd", entries)
        return [(float(d.get("timestep")), d.get("file")) for d in ET.parse(p).getroot().iter("DataSet")]
    assert times([(0.0, "a.vtu"), (0.5, "b.vtu"), (1.0, "c.vtu")]) == [(0.0, "a.vtu"), (0.5, "b.vtu"), (1.0, "c.vtu")]
    for lam in ([0.0, -0.2, -1.0], [0.0, 0.8, 0.6, 0.9], [0.0, 0.5, 0.5]):
        got = times([(x, f"s{k}.vtu") for k, x in enumerate(lam)])
        assert got == [(float(k), f"s{k}.vtu") for k in range(len(lam))]


def test_plots_nonempty_png(tmp_path, mesh):
    X, quads, g0, g, *_ = mesh
    loads = np.linspace(0, 1, 5)
    p1 = io.plot_load_deflection(
        tmp_path / "ld.png", loads, {"w": loads**2, "u": -0.5 * loads}, labels={"w": "tip w"},
        reference={"w": (loads[::2], loads[::2] ** 2 + 0.01), "lit": ([0, 1], [0, 0.9])},
        axes=("tip displacement [mm]", "P [N]"), title="test")
    p2 = io.plot_shell(tmp_path / "shell.png", X, quads, g, title="deformed")
    for p in (p1, p2):
        data = open(p, "rb").read()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 2000


# ------------------------------------------------------------------ the plot worker ------
def _raise_value_error(message):
    raise ValueError(message)


def _png_size(path):
    from core_se3.io.plots import plot_load_deflection
    plot_load_deflection(path, [0.0, 1.0], {"uz": [0.0, 0.5]})
    return 7


def test_plot_worker_draws_and_raises_the_plots_exception(tmp_path):
    """The forked worker draws the PNG it is sent; an exception of the plot reaches the caller
    with its type and message, and no worker is left behind."""
    import os
    from core_se3.io.worker import PlotProcess
    path = tmp_path / "c.png"
    with PlotProcess() as plots:
        assert plots.pid is not None                 # a worker (Linux has fork)
        assert plots.draw(_png_size, str(path)) is None
    assert path.read_bytes()[1:4] == b"PNG"
    with PlotProcess() as plots:
        pid = plots.pid
        with pytest.raises(ValueError, match="no such axis"):
            plots.draw(_raise_value_error, "no such axis")
    with pytest.raises(ChildProcessError):           # reaped
        os.waitpid(pid, os.WNOHANG)


def test_plot_worker_unused_exits_and_unpicklable_jobs_are_drawn_here(tmp_path):
    import os
    from core_se3.io.worker import PlotProcess
    with PlotProcess() as plots:
        pid = plots.pid
    with pytest.raises(ChildProcessError):           # the unused worker ended and was reaped
        os.waitpid(pid, os.WNOHANG)
    with PlotProcess() as plots:
        assert plots.draw(lambda: 3) == 3            # a lambda does not pickle: drawn here
    with PlotProcess(enabled=False) as plots:
        assert plots.pid is None and plots.draw(_png_size, str(tmp_path / "d.png")) == 7
    assert (tmp_path / "d.png").exists()


def test_plot_worker_submit_returns_before_the_png_and_wait_collects_it(tmp_path):
    """submit() sends the job and returns; the caller's own output is written meanwhile and
    wait() returns once the PNG exists.  Without a worker the job is kept until wait(), so a
    failing plot cannot stop the caller's other output."""
    from core_se3.io.worker import PlotProcess
    path = tmp_path / "s.png"
    with PlotProcess() as plots:
        plots.submit(_png_size, str(path))
        (tmp_path / "other.json").write_text("{}")   # the caller's other output
        assert plots.wait() is None
        assert path.read_bytes()[1:4] == b"PNG"
        assert plots.wait() is None                  # nothing in flight: no-op
    with PlotProcess(enabled=False) as plots:
        plots.submit(_raise_value_error, "later")
        (tmp_path / "kept.json").write_text("{}")   # written before the plot's error
        with pytest.raises(ValueError, match="later"):
            plots.wait()
    assert (tmp_path / "kept.json").exists()


def test_a_mesh_file_error_keeps_its_advice_and_hides_the_files_text(tmp_path):
    """A quad-dominant VTU (4 quads and a triangle) in a scenario: the refusal names the other
    cells and the fix, ``triangles = "split"``, which then reads it (4 x 4 + 3 quads).  Before,
    io.files.without_contents cut every quoted passage, the reader's own advice too: '... the
    mesh also has [...] cells: ... becomes all quads with triangles = ... (... triangles=...)'.
    A quoted passage that is the file's text (a name the file holds) is still cut."""
    from core_se3 import scenario
    from core_se3.errors import ScenarioError
    X = np.array([[i * 2.5, j, 0.0] for i in range(5) for j in range(2)] + [[11.0, 0.5, 0.0]])
    quads = np.array([[2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1] for i in range(4)])
    meshio.write(tmp_path / "plate.vtu", meshio.Mesh(X, [("quad", quads), ("triangle", np.array([[8, 10, 9]]))]))
    doc = {"mesh": {"file": "plate.vtu"}, "edges": {"root": {"box": {"x": [0.0, 0.0]}}},
           "material": {"E": 1.2e6, "nu": 0.3, "h": 0.1}, "supports": [{"type": "clamp", "edge": "root"}]}
    with pytest.raises(ScenarioError) as exc:
        scenario.from_dict(doc, base_dir=str(tmp_path))
    msg = str(exc.value)
    assert "['triangle'] cells" in msg and 'triangles = "split"' in msg and "[...]" not in msg, msg
    doc["mesh"]["triangles"] = "split"
    assert scenario.from_dict(doc, base_dir=str(tmp_path)).mesh.n_elements == 4 * 4 + 3
    (tmp_path / "named.txt").write_text("a group named 'palm_secret'\n")
    assert io.without_contents("unknown group 'palm_secret'", str(tmp_path / "named.txt")) == "unknown group ..."


@pytest.mark.parametrize("kind,advice", [("run", True), ("sweep", True), ("design", False)])
def test_an_earlier_directory_is_refused_with_the_options_its_command_has(tmp_path, kind, advice):
    """A second `core-se3 design` into its own earlier --out read 'continue it with --resume,
    start over with --force, ...', but design has no --resume (argparse: unrecognized
    arguments).  Only run and sweep, which continue, are told to; all are told --force."""
    from core_se3.io.rundir import RunDirectory, RunDirectoryError
    with RunDirectory(str(tmp_path), kind).claim() as rd:
        open(rd.file("a.json"), "w").write("{}")
    with pytest.raises(RunDirectoryError) as exc:
        RunDirectory(str(tmp_path), kind).claim()
    assert ("--resume" in str(exc.value)) == advice and "--force" in str(exc.value)


def test_an_output_path_that_is_a_file_is_refused_by_name(tmp_path):
    """scenario.run(scn, out=FILE) raised a bare FileExistsError from os.makedirs (the CLI: 'cannot
    write the outputs ([Errno 17] File exists ...): the steps converged so far are kept where
    they could be written' when nothing had run).  Now a RunDirectoryError says that --out is a
    file, and the file is untouched."""
    from core_se3 import scenario
    from core_se3.io.rundir import RunDirectoryError
    scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 2, "ny": 1},
                              "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1},
                              "supports": [{"type": "clamp", "edge": "x0"}], "solver": {"steps": 1}})
    f = tmp_path / "notes.txt"
    f.write_text("mine")
    with pytest.raises(RunDirectoryError, match="is a file, not a directory"):
        scenario.run(scn, out=str(f))
    assert f.read_text() == "mine"


def test_a_cut_short_checkpoint_says_what_to_do(tmp_path):
    """A checkpoint cut to half its bytes (a copy interrupted, a full disk) was refused as
    'cannot read checkpoint ...: File is not a zip file', without the way on; now it says the
    file is damaged and how to start over."""
    from core_se3.errors import CheckpointError
    ck = io.Checkpoint(tmp_path)
    ck.save("fp", dict(step=1, lam=0.5, g=np.tile(np.eye(4), (50, 1, 1)), unwrap={}, records=[], timings={}))
    data = open(ck.path, "rb").read()
    open(ck.path, "wb").write(data[:len(data) // 2])
    with pytest.raises(CheckpointError, match=r"checkpoint\.npz: .*cut-short file.*without --resume \(and with "
                                              r"--force\) to start over"):
        ck.load("fp")
