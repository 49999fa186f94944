"""The FMI 2.0 Co-Simulation contract: call sequence, logging, reset,
resource URIs, capabilities, bad values, discarded steps, two instances."""
import pathlib
import re
import shutil

import numpy as np
import pytest
from fmpy import extract

from conftest import DISCARD, ERROR, OK, Slave, load_scene, packed


def test_call_in_the_wrong_state_is_an_error_with_a_log_line(slave):
    assert slave.instantiate()
    assert slave.step(0.0, 0.01) == ERROR  # before initialization
    assert "fmi2DoStep: not allowed in state Instantiated" in slave.messages()
    assert slave.call("exitInitializationMode") == ERROR
    assert "fmi2ExitInitializationMode: not allowed in state Instantiated" in slave.messages()
    # The instance is still usable along the right sequence.
    assert slave.call("setupExperiment", None, 0.0, None) == OK
    assert slave.call("enterInitializationMode") == OK
    assert slave.call("setupExperiment", None, 0.0, None) == ERROR
    assert slave.call("exitInitializationMode") == OK
    assert slave.step(0.0, 0.01) == OK
    assert slave.call("terminate") == OK
    assert slave.step(0.01, 0.01) == ERROR
    assert "not allowed in state Terminated" in slave.messages()


def test_reset_restores_start_values_time_and_state(slave):
    slave.start({"hinge.damping": 0.3})
    first = [slave.get("bob.position.x", "bob.position.y")]
    for k in range(50):
        assert slave.step(0.02 * k, 0.02) == OK
    moved = slave.get("bob.position.x", "bob.position.y")
    assert slave.call("reset") == OK
    assert slave.call("setupExperiment", None, 0.0, None) == OK
    assert slave.call("enterInitializationMode") == OK
    assert slave.call("exitInitializationMode") == OK
    assert slave.get("hinge.damping") == 0.0  # start value again
    np.testing.assert_array_equal(slave.get("bob.position.x", "bob.position.y"), first[0])
    assert np.linalg.norm(np.array(moved) - np.array(first[0])) > 0.1
    assert slave.step(0.0, 0.02) == OK  # time is 0 again
    assert slave.step(0.5, 0.02) == ERROR  # not the FMU's time


@pytest.mark.parametrize("form", ["file:/", "file:///", "file://localhost/"])
def test_resource_location_forms_with_spaces_and_utf8(pendulum_fmu, tmp_path, form):
    unzip = tmp_path / "dir with spaces" / "ünïcode Ω"
    unzip.mkdir(parents=True)
    extract(str(pendulum_fmu), str(unzip))
    s = Slave(pendulum_fmu, unzip_dir=str(unzip))
    try:
        escaped = (unzip / "resources").as_uri()[len("file://"):]  # percent-escaped absolute path
        assert "%20" in escaped and "%C3%BC" in escaped.upper()
        assert s.instantiate(resource_uri=form + escaped.lstrip("/")), s.messages()
    finally:
        s.free()


def test_bad_resource_location_and_guid_fail_instantiate_with_a_reason(slave):
    assert not slave.instantiate(resource_uri="http://example.org/resources")
    assert "expected a file: URI" in slave.messages()
    assert not slave.instantiate(resource_uri="file://otherhost/tmp/resources")
    assert "remote host" in slave.messages()
    assert not slave.instantiate(guid="{00000000-0000-0000-0000-000000000000}")
    assert "does not match this FMU's scene" in slave.messages()


def test_undeclared_capabilities_return_error_with_a_log_line(slave):
    slave.start()
    cs = slave.md.coSimulation
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate and cs.canInterpolateInputs  # test_fmu_state.py
    assert cs.providesDirectionalDerivative and cs.maxOutputDerivativeOrder == 2  # test_derivatives.py
    assert slave.call("cancelStep") == ERROR
    assert "nothing to cancel" in slave.messages()


def test_bad_values_are_refused_naming_the_variable(slave):
    assert slave.instantiate()
    assert slave.set("mass", -1.0) == ERROR
    assert "'mass' = -1" in slave.messages() and "bodies[0].mass" in slave.messages()
    assert slave.set("solver.rho_inf", 1.5) == ERROR
    assert "'solver.rho_inf'" in slave.messages() and "[0, 1]" in slave.messages()
    assert slave.set("solver.tolerance", 0.0) == ERROR
    assert "'solver.tolerance'" in slave.messages() and "> 0" in slave.messages()
    assert slave.set("hinge.torque", float("nan")) == ERROR
    assert "'hinge.torque'" in slave.messages() and "finite" in slave.messages()
    assert slave.call("setReal", [10**6], [1.0]) == ERROR
    assert "no Real variable with value reference 1000000" in slave.messages()
    assert slave.set("bob.position.x", 1.0) == ERROR
    assert "'bob.position.x' is an output" in slave.messages()
    assert slave.call("setInteger", [0], [1]) == ERROR
    # A refused value changed nothing: the run starts from the scene's values.
    assert slave.call("setupExperiment", None, 0.0, None) == OK
    assert slave.call("enterInitializationMode") == OK
    assert slave.call("exitInitializationMode") == OK
    assert slave.get("mass") == 1.0
    assert slave.set("length", 2.0) == ERROR  # fixed parameters are frozen after initialization
    assert "fixed parameter" in slave.messages()


def test_fixed_parameters_reach_the_mechanism(pendulum_fmu):
    s = Slave(pendulum_fmu)
    try:
        s.start({"length": 2.5, "gravity.y": -1.62})
        assert abs(s.get("bob.position.x") - 2.5) < 1e-15
        s.step(0.0, 1e-3)
        # Released from rest: the initial acceleration is g, straight down.
        assert abs(s.get("bob.velocity.y") / 1e-3 - (-1.62)) < 1e-3
    finally:
        s.free()


def test_failed_step_returns_discard_with_the_state_of_the_step_start(tmp_path):
    # Newton allowed one iteration to a tolerance it cannot reach: every
    # substep fails, halving down to h_min, and the step must be discarded.
    scene = load_scene("pendulum")
    scene["solver"] = {"h_max": 1e-3, "h_min": 2e-4, "max_iterations": 1, "tolerance": 1e-300}
    s = Slave(packed(scene, tmp_path))
    try:
        s.start({"angle0": 0.3})
        before = s.get("bob.position.x", "bob.position.y", "hinge.angle_rate", "hinge.reaction_force.x")
        assert s.step(0.0, 0.01) == DISCARD
        assert "fmi2DoStep: substep failed at t = " in s.messages()
        assert s.messages().endswith("state restored to t = 0")
        after = s.get("bob.position.x", "bob.position.y", "hinge.angle_rate", "hinge.reaction_force.x")
        np.testing.assert_array_equal(before, after)
        assert np.all(np.isfinite(after))
        assert s.fmu.getRealStatus(2) == 0.0  # fmi2LastSuccessfulTime
        assert s.fmu.getBooleanStatus(3) is True or s.fmu.getBooleanStatus(3) == 1  # fmi2Terminated
        assert s.step(0.0, 0.01) == ERROR  # stepFailed: no further steps
        assert s.call("terminate") == OK
    finally:
        s.free()


def test_two_instances_in_one_process_do_not_interfere(pendulum_fmu):
    a, b = Slave(pendulum_fmu, instance_name="a"), Slave(pendulum_fmu, instance_name="b")
    alone = Slave(pendulum_fmu, instance_name="alone")
    try:
        a.start({"length": 1.0})
        b.start({"length": 2.0, "hinge.damping": 0.5})
        alone.start({"length": 1.0})
        t = 0.0
        for _ in range(300):  # interleaved steps, different parameters
            assert a.step(t, 0.01) == OK and b.step(t, 0.01) == OK and alone.step(t, 0.01) == OK
            t += 0.01
        assert a.get("bob.position.x", "bob.position.y") == alone.get("bob.position.x", "bob.position.y")
        assert abs(b.get("bob.position.x") ** 2 + b.get("bob.position.y") ** 2 - 4.0) < 1e-9
    finally:
        for s in (a, b, alone):
            s.free()
            shutil.rmtree(s.unzip_dir, ignore_errors=True)


def test_log_categories_filter_and_unknown_category_is_refused(slave):
    assert slave.instantiate(logging_on=True)
    assert any(c == "logEvents" for _, c, _ in slave.log)  # loggingOn with no categories: all
    assert slave.call("setDebugLogging", True, ["logStep"]) == OK
    slave.log.clear()
    slave.call("setupExperiment", None, 0.0, None)
    slave.call("enterInitializationMode")
    slave.call("exitInitializationMode")
    slave.step(0.0, 0.01)
    categories = {c for _, c, _ in slave.log}
    assert categories == {"logStep"}
    assert any("Newton iterations" in m for _, _, m in slave.log)
    # The run's totals once, at fmi2Terminate, and only when asked for.
    slave.step(0.01, 0.01)
    assert slave.call("setDebugLogging", True, ["logStatistics"]) == OK
    slave.log.clear()
    slave.step(0.02, 0.01)
    assert slave.log == []
    assert slave.call("terminate") == OK
    assert [c for _, c, _ in slave.log] == ["logStatistics"]
    substeps = int(re.search(r"substeps (\d+)", slave.log[0][2]).group(1))
    assert substeps == 3 * round(0.01 / 1e-3), slave.log  # the pendulum's h_max = 1e-3
    assert slave.call("setDebugLogging", True, ["logNoSuchThing"]) == ERROR
    assert 'unknown log category "logNoSuchThing"' in slave.messages()


def test_newton_tolerance_parameter_takes_effect(pendulum_fmu):
    """solver.tolerance reaches the solver: a loose one takes fewer Newton
    iterations (counted by logStatistics) for nearly the same motion."""
    def run(tolerance):
        slave = Slave(pendulum_fmu)
        try:
            assert slave.instantiate(logging_on=True)
            assert slave.call("setDebugLogging", True, ["logStatistics"]) == OK
            start = {} if tolerance is None else {"solver.tolerance": tolerance}
            assert slave.call("setupExperiment", None, 0.0, None) == OK
            for name, value in start.items():
                assert slave.set(name, value) == OK
            assert slave.call("enterInitializationMode") == OK
            assert slave.call("exitInitializationMode") == OK
            for k in range(100):
                assert slave.step(0.01 * k, 0.01) == OK
            angle = slave.get("hinge.angle")
            assert slave.call("terminate") == OK
            line = [m for _, c, m in slave.log if c == "logStatistics"][-1]
            return angle, int(re.search(r"Newton iterations (\d+)", line).group(1))
        finally:
            slave.free()
            shutil.rmtree(slave.unzip_dir, ignore_errors=True)

    tight, tight_iterations = run(None)      # the default 1e-14
    loose, loose_iterations = run(1e-6)
    # Measured: 1554 and 1044 iterations, angles 1e-8 apart.
    assert loose_iterations < 0.8 * tight_iterations, (loose_iterations, tight_iterations)
    assert abs(loose - tight) < 1e-6
