"""The user's Python tools (python/mfbd): simulate CLI (progress, parameters,
output selection, discard), plots, visual keys, ParaView files read back,
pictures, and a Dask sweep against direct runs."""
import subprocess
import sys
import zipfile

import numpy as np

from conftest import EXAMPLES, FMUS, ROOT, load_scene, pack, packed

sys.path.insert(0, str(ROOT / "python"))
from mfbd import run as runner  # noqa: E402
from mfbd.drawing import Drawing  # noqa: E402
from mfbd.paraview import read_series, write_series  # noqa: E402
from mfbd.plot import figure, panels  # noqa: E402
from mfbd.scene import quaternion_matrix  # noqa: E402
from mfbd.table import read_csv  # noqa: E402

SIMULATE = [sys.executable, str(EXAMPLES / "simulate.py")]


def simulate(*args):
    return subprocess.run(SIMULATE + [str(a) for a in args], capture_output=True, text=True)


def test_progress_shows_time_rate_and_eta_and_quiet_hides_it(tmp_path):
    shown = simulate(FMUS / "pendulum.fmu", "--out", tmp_path, "--stop-time", "0.5", "--no-plot")
    assert shown.returncode == 0, shown.stderr
    assert "t = 0.5/0.5 s" in shown.stderr and "real-time factor" in shown.stderr and "ETA" in shown.stderr
    quiet = simulate(FMUS / "pendulum.fmu", "--out", tmp_path, "--stop-time", "0.5", "--no-plot", "--quiet")
    assert quiet.returncode == 0 and "real-time factor" not in quiet.stderr


def test_verbose_shows_the_fmus_log_step(tmp_path):
    r = simulate(FMUS / "pendulum.fmu", "--out", tmp_path, "--stop-time", "0.02", "--no-plot", "-q", "--verbose")
    assert r.returncode == 0, r.stderr
    assert r.stderr.count("logStep") == 2  # one line per communication step (0.01 s)


def test_parameters_outputs_stop_time_and_step(tmp_path):
    r = simulate(FMUS / "pendulum.fmu", "--out", tmp_path, "-q", "--param", "angle0=0.5", "--stop-time", "0.3",
                 "--step", "0.05", "--tolerance", "1e-12", "--output", "hinge.angle", "bob.position.?", "--parquet")
    assert r.returncode == 0, r.stderr
    names, data, truncated = read_csv(tmp_path / "pendulum.csv")
    assert names == ["time", "hinge.angle", "bob.position.x", "bob.position.y", "bob.position.z"]
    assert truncated == ""
    np.testing.assert_allclose(data[:, 0], np.arange(7) * 0.05, atol=1e-15)
    assert data[0, 1] == 0.5
    assert abs(data[0, 2] - np.cos(0.5)) < 1e-12 and abs(data[0, 3] - np.sin(0.5)) < 1e-12
    import pyarrow.parquet as pq
    table = pq.read_table(tmp_path / "pendulum.parquet")
    assert table.column_names == names and table.schema.metadata[b"unit:hinge.angle"] == b"rad"


def test_bad_parameter_and_output_are_named(tmp_path):
    r = simulate(FMUS / "pendulum.fmu", "--out", tmp_path, "-q", "--param", "lenght=2")
    assert r.returncode == 1 and "lenght: no such parameter of pendulum" in r.stderr
    r = simulate(FMUS / "pendulum.fmu", "--out", tmp_path, "-q", "--output", "hinge.angel")
    assert r.returncode == 1 and "'hinge.angel' matches no output" in r.stderr


def test_discard_is_loud(tmp_path):
    scene = load_scene("pendulum")
    # Newton (generalized-alpha, not the explicit method the tolerance would
    # choose) cannot converge in one iteration to its own tolerance (given,
    # so it does not follow the error tolerance)
    scene["solver"] = {"h_max": 1e-2, "h_min": 1e-2, "max_iterations": 1, "tolerance": 1e-14,
                       "method": "generalized_alpha"}
    fmu = packed(scene, tmp_path, "discarding")
    r = simulate(fmu, "--out", tmp_path, "-q", "--stop-time", "1")
    assert r.returncode == 3
    assert "RUN TRUNCATED: fmi2Discard at t = 0 s" in r.stderr and "Newton did not converge" in r.stderr
    _, data, truncated = read_csv(tmp_path / "discarding.csv")
    assert truncated.startswith("fmi2Discard at t = 0 s") and len(data) == 1


def synthetic(values, units):
    t = np.linspace(0, 1, 201)
    return runner.Result("m", "", t, {n: f(t) for n, f in values.items()}, units, {})


def test_small_motions_get_their_own_panel_and_legends_stay_outside():
    # cantilever_vibration's tip: x stays near 1 m while y swings by 1e-4 m
    r = synthetic({"beam.node16.position.x": lambda t: 1 - 1e-8 * np.sin(9 * t) ** 2,
                   "beam.node16.position.y": lambda t: 1e-4 * np.sin(9 * t),
                   "beam.node16.position.z": lambda t: 0 * t,
                   **{f"b{k}.angle": (lambda t, k=k: k * t) for k in range(12)}},
                  {**{f"beam.node16.position.{c}": "m" for c in "xyz"}, **{f"b{k}.angle": "rad" for k in range(12)}})
    groups = [(q, u, sorted(n)) for q, u, n in panels(r, list(r.values))]
    assert ("position", "m", ["beam.node16.position.y", "beam.node16.position.z"]) in groups
    assert ("position", "m", ["beam.node16.position.x"]) in groups
    fig = figure(r)
    fig.canvas.draw()
    for ax in fig.axes:
        assert ax.get_ylabel().endswith("[m]") or ax.get_ylabel().endswith("[rad]")
        legend = ax.get_legend()
        if legend:
            assert not legend.get_window_extent().overlaps(ax.get_window_extent())
            assert len(legend.get_texts()) <= 6
    angle = [ax for ax in fig.axes if "angle" in ax.get_ylabel()][0]
    assert angle.get_legend().get_texts()[-1].get_text() == "... and 7 more (CSV)"


def run_for_drawing(fmu, stop_time):
    return runner.simulate(fmu, outputs=None, stop_time=stop_time, progress=False)


def part_points(mesh, part):
    cells = mesh.cells_dict["triangle"][mesh.cell_data["part"][0] == part]
    return mesh.points[np.unique(cells)]


def test_paraview_series_matches_the_fmu_outputs(tmp_path):
    fmu = FMUS / "flexible_slider_crank.fmu"
    result = run_for_drawing(fmu, 0.05)
    drawing = Drawing(fmu, result)
    pvd = write_series(drawing, tmp_path, every=20)
    series = read_series(pvd)
    assert [t for t, _ in series] == list(result.time[::20])
    names = [p.name for p in drawing.parts]
    slider, rod = names.index("slider"), names.index("rod[0-4]")
    v = result.values
    for (t, mesh), k in zip(series, range(0, len(result.time), 20)):
        # the slider's box is centred on its body frame
        centre = part_points(mesh, slider).mean(axis=0)
        np.testing.assert_allclose(centre, [v[f"slider.position.{c}"][k] for c in "xyz"], atol=1e-12)
        # the rod's first section ring is centred on node 0, in the node's y-z plane
        ring = mesh.points[mesh.cells_dict["triangle"][mesh.cell_data["part"][0] == rod].min():][:16]
        node0 = np.array([v[f"rod.node0.position.{c}"][k] for c in "xyz"])
        np.testing.assert_allclose(ring.mean(axis=0), node0, atol=1e-12)
        x_axis = quaternion_matrix([v[f"rod.node0.orientation.{c}"][k] for c in "wxyz"])[:, 0]
        assert np.abs((ring - node0) @ x_axis).max() < 1e-12
        assert abs(np.linalg.norm(ring - node0, axis=1).max() - 0.003) < 1e-12  # circle d = 6 mm
    # point data: the slider's velocity; cell data: element 0's section force at end 1
    t, mesh = series[-1]
    k = 20 * (len(series) - 1)
    slider_points = np.unique(mesh.cells_dict["triangle"][mesh.cell_data["part"][0] == slider])
    np.testing.assert_allclose(mesh.point_data["velocity"][slider_points],
                               np.tile([v[f"slider.velocity.{c}"][k] for c in "xyz"], (8, 1)), atol=1e-12)
    rod_cells = mesh.cell_data["part"][0] == rod
    np.testing.assert_allclose(mesh.cell_data["section_force"][0][rod_cells][0],
                               [v[f"rod.element0.end1.force.{c}"][k] for c in "xyz"], rtol=1e-12)


def test_visual_keys_are_ignored_by_the_physics_and_checked(tmp_path):
    plain = load_scene("pendulum")
    del plain["bodies"][0]["visual"]
    a = runner.simulate(packed(plain, tmp_path, "plain"), stop_time=1, progress=False)
    b = runner.simulate(FMUS / "pendulum.fmu", stop_time=1, progress=False)
    assert all(np.array_equal(a.values[n], b.values[n]) for n in a.values)
    plain["bodies"][0]["visual"] = 3
    r = pack(plain, tmp_path, "bad")
    assert r.returncode == 1 and "bodies[0].visual: expected an object" in r.stderr
    plain["bodies"][0]["visual"] = [{"shape": "sphere", "radius": "0.1*length"}, {"shape": "capsule", "radius": 0.1}]
    r = simulate(packed(plain, tmp_path, "bad_shape"), "--out", tmp_path, "-q", "--render", tmp_path / "x.png")
    assert r.returncode == 1
    assert "bodies[0].visual[1]: a capsule takes length, radius" in r.stderr and "missing ['length']" in r.stderr
    assert "output points" not in r.stdout  # refused before the run


def test_a_scene_without_exposed_poses_is_refused_by_name(tmp_path):
    r = simulate(FMUS / "cantilever_vibration.fmu", "--out", tmp_path, "-q", "--stop-time", "0.1",
                 "--vtk", tmp_path / "vtk")
    assert r.returncode == 1
    assert "nothing to draw: beam expose no pose" in r.stderr and '"nodes": "all"' in r.stderr


def tetrahedron(path):
    path.write_text("v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")


def test_mesh_file_travels_in_the_fmu_and_is_posed(tmp_path):
    scene = load_scene("pendulum")
    scene["bodies"][0]["visual"] = {"shape": "mesh", "file": "meshes/tet.obj", "position": [-0.5, 0, 0]}
    (tmp_path / "meshes").mkdir()
    tetrahedron(tmp_path / "meshes" / "tet.obj")
    fmu = packed(scene, tmp_path, "meshed")
    assert zipfile.ZipFile(fmu).read("resources/visual/tet.obj") == (tmp_path / "meshes" / "tet.obj").read_bytes()
    result = runner.simulate(fmu, stop_time=0.5, progress=False)
    points, triangles, _, _ = Drawing(fmu, result).frame(-1)
    assert len(points) == 4 and len(triangles) == 4
    v = result.values
    R = quaternion_matrix([v[f"bob.orientation.{c}"][-1] for c in "wxyz"])
    p = np.array([v[f"bob.position.{c}"][-1] for c in "xyz"])
    np.testing.assert_allclose(points[3], p + R @ [-0.5, 0, 0.1], atol=1e-12)
    scene["bodies"][0]["visual"]["file"] = "meshes/none.stl"
    r = pack(scene, tmp_path, "missing")
    assert r.returncode == 1 and "bodies[0].visual.file: mesh file 'meshes/none.stl' not found" in r.stderr


def test_render_and_animation(tmp_path):
    from PIL import Image
    r = simulate(FMUS / "pendulum.fmu", "--out", tmp_path, "-q", "--no-plot", "--stop-time", "0.2",
                 "--render", tmp_path / "frame.png", "--gif", tmp_path / "swing.gif")
    assert r.returncode == 0, r.stderr
    image = np.asarray(Image.open(tmp_path / "frame.png").convert("RGB")).astype(float)
    red = (image[..., 0] > 120) & (image[..., 1] < 90) & (image[..., 2] < 90)  # the bob, #c0392b shaded
    assert red.sum() > 100
    assert Image.open(tmp_path / "swing.gif").n_frames == 21


def test_dask_sweep_matches_direct_runs(tmp_path):
    sys.path.insert(0, str(EXAMPLES / "flexible_slider_crank"))
    from plot import midspan_deflection
    from mfbd import sweep
    fmu = FMUS / "flexible_slider_crank.fmu"
    points = sweep.samples([("E", [1e11, 2e11]), ("rod.damping", [0.0, 1e-4])])
    nodes = [0, 4, 8]
    metric = {"peak": lambda r: np.max(np.abs(midspan_deflection(r.column, nodes)))}
    rows = sweep.run_sweep(fmu, points, ["rod.node*.position.*"], stop_time=0.1, metrics=metric,
                           workers=2, progress=False)
    assert [(r["E"], r["rod.damping"]) for r in rows] == [(p["E"], p["rod.damping"]) for p in points]
    for row, p in zip(rows, points):
        direct = runner.simulate(fmu, p, ["rod.node*.position.*"], stop_time=0.1, progress=False)
        assert row["peak"] == np.max(np.abs(midspan_deflection(direct.column, nodes)))
    assert rows[0]["peak"] > rows[2]["peak"]  # the stiffer rod bends less
    sweep.write_table(rows, tmp_path / "s.csv")
    assert (tmp_path / "s.csv").read_text().splitlines()[0].startswith("E,rod.damping,peak:")


def test_sweep_command_reports_discarded_runs(tmp_path):
    scene = load_scene("pendulum")
    # Newton (generalized-alpha, not the explicit method the tolerance would
    # choose) cannot converge in one iteration to its own tolerance (given,
    # so it does not follow the error tolerance)
    scene["solver"] = {"h_max": 1e-2, "h_min": 1e-2, "max_iterations": 1, "tolerance": 1e-14,
                       "method": "generalized_alpha"}
    fmu = packed(scene, tmp_path, "discarding")
    r = subprocess.run([sys.executable, str(EXAMPLES / "sweep.py"), str(fmu), "--random", "angle0=0:1", "--samples",
                        "2", "--seed", "3", "--output", "hinge.angle", "--stop-time", "0.1", "--workers", "1",
                        "--out", str(tmp_path / "sweep"), "-q"], capture_output=True, text=True)
    assert r.returncode == 3, r.stderr
    assert "2 runs, 2 discarded" in r.stdout
    rows = (tmp_path / "sweep" / "sweep.csv").read_text().splitlines()
    assert len(rows) == 3 and all(",True,fmi2Discard at t = 0 s" in row for row in rows[1:])
    expected = np.random.default_rng(3).uniform(0, 1, 2)
    assert [float(row.split(",")[0]) for row in rows[1:]] == list(expected)


def test_runs_are_error_controlled_by_the_default_experiment_tolerance():
    # The pendulum at h_max = 0.1 s (the communication step): given the
    # DefaultExperiment's tolerance (1e-4) and stop time, the FMU controls
    # the error (Dormand-Prince); with --relative-tolerance 0, fixed
    # substeps of 0.1 s. Bob position at 2 s against the pendulum's ODE.
    from scipy.integrate import solve_ivp
    theta = solve_ivp(lambda t, y: [y[1], -9.81 * np.cos(y[0])], (0, 2.0), [0.0, 0.0], method="DOP853",
                      rtol=1e-13, atol=1e-13).y[0, -1]
    errors = {}
    for tolerance in (None, 0):
        r = runner.simulate(FMUS / "pendulum.fmu", {"solver.h_max": 0.1}, ["bob.position.x", "bob.position.y"],
                            2.0, 0.1, progress=False, relative_tolerance=tolerance)
        errors[tolerance] = np.hypot(r.values["bob.position.x"][-1] - np.cos(theta),
                                     r.values["bob.position.y"][-1] - np.sin(theta))
    assert errors[None] < 1e-3 < errors[0], errors


def test_the_last_step_ends_at_the_stop_time():
    r = runner.simulate(FMUS / "pendulum.fmu", outputs=["hinge.angle"], stop_time=1.0, step=0.3, progress=False)
    np.testing.assert_allclose(r.time, [0, 0.3, 0.6, 0.9, 1.0], atol=1e-15)
    assert r.time[-1] == 1.0
