"""The pendulum through fmpy, against closed-form and published references
(shared/benchmarks R1 and the large-amplitude period)."""
import numpy as np
from fmpy import simulate_fmu
from scipy.special import ellipk

from conftest import Slave

G, L, M = 9.81, 1.0, 1.0


def crossings(t, y, direction):
    """Times where y crosses zero upwards (+1) or downwards (-1), interpolated linearly."""
    i = np.nonzero((np.sign(y[:-1]) == -direction) & (np.sign(y[1:]) == direction))[0]
    return t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])


def test_large_amplitude_period_from_170_degrees(pendulum_fmu):
    theta0 = np.radians(170.0)  # from hanging straight down
    exact = 4.0 * np.sqrt(L / G) * ellipk(np.sin(theta0 / 2.0) ** 2)  # scipy's K takes m = k^2
    # The design configuration is horizontal: 170 degrees from down is 80 above it.
    result = simulate_fmu(pendulum_fmu, stop_time=2.3 * exact, output_interval=1e-3,
                          start_values={"angle0": np.radians(80.0), "solver.h_max": 1e-4},
                          output=["hinge.angle_rate"])
    # The rate turns from + to - at the top of every swing: once per period.
    tops = crossings(result["time"], result["hinge.angle_rate"], -1)
    assert len(tops) >= 2
    periods = np.diff(tops)
    assert np.all(np.abs(periods / exact - 1.0) < 1e-5), (periods, exact)


def test_iftomm_pendulum_position_at_10s(pendulum_fmu):
    # R1 in shared/benchmarks: released from horizontal at rest.
    result = simulate_fmu(pendulum_fmu, stop_time=10.0, output_interval=0.01,
                          start_values={"solver.h_max": 1e-4},
                          output=["bob.position.x", "bob.position.y"])
    assert abs(result["time"][-1] - 10.0) < 1e-12
    assert abs(result["bob.position.x"][-1] - 0.275087462576) < 1e-6
    assert abs(result["bob.position.y"][-1] - (-0.961419205099)) < 1e-6


def test_reaction_force_along_the_rod_at_every_output_point(pendulum_fmu):
    result = simulate_fmu(pendulum_fmu, stop_time=5.0, output_interval=0.01,
                          output=["hinge.angle", "hinge.angle_rate", "hinge.reaction_force.x",
                                  "hinge.reaction_force.y", "hinge.reaction_force.z", "hinge.reaction_torque.z"])
    theta = result["hinge.angle"] + np.pi / 2.0  # from hanging down
    tension = M * (G * np.cos(theta) + L * result["hinge.angle_rate"] ** 2)
    # Force of the pivot on the bob in the child marker frame, whose x axis
    # points from the pivot to the bob: the rod pulls along -x.
    assert np.max(np.abs(-result["hinge.reaction_force.x"] - tension)) < 1e-6 * M * G
    assert np.max(np.abs(result["hinge.reaction_force.y"])) < 1e-6 * M * G  # point mass, no torque
    assert np.max(np.abs(result["hinge.reaction_force.z"])) < 1e-6 * M * G
    assert np.max(np.abs(tension)) > 2.9 * M * G  # 3 m g at the bottom: the check saw the swing


def test_input_torque_holds_the_pendulum_horizontal(slave):
    # A joint torque m g L balances gravity at the horizontal start exactly.
    slave.start({"hinge.torque": M * G * L})
    for k in range(100):
        assert slave.step(k * 0.01, 0.01) == 0
    assert abs(slave.get("hinge.angle")) < 1e-12
    assert abs(slave.get("hinge.reaction_torque.z") - M * G * L) < 1e-9


def test_tunable_damping_sets_the_decay_rate(pendulum_fmu):
    # Small oscillations about hanging down: theta'' + c/(m L^2) theta' + g/L theta = 0,
    # amplitude ~ exp(-c t / (2 m L^2)). Damping is switched on mid-run (tunable).
    c = 0.2
    s = Slave(pendulum_fmu)
    try:
        s.start({"angle0": -np.pi / 2 + 1e-3, "solver.h_max": 1e-3})
        t, h = 0.0, 1e-3
        for _ in range(1000):
            assert s.step(t, h) == 0
            t += h
        assert s.set("hinge.damping", c) == 0
        times, angles = [], []
        for _ in range(8000):
            assert s.step(t, h) == 0
            t += h
            times.append(t)
            angles.append(s.get("hinge.angle") + np.pi / 2)
        times, angles = np.array(times), np.array(angles)
        peaks = [i for i in range(1, len(angles) - 1) if angles[i - 1] < angles[i] >= angles[i + 1]]
        rate = -np.polyfit(times[peaks], np.log(angles[peaks]), 1)[0]
        assert abs(rate / (c / (2 * M * L * L)) - 1.0) < 2e-3, rate
    finally:
        s.free()


def test_orientation_and_angular_velocity_outputs(pendulum_fmu):
    # A rotation by the hinge angle about world z: q = (cos(a/2), 0, 0, sin(a/2)) up
    # to one sign, kept continuous between communication points.
    result = simulate_fmu(pendulum_fmu, stop_time=3.0, output_interval=0.01,
                          output=["hinge.angle", "hinge.angle_rate", "bob.orientation.w", "bob.orientation.x",
                                  "bob.orientation.y", "bob.orientation.z", "bob.angular_velocity.z",
                                  "bob.velocity.x", "bob.velocity.y", "bob.position.x", "bob.position.y"])
    a = result["hinge.angle"]
    q = np.column_stack([result[f"bob.orientation.{c}"] for c in "wxyz"])
    expected = np.column_stack([np.cos(a / 2), 0 * a, 0 * a, np.sin(a / 2)])
    sign = np.sign(np.sum(q * expected, axis=1))
    assert np.all(sign == sign[0])  # continuous: no flips
    assert np.max(np.abs(q - sign[:, None] * expected)) < 1e-12
    assert np.max(np.abs(result["bob.angular_velocity.z"] - result["hinge.angle_rate"])) < 1e-12
    # Velocity is the rate of the position: v = w x r.
    vx = -result["hinge.angle_rate"] * result["bob.position.y"]
    vy = result["hinge.angle_rate"] * result["bob.position.x"]
    assert np.max(np.abs(result["bob.velocity.x"] - vx)) < 1e-12
    assert np.max(np.abs(result["bob.velocity.y"] - vy)) < 1e-12


def test_variable_communication_steps_land_on_the_same_solution(pendulum_fmu):
    # Irregular communication points; substeps are cut to land on each one.
    rng = np.random.default_rng(3)
    steps = rng.uniform(1e-4, 0.05, size=400)
    steps = steps[np.cumsum(steps) < 5.0]
    s = Slave(pendulum_fmu)
    try:
        s.start({"solver.h_max": 1e-4})
        t = 0.0
        for h in steps:
            assert s.step(t, h) == 0
            t += h
        assert s.step(t, 5.0 - t) == 0
        irregular = np.array(s.get("bob.position.x", "bob.position.y"))
    finally:
        s.free()
    regular = simulate_fmu(pendulum_fmu, stop_time=5.0, output_interval=0.01, start_values={"solver.h_max": 1e-4},
                           output=["bob.position.x", "bob.position.y"])
    # Both are second-order accurate at h = 1e-4: they agree to the discretisation error.
    assert np.hypot(*(irregular - [regular["bob.position.x"][-1], regular["bob.position.y"][-1]])) < 2e-7
