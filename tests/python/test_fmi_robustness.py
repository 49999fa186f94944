"""What a hostile or careless master can do: calls in state Error, refused
multi-value calls, values that would make a step unbounded, and time kept
exactly at large start times and tiny steps. Calls that crashed or hung
before the fix run in a child process, so that a crash or hang fails the
test instead of killing pytest."""
import multiprocessing
import shutil
import traceback

import numpy as np
import pytest

from conftest import DISCARD, ERROR, FMUS, OK, Slave, load_scene, packed


def in_child(function, *args, timeout=60.0):
    """Runs function(*args) in a forked process; returns its result, or
    fails naming the signal or the timeout."""
    context = multiprocessing.get_context("fork")
    receive, send = context.Pipe(duplex=False)

    def run():
        try:
            send.send(("ok", function(*args)))
        except BaseException:  # an assertion inside the child: report it
            send.send(("raised", traceback.format_exc()))

    process = context.Process(target=run)
    process.start()
    ready = receive.poll(timeout)
    if not ready:
        process.kill()
        process.join()
        pytest.fail(f"hung: no answer within {timeout} s"
                    if process.exitcode in (None, -9) else f"died with exit code {process.exitcode}")
    kind, value = receive.recv()
    process.join()
    if kind == "raised":
        pytest.fail(value)
    return value


def _slave(fmu):
    return Slave(fmu)


def _done(s):
    s.free()
    shutil.rmtree(s.unzip_dir, ignore_errors=True)


# -- State Error: outputs have no value, nothing crashes ---------------------

def _error_state_after_enter(fmu):
    s = _slave(fmu)
    try:
        assert s.instantiate()
        assert s.call("setupExperiment", None, 1.0, None) == OK
        entered = s.call("enterInitializationMode")  # the drive 1/(1 - t) is infinite at t = 1
        outputs = s.call("getReal", [s.vr["hinge.angle"], s.vr["bob.position.x"]])
        parameter = s.fmu.getReal([s.vr["mass"]])[0]
        exited = s.call("exitInitializationMode")
        terminated = s.call("terminate")
        stepped = s.step(1.0, 0.01)
        log = s.messages()
        # fmi2Reset leaves state Error; a start at t = 0 runs.
        reset = s.call("reset")
        assert s.call("setupExperiment", None, 0.0, None) == OK
        assert s.call("enterInitializationMode") == OK and s.call("exitInitializationMode") == OK
        assert s.step(0.0, 0.01) == OK
        return entered, outputs, parameter, exited, terminated, stepped, reset, log
    finally:
        _done(s)


def test_outputs_in_state_error_after_a_failed_initialization_are_an_error_not_a_crash(tmp_path):
    scene = load_scene("pendulum")
    joint = scene["joints"][0]
    joint["drive"] = "1/(1 - t)"
    joint["actuated"] = False
    del joint["initial"]
    fmu = packed(scene, tmp_path)
    entered, outputs, parameter, exited, terminated, stepped, reset, log = in_child(_error_state_after_enter, fmu)
    assert entered == ERROR
    assert outputs == ERROR
    assert "output 'hinge.angle' has no value in state Error" in log
    assert parameter == 1.0  # parameters keep their values
    assert (exited, terminated, stepped) == (ERROR, ERROR, ERROR)
    assert reset == OK


def _error_state_after_exit(fmu):
    s = _slave(fmu)
    try:
        assert s.instantiate()
        assert s.call("setupExperiment", None, 0.0, None) == OK
        assert s.call("enterInitializationMode") == OK
        inside = s.fmu.getReal([s.vr["hinge.position"]])[0]  # valid in initialization mode
        exited = s.call("exitInitializationMode")  # no equilibrium: nothing holds the slider
        outputs = s.call("getReal", [s.vr["hinge.position"]])
        return inside, exited, outputs, s.messages()
    finally:
        _done(s)


def test_outputs_in_state_error_after_a_failed_exit_are_an_error(tmp_path):
    scene = load_scene("pendulum")
    scene["joints"][0].update({"type": "prismatic", "axis": [0, 1, 0]})
    scene["solver"]["initial_equilibrium"] = True
    inside, exited, outputs, log = in_child(_error_state_after_exit, packed(scene, tmp_path))
    assert inside == 0.0
    assert exited == ERROR and "no static equilibrium" in log
    assert outputs == ERROR and "output 'hinge.position' has no value in state Error" in log


# -- A refused call changes nothing ------------------------------------------

def test_a_refused_multi_value_set_real_changes_nothing(slave):
    slave.start()
    vr = slave.vr
    assert slave.call("setReal", [vr["hinge.torque"], 999999], [5.0, 1.0]) == ERROR
    assert "no Real variable with value reference 999999" in slave.messages()
    assert slave.get("hinge.torque") == 0.0
    assert slave.call("setReal", [vr["hinge.torque"], vr["hinge.damping"]], [5.0, -1.0]) == ERROR
    assert slave.get("hinge.torque", "hinge.damping") == [0.0, 0.0]
    assert slave.call("setReal", [vr["hinge.torque"], vr["hinge.angle"]], [5.0, 1.0]) == ERROR
    assert slave.get("hinge.torque") == 0.0
    # The step after the refused calls is the unforced one.
    reference = Slave(FMUS / "pendulum.fmu")
    try:
        reference.start()
        assert slave.step(0.0, 0.1) == OK and reference.step(0.0, 0.1) == OK
        assert slave.get("hinge.angle") == reference.get("hinge.angle")
    finally:
        _done(reference)


def test_user_parameters_of_one_call_are_checked_together_and_refused_together(slave):
    assert slave.instantiate()
    vr = slave.vr
    assert slave.call("setReal", [vr["length"], vr["mass"]], [2.0, -1.0]) == ERROR
    assert "'length' = 2, 'mass' = -1: the scene would be invalid" in slave.messages()
    assert slave.call("setupExperiment", None, 0.0, None) == OK
    assert slave.call("enterInitializationMode") == OK
    assert slave.get("mass", "length") == [1.0, 1.0]


# -- Bounded work per step ---------------------------------------------------

@pytest.mark.parametrize("h_max", [5e-324, 1e-16, 1e-10])
def test_h_max_below_h_min_is_refused_naming_the_range(slave, h_max):
    assert slave.instantiate()
    assert slave.set("solver.h_max", h_max) == ERROR
    assert "'solver.h_max' =" in slave.messages() and "expected h_max >= solver.h_min = 1e-09 s" in slave.messages()
    assert slave.set("solver.h_max", 1e-9) == OK  # h_min itself is allowed


@pytest.mark.parametrize("name, value", [("gravity.y", 1e300), ("gravity.x", -1e21), ("hinge.damping", 1e300),
                                         ("hinge.damping", -1.0)])
def test_built_in_parameters_beyond_the_scene_range_are_refused(slave, name, value):
    """Gravity and damping keep to the range of scene numbers (1e20), as the
    scene's own fields do: 1e300 was accepted and failed later."""
    assert slave.instantiate()
    start = next(v.start for v in slave.md.modelVariables if v.name == name)
    assert slave.set(name, value) == ERROR
    assert f"'{name}' =" in slave.messages() and "expected" in slave.messages()
    assert slave.call("setupExperiment", None, 0.0, None) == OK
    assert slave.call("enterInitializationMode") == OK, slave.messages()
    assert slave.get(name) == float(start)


@pytest.mark.parametrize("value", [0.0, -3.0, 2.5, 1e10, float("inf")])
def test_max_substeps_outside_its_range_is_refused(slave, value):
    assert slave.instantiate()
    assert slave.set("solver.max_substeps", value) == ERROR
    message = slave.messages()
    assert "'solver.max_substeps' =" in message
    assert "expected a whole number from 1 to 1e+09" in message or "expected a finite value" in message


def _step_beyond_the_bound(fmu, start, t, H):
    s = _slave(fmu)
    try:
        s.start(start)
        names = [v.name for v in s.md.modelVariables if v.causality == "output"]
        before = s.get(*names)
        status = s.step(t, H)
        after = s.get(*names)
        return status, before, after, s.fmu.getRealStatus(2), s.messages()
    finally:
        _done(s)


@pytest.mark.parametrize("fmu, start, H, bound", [
    ("cantilever_vibration", {"solver.h_max": 1e-9}, 0.01, "1e+05"),  # 1e7 substeps
    ("pendulum", {}, 1e300, "1e+05"),
    ("pendulum", {"solver.max_substeps": 5}, 0.01, "5"),  # 10 substeps
])
def test_a_step_beyond_max_substeps_is_discarded_at_once_with_the_step_start(fmu, start, H, bound):
    status, before, after, last_time, log = in_child(_step_beyond_the_bound, FMUS / f"{fmu}.fmu", start, 0.0, H)
    assert status == DISCARD
    assert f"the step of {H:g} s would need" in log and f"more than solver.max_substeps = {bound}" in log
    np.testing.assert_array_equal(after, before)
    assert last_time == 0.0


def test_max_substeps_counts_rejected_substeps(tmp_path):
    # Newton allowed one iteration to a tolerance it cannot reach: every
    # substep fails and halves h. Ten substeps of h_max fit in 12, but after
    # the first fails, twenty of half the size do not.
    scene = load_scene("pendulum")
    scene["solver"] = {"h_max": 1e-3, "h_min": 1e-9, "max_iterations": 1, "tolerance": 1e-300}
    s = Slave(packed(scene, tmp_path))
    try:
        s.start({"angle0": 0.3, "solver.max_substeps": 12})
        assert s.step(0.0, 0.01) == DISCARD
        message = s.messages()
        assert "substep failed at t = 0 with h = 0.001" in message  # the cause comes first
        assert "; the step of 0.01 s would need 21 substeps" in message
        assert "more than solver.max_substeps = 12" in message
    finally:
        _done(s)


def test_steps_within_max_substeps_run(slave):
    slave.start({"solver.max_substeps": 10})
    assert slave.step(0.0, 0.01) == OK  # ten substeps of h_max = 1e-3


# -- Time -------------------------------------------------------------------

def _swing(t0, H=0.01, steps=100):
    s = Slave(FMUS / "pendulum.fmu")
    try:
        s.start({"angle0": 0.3}, start_time=t0)
        for k in range(steps):
            assert s.step(t0 + k * H, H) == OK, s.messages()
        return s.get("hinge.angle", "hinge.angle_rate"), s.fmu.getRealStatus(2)
    finally:
        _done(s)


@pytest.mark.parametrize("t0", [1e9, 1e10])
def test_a_late_start_gives_the_same_motion(t0):
    # The old code skipped what was left below 1e-12 |t|: 0.16 rad off at
    # 1e9 after 1 s. The substeps depend on the step's duration alone, so
    # the motion of a scene without functions of time is the same.
    (angle0, rate0), _ = _swing(0.0)
    (angle, rate), last = _swing(t0)
    assert abs(angle - angle0) <= 1e-12 and abs(rate - rate0) <= 1e-12, (angle - angle0, rate - rate0)
    assert last == t0 + 99 * 0.01 + 0.01  # the FMU's time is the master's last t + H


def test_the_fmu_takes_the_masters_time_however_it_accumulates(slave):
    t0, H = 1e10, 0.01
    slave.start(start_time=t0)
    t = t0
    for k in range(5):  # t += H: rounds to 1.9e-6 at 1e10
        assert slave.step(t, H) == OK
        t += H
    assert slave.fmu.getRealStatus(2) == t
    for k in range(5, 10):  # t0 + k H: differs from the sum by round-off
        assert slave.step(t0 + k * H, H) == OK, slave.messages()
    assert slave.fmu.getRealStatus(2) == t0 + 9 * H + H
    # A time off by more than round-off is refused (the old check allowed 10 s here).
    assert slave.step(t0 + 10 * H + 1e-3, H) == ERROR
    assert "is not the FMU's time" in slave.messages()
    assert slave.step(t0 + 10 * H, H) == OK


def _nanosecond_steps(t0, H, steps):
    s = Slave(FMUS / "pendulum.fmu")
    try:
        s.start({"angle0": 0.3}, start_time=t0)
        t = t0
        for _ in range(steps):
            assert s.step(t, H) == OK, s.messages()
            t += H
        return s.get("hinge.angle", "hinge.angle_rate")
    finally:
        _done(s)


def test_nanosecond_steps_move_the_state_as_one_step_of_their_length():
    # 1000 steps of 1e-9 s from t = 1e4 (the old code skipped each: below
    # 1e-12 |t|) against one step of 1e-6 s. Released from rest, the angle
    # rate after 1e-6 s is -g cos(0.3)/L 1e-6 = -9.37e-6 rad/s and the angle
    # moves 4.7e-12 rad. Generalized-alpha integrates a constant acceleration
    # exactly at any substep, and over 1e-6 s it changes by 1e-12 of itself:
    # the two agree to round-off (measured: rates 3e-13 apart, relative). The
    # angle, near 0.3, rounds to its ulp (5.6e-17) at each of the 1000
    # substeps: at most 1000 half-ulps = 2.8e-14 apart (measured 2.8e-16).
    angle1, rate1 = _nanosecond_steps(1e4, 1e-6, 1)
    angle, rate = _nanosecond_steps(1e4, 1e-9, 1000)
    expected_rate = -9.81 * np.cos(0.3) * 1e-6
    assert abs(rate1 - expected_rate) <= 1e-9 * abs(expected_rate)
    assert abs(rate - rate1) <= 1e-9 * abs(rate1), (rate, rate1)
    assert abs(angle - angle1) <= 1000 * 0.5 * np.spacing(0.3), (angle - 0.3, angle1 - 0.3)
    assert abs(angle - 0.3) > 4e-12  # it moved
