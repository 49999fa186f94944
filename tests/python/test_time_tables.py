"""Tabulated time functions ({"table": [[t, value], ...]}: a C2 cubic spline
with zero end slopes, held outside) for a rigid joint drive, a driven support
of a flexible node and a load scale, each sampled from a smooth analytic
function at rest at both ends and checked against that function."""
import numpy as np
from fmpy import simulate_fmu

from conftest import load_scene, packed
from test_flexible import with_elements


def ramp(s):
    """Cycloidal ramp 0 -> 1 over s in [0, 1], at rest (zero rate and
    acceleration) at both ends; held at 0 before and 1 after."""
    s = np.clip(s, 0.0, 1.0)
    return s - np.sin(2 * np.pi * s) / (2 * np.pi)


def ramp_rate(s):
    return np.where((s > 0) & (s < 1), 1 - np.cos(2 * np.pi * s), 0.0)


def ramp_acceleration(s):
    return np.where((s > 0) & (s < 1), 2 * np.pi * np.sin(2 * np.pi * s), 0.0)


def table(amplitude, duration, points):
    t = np.linspace(0.0, duration, points)
    return {"table": [[float(ti), float(amplitude * ramp(ti / duration))] for ti in t]}


def test_table_drive_of_a_rigid_joint_gives_the_angle_and_the_torque(tmp_path):
    # Pendulum (1 kg point mass at 1 m, g = 9.81) driven through 1 rad in
    # T = 1 s: drive torque m L^2 theta'' + m g L cos(theta).
    scene = load_scene("pendulum")
    hinge = scene["joints"][0]
    hinge["drive"] = table(1.0, 1.0, 41)
    hinge["actuated"] = False
    scene["experiment"] = {"stop_time": 1.5, "output_interval": 0.01}  # between the knots too
    r = simulate_fmu(packed(scene, tmp_path), output=["hinge.angle", "hinge.angle_rate", "hinge.drive_torque"])
    t = r["time"]
    theta = ramp(t)
    # Spline errors at 40 intervals of the unit ramp: value 3e-7, rate 3e-5,
    # acceleration 1.3e-2 (tests/cpp/test_time_function.cpp orders).
    assert np.max(np.abs(r["hinge.angle"] - theta)) < 1e-6
    assert np.max(np.abs(r["hinge.angle_rate"] - ramp_rate(t))) < 1e-4
    torque = ramp_acceleration(t) + 9.81 * np.cos(theta)
    assert np.max(np.abs(r["hinge.drive_torque"] - torque)) < 2e-2
    held = t > 1.0 + 1e-9
    assert np.max(np.abs(r["hinge.drive_torque"][held] - 9.81 * np.cos(1.0))) < 1e-9


def test_table_drive_of_a_flexible_support_moves_the_beam_as_its_function(tmp_path):
    # The spin-up beam turned through 3 rad in 4 s, rest to rest: driven by
    # the expression and by a 41-point table of it; the root node follows the
    # table and the tip (in the hub frame) follows the expression's run.
    runs = {}
    expression = "3*(min(t/4, 1) - sin(2*pi*min(t/4, 1))/(2*pi))"
    for name, angle in (("expression", expression), ("table", table(3.0, 4.0, 41))):
        scene = load_scene("spin_up_beam")
        body = scene["flexible_bodies"][0]
        body["supports"][0]["angle"] = angle
        body["outputs"] = {"nodes": [0, 8]}
        outputs = ["beam.node0.orientation.w", "beam.node0.orientation.z", "beam.node0.angular_velocity.z",
                   "beam.node8.position.x", "beam.node8.position.y"]
        runs[name] = simulate_fmu(packed(scene, tmp_path, name), stop_time=5.0, output_interval=0.05, output=outputs)
    r = runs["table"]
    t = r["time"]
    hub = 3.0 * ramp(t / 4.0)
    angle = 2 * np.arctan2(r["beam.node0.orientation.z"], r["beam.node0.orientation.w"])
    # Spline errors at 40 intervals of the ramp (amplitude 3, over 4 s):
    # angle 8e-7 rad, rate 3e-5 rad/s.
    assert np.max(np.abs(angle - hub)) < 3e-6
    assert np.max(np.abs(r["beam.node0.angular_velocity.z"] - 0.75 * ramp_rate(t / 4.0))) < 1e-4

    def tip_in_hub_frame(run):
        x, y = run["beam.node8.position.x"], run["beam.node8.position.y"]
        return -np.sin(hub) * x + np.cos(hub) * y

    lag = tip_in_hub_frame(runs["expression"])
    assert np.max(np.abs(lag)) > 1.0  # the beam does bend: 1.5 m at the tip
    # The table's acceleration error (0.2 %) oscillates at the knot spacing,
    # far above the beam's first frequency (0.6 Hz): the tip sees 6e-6 of it.
    assert np.max(np.abs(tip_in_hub_frame(r) - lag)) < 1e-4 * np.max(np.abs(lag))


def test_table_load_scale_gives_the_static_deflection_of_its_function(tmp_path):
    # Static cantilever (EI = L = 1, shear-rigid), small tip load P scaled by
    # a 21-point table of the ramp: tip deflection P L^3/(3 EI) ramp(t).
    scene = with_elements(load_scene("cantilever_moment"), 8)
    P = 1e-4
    scene["flexible_bodies"][0]["loads"] = [{"node": 8, "force": [0, P, 0], "scale": table(1.0, 1.0, 21)}]
    scene["experiment"] = {"stop_time": 1.5, "output_interval": 0.01}  # between the knots too
    r = simulate_fmu(packed(scene, tmp_path), output=["beam.node8.position.y"])
    exact = P / 3.0 * ramp(r["time"])
    # Spline value error at 20 intervals: 4e-6 of the ramp; geometric
    # nonlinearity at this load: ~1e-8 relative.
    assert np.max(np.abs(r["beam.node8.position.y"] - exact)) < 1e-5 * P / 3.0
