"""Input interpolation (fmi2SetRealInputDerivatives): inside a step's
substeps an input follows u + du (t - tc) + d2u (t - tc)^2 / 2, so a master
that passes a ramp's value and derivatives reproduces the motion of a scene
that prescribes the same ramp as a time function; refused calls name the
variable and change nothing; setting the value again restarts the
derivatives at zero."""
import numpy as np
import pytest

from conftest import ERROR, FMUS, OK, Slave, load_scene, packed
from test_drives import driven_double_pendulum

H = 0.01


def run_steps(s, steps, before_step, outputs):
    rows, t = [], 0.0
    for k in range(steps):
        before_step(s, t)
        assert s.step(t, H) == OK, s.messages()
        t += H
        rows.append(s.get(*outputs))
    return np.array(rows)


def pendulum_runs(befores, outputs):
    """The pendulum over 10 steps, once for each `before_step` (the master's
    calls before each step): the outputs after each step, one array a run."""
    results = []
    for before in befores:
        s = Slave(FMUS / "pendulum.fmu")
        try:
            s.start()
            results.append(run_steps(s, 10, before, outputs))
        finally:
            s.free()
    return results


def derivatives(s, name, values):
    vr = s.vr[name]
    assert s.call("setRealInputDerivatives", [vr] * len(values), list(range(1, len(values) + 1)), values) == OK, \
        s.messages()


# Generalized-alpha at fixed substeps (no tolerance); Dormand-Prince at
# substeps of h_max too (a tolerance of 0.9 accepts every one), so that the
# runs compared take the same substeps.
@pytest.mark.parametrize("method,tolerance", [("generalized_alpha", None), ("dormand_prince", 0.9)])
def test_rate_input_with_derivatives_follows_a_prescribed_drive(tmp_path, method, tolerance):
    # Rate w0 + alpha t + beta t^2 / 2 from the master; the reference scene
    # prescribes its integral as the hinge's drive.
    w0, alpha, beta = 1.0, 2.0, -3.0
    reference = driven_double_pendulum(w0)
    reference["joints"][0]["drive"] = f"{w0}*t + {alpha}*t^2/2 + {beta}*t^3/6"
    outputs = ("hinge1.angle", "hinge2.angle", "bob2.position.x", "bob2.position.y")

    def rate(t, order):
        return [w0 + alpha * t + beta * t * t / 2, alpha + beta * t, beta][order]

    def interpolated(s, t):
        assert s.set("hinge1.drive_rate", rate(t, 0)) == OK
        derivatives(s, "hinge1.drive_rate", [rate(t, 1), rate(t, 2)])

    def held(s, t):
        assert s.set("hinge1.drive_rate", rate(t, 0)) == OK

    results = {}
    for label, scene, before in (("prescribed", reference, lambda s, t: None),
                                 ("interpolated", driven_double_pendulum(w0), interpolated),
                                 ("held", driven_double_pendulum(w0), held)):
        scene["solver"]["method"] = method
        s = Slave(packed(scene, tmp_path, label))
        try:
            # The inputs of the start (before initialization: its velocities
            # and accelerations meet the drive).
            assert s.instantiate() and s.call("setupExperiment", tolerance, 0.0, None) == OK
            if label != "prescribed":
                before(s, 0.0)
            assert s.call("enterInitializationMode") == OK and s.call("exitInitializationMode") == OK, s.messages()
            results[label] = run_steps(s, 60, before, outputs)
        finally:
            s.free()
    scale = np.abs(results["prescribed"]).max()
    assert np.abs(results["interpolated"] - results["prescribed"]).max() <= 1e-9 * scale
    # Without the derivatives the held rate lags the drive by O(H).
    assert np.abs(results["held"] - results["prescribed"]).max() > 1e-4 * scale


def test_load_input_with_derivatives_follows_a_time_function_load(tmp_path):
    scene = load_scene("cantilever_vibration")
    p = {k: v["value"] for k, v in scene["parameters"].items()}
    F0 = 0.01 * p["EI"] / p["L"] ** 2
    reference = scene
    reference["flexible_bodies"][0]["loads"] = [{"node": 16, "force": [0, F0, 0], "scale": "t + 4*t^2"}]
    driven = load_scene("cantilever_vibration")
    driven["flexible_bodies"][0]["loads"] = [{"node": 16, "input": True}]
    outputs = ("beam.node16.position.y", "beam.node16.velocity.y")

    def interpolated(s, t):
        assert s.set("beam.node16.force.y", F0 * (t + 4 * t * t)) == OK
        derivatives(s, "beam.node16.force.y", [F0 * (1 + 8 * t), 8 * F0])

    results = {}
    for label, sc, before in (("prescribed", reference, lambda s, t: None), ("interpolated", driven, interpolated)):
        s = Slave(packed(sc, tmp_path, label))
        try:
            s.start()
            results[label] = run_steps(s, 40, before, outputs)
        finally:
            s.free()
    for column in range(len(outputs)):
        scale = np.abs(results["prescribed"][:, column]).max()
        assert np.abs(results["interpolated"][:, column] - results["prescribed"][:, column]).max() <= 1e-9 * scale


def test_refused_derivatives_name_the_variable_and_change_nothing():
    outputs = ("hinge.angle", "hinge.angle_rate", "hinge.reaction_force.x")

    def plain(s, t):
        assert s.set("hinge.torque", 0.5) == OK
        derivatives(s, "hinge.torque", [2.0])

    def with_refusals(s, t):
        plain(s, t)
        torque = s.vr["hinge.torque"]
        for vr, order, value, message in (
                (torque, 0, 1.0, "'hinge.torque': derivative order 0 is not supported (1 to 2)"),
                (torque, 3, 1.0, "'hinge.torque': derivative order 3 is not supported"),
                (torque, 1, float("nan"), "'hinge.torque': derivative of order 1 = nan: expected a finite value"),
                (s.vr["hinge.angle"], 1, 1.0, "'hinge.angle' is not an input"),
                (s.vr["mass"], 1, 1.0, "'mass' is not an input"),
                (987654, 1, 1.0, "no Real variable with value reference 987654")):
            # A refused entry refuses the whole call: the valid first one is not applied either.
            status = s.call("setRealInputDerivatives", [torque, vr], [1, order], [7.0, value])
            assert status == ERROR and message in s.log[-1][2], s.log[-1][2]

    results = pendulum_runs((plain, with_refusals), outputs)
    assert np.array_equal(results[0], results[1])


def test_setting_the_value_again_restarts_the_derivatives_at_zero():
    outputs = ("hinge.angle", "hinge.angle_rate")

    def value_only(s, t):
        assert s.set("hinge.torque", 0.5) == OK

    def derivative_then_value(s, t):
        assert s.set("hinge.torque", 0.5) == OK
        derivatives(s, "hinge.torque", [30.0, -4.0])
        assert s.set("hinge.torque", 0.5) == OK

    def derivative(s, t):
        assert s.set("hinge.torque", 0.5) == OK
        derivatives(s, "hinge.torque", [30.0])

    results = pendulum_runs((value_only, derivative_then_value, derivative), outputs)
    assert np.array_equal(results[0], results[1])
    assert not np.allclose(results[0], results[2], rtol=1e-6, atol=0)  # the derivative did act
