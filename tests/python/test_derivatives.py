"""Output derivatives (fmi2GetRealOutputDerivatives) and partial derivatives
of outputs with respect to inputs (fmi2GetDirectionalDerivative).

Output derivatives are checked against central differences of the outputs
over small communication steps (the FMU's own motion), partials against
differences of the outputs after fmi2SetReal of an input without a step,
and ModelStructure's dependencies against the partials."""
import math

import numpy as np
import pytest
from fmpy import read_model_description

from conftest import FMUS, OK, Slave, load_scene, packed


def outputs_of(s):
    return [v for v in s.md.modelVariables if v.causality == "output"]


def inputs_of(s):
    return [v for v in s.md.modelVariables if v.causality == "input"]


def started(fmu, start_values=None):
    s = Slave(fmu)
    s.start(start_values)
    return s


def worst_by_unit(variables, computed, reference, floor):
    """Largest |computed - reference| over the largest |reference| among the
    outputs of the same unit (derivatives that vanish, e.g. out of a plane,
    are compared at the scale of their unit's others, and at least at
    `floor` times the largest derivative: a unit whose outputs all vanish,
    such as the z torques of a planar loop, shows their round-off)."""
    worst = (0.0, "")
    floor = floor * np.abs(reference).max()
    for unit in {v.unit for v in variables}:
        idx = [i for i, v in enumerate(variables) if v.unit == unit]
        scale = max(np.abs(reference[idx]).max(), floor)
        for i in idx:
            worst = max(worst, (abs(computed[i] - reference[i]) / scale, variables[i].name))
    return worst


# name, start values, time of the check, communication step of the differences, orders offered
CASES = [
    ("pendulum", {"solver.h_max": 1e-4}, 0.3, 1e-3, 2),
    ("robot_arm", {"solver.h_max": 1e-4}, 0.2, 1e-3, 2),
    ("four_bar", {"solver.h_max": 1e-4}, 0.2, 1e-3, 2),  # closed loop
    ("slider_crank", {"solver.h_max": 2e-5}, 0.3, 2e-4, 2),  # closed loop with a prescribed drive
    ("spinning_top", {"solver.h_max": 1e-5}, 0.02, 2e-4, 2),  # spherical joint: rotation vector coordinates
    ("flexible_robot_arm", {"solver.h_max": 2e-5}, 0.1, 2e-4, 1),  # beams, flexible body joints
]


@pytest.mark.parametrize("name,start,t0,delta,max_order", CASES, ids=[c[0] for c in CASES])
def test_output_derivatives_match_differences_of_the_outputs_over_small_steps(name, start, t0, delta, max_order):
    check_output_derivatives(FMUS / f"{name}.fmu", start, t0, delta, max_order)


def explicit(name, tmp_path):
    scene = load_scene(name)
    scene["solver"]["method"] = "dormand_prince"
    return packed(scene, tmp_path, name)


# The explicit integrator: the same consistent accelerations (its own
# factorization), at substeps of h_max (a tolerance of 0.9 accepts each).
@pytest.mark.parametrize("name,start,t0,delta,max_order", CASES[:5], ids=[c[0] for c in CASES[:5]])
def test_output_derivatives_with_the_explicit_integrator(name, start, t0, delta, max_order, tmp_path):
    check_output_derivatives(explicit(name, tmp_path), start, t0, delta, max_order, tolerance=0.9)


def check_output_derivatives(fmu, start, t0, delta, max_order, tolerance=None):
    s = Slave(fmu)
    s.start(start, tolerance=tolerance)
    try:
        assert s.md.coSimulation.maxOutputDerivativeOrder == max_order
        outs = outputs_of(s)
        vrs = [v.valueReference for v in outs]
        t = 0.0
        for _ in range(round(t0 / delta) - 1):
            assert s.step(t, delta) == OK
            t += delta
        before = np.array(s.fmu.getReal(vrs))
        assert s.step(t, delta) == OK
        t += delta
        now = np.array(s.fmu.getReal(vrs))
        d = {k: np.array(s.fmu.getRealOutputDerivatives(vrs, [k] * len(vrs))) for k in range(1, max_order + 1)}
        assert np.array_equal(np.array(s.fmu.getReal(vrs)), now)  # the call changed no output
        assert s.step(t, delta) == OK
        after = np.array(s.fmu.getReal(vrs))
        first = (after - before) / (2 * delta)
        error, where = worst_by_unit(outs, d[1], first, 1e-5)
        assert error < 1e-3, f"order 1 of {where}: {error:.2e}"
        if max_order == 2:
            second = (after - 2 * now + before) / delta**2
            error, where = worst_by_unit(outs, d[2], second, 1e-4)
            assert error < 2e-3, f"order 2 of {where}: {error:.2e}"
    finally:
        s.free()


def test_kinematic_output_derivatives_are_the_rates_and_the_equations_of_motion():
    """Pendulum (point mass m on a massless link L, angle from horizontal):
    d/dt angle is the rate output, d/dt position the velocity output, and
    d2/dt2 angle = d/dt rate = -g cos(angle) / L + torque / (m L^2)."""
    m, L, tau = 3.0, 2.0, 1.5
    s = started(FMUS / "pendulum.fmu", {"mass": m, "length": L, "angle0": 0.4})
    try:
        assert s.set("hinge.torque", tau) == OK
        t = 0.0
        for _ in range(20):
            assert s.step(t, 0.01) == OK
            t += 0.01
        vr = s.vr
        names = ["hinge.angle", "hinge.angle_rate", "bob.position.x", "bob.position.y"]
        d1 = s.fmu.getRealOutputDerivatives([vr[n] for n in names], [1] * 4)
        d2 = s.fmu.getRealOutputDerivatives([vr["hinge.angle"], vr["bob.position.x"]], [2, 2])
        angle, rate, vx, vy = s.get("hinge.angle", "hinge.angle_rate", "bob.velocity.x", "bob.velocity.y")
        assert d1[0] == rate and d1[2] == vx and d1[3] == vy
        alpha = -9.81 * math.cos(angle) / L + tau / (m * L * L)
        assert abs(d1[1] - alpha) < 1e-12 * 10
        assert abs(d2[0] - alpha) < 1e-9
        # x = L cos(angle): x'' = -L (sin(angle) alpha + cos(angle) rate^2)
        assert abs(d2[1] + L * (math.sin(angle) * alpha + math.cos(angle) * rate**2)) < 1e-9
    finally:
        s.free()


def test_output_derivatives_refuse_bad_references_and_orders_naming_them():
    s = started(FMUS / "pendulum.fmu")
    try:
        vr = s.vr
        assert s.refuses("'hinge.torque' is an input", "getRealOutputDerivatives",
                         [vr["hinge.torque"]], [1]), s.messages()
        assert s.refuses("'mass' is a parameter", "getRealOutputDerivatives", [vr["mass"]], [1]), s.messages()
        for order in (0, 3, -1):
            assert s.refuses(f"order {order} of 'hinge.angle': expected 1 to 2", "getRealOutputDerivatives",
                             [vr["hinge.angle"]], [order]), s.messages()
        assert s.call("getRealOutputDerivatives", [], []) == OK
        # A refused call changed nothing: the run goes on as one without it.
        assert s.step(0.0, 0.01) == OK
        ref = started(FMUS / "pendulum.fmu")
        assert ref.step(0.0, 0.01) == OK
        assert s.get("hinge.angle", "hinge.angle_rate") == ref.get("hinge.angle", "hinge.angle_rate")
        ref.free()
    finally:
        s.free()


def partials_by_differences(s, outs, inputs, step=1.0):
    """d output / d input by central differences of fmi2GetReal after
    fmi2SetReal of the input (no step), the input put back after."""
    vrs = [v.valueReference for v in outs]
    columns = []
    for u in inputs:
        u0 = s.fmu.getReal([u.valueReference])[0]
        values = []
        for x in (u0 + step, u0 - step):
            s.fmu.setReal([u.valueReference], [x])
            values.append(np.array(s.fmu.getReal(vrs)))
        s.fmu.setReal([u.valueReference], [u0])
        columns.append((values[0] - values[1]) / (2 * step))
    return np.array(columns).T


def check_partials(s, rtol=1e-9):
    """Each input's column of partials against differences of the outputs,
    and against ModelStructure: a nonzero partial is declared, a pair not
    declared has a zero partial (computed and by differences)."""
    outs, ins = outputs_of(s), inputs_of(s)
    vrs = [v.valueReference for v in outs]
    before = s.fmu.getReal(vrs)
    computed = np.array([s.fmu.getDirectionalDerivative(vrs, [u.valueReference], [1.0]) for u in ins]).T
    assert s.fmu.getReal(vrs) == before  # nothing changed
    reference = partials_by_differences(s, outs, ins)
    scale = np.maximum(np.abs(reference).max(axis=1, keepdims=True), 1.0)
    error = np.abs(computed - reference) / scale
    i, j = np.unravel_index(error.argmax(), error.shape)
    assert error.max() < rtol, f"d {outs[i].name} / d {ins[j].name}: {computed[i, j]} vs {reference[i, j]}"
    declared = {(u.variable.name, d.name) for u in s.md.outputs for d in (u.dependencies or [])}
    for i, o in enumerate(outs):
        for j, u in enumerate(ins):
            if (o.name, u.name) in declared:
                continue
            assert computed[i, j] == 0.0 and reference[i, j] == 0.0, f"{o.name} depends on {u.name}, undeclared"
    nonzero = {(outs[i].name, ins[j].name) for i, j in zip(*np.nonzero(np.abs(reference) > 1e-9 * scale))}
    assert nonzero <= declared
    # A seed over several inputs is the sum of the columns.
    seed = np.linspace(0.5, -1.5, len(ins))
    combined = s.fmu.getDirectionalDerivative(vrs, [u.valueReference for u in ins], list(seed))
    assert np.abs(np.array(combined) - computed @ seed).max() < 1e-9 * max(1.0, np.abs(computed).max())
    return computed, nonzero, declared


def test_pendulum_reaction_partial_is_one_over_the_length():
    """A hinge torque tau accelerates the point mass tangentially by tau /
    (m L): the hinge's reaction force on the bob changes by tau / L along
    the tangent (the child frame's y), whatever the mass."""
    s = started(FMUS / "pendulum.fmu", {"mass": 3.0, "length": 2.0, "angle0": 0.3})
    try:
        assert s.step(0.0, 0.05) == OK
        vr = s.vr
        d = s.fmu.getDirectionalDerivative([vr["hinge.reaction_force.x"], vr["hinge.reaction_force.y"],
                                            vr["bob.position.x"], vr["hinge.angle_rate"]], [vr["hinge.torque"]], [1.0])
        assert abs(d[0]) < 1e-12 and abs(d[1] - 0.5) < 1e-12 and d[2] == 0.0 and d[3] == 0.0
        check_partials(s)
    finally:
        s.free()


def test_robot_arm_partials_agree_with_differences_and_model_structure():
    s = started(FMUS / "robot_arm.fmu")
    try:
        t = 0.0
        for k in range(10):
            for j, u in enumerate(inputs_of(s)):
                s.fmu.setReal([u.valueReference], [math.sin(0.3 * k + j)])
            assert s.step(t, 0.01) == OK
            t += 0.01
        computed, nonzero, _ = check_partials(s)
        assert len(nonzero) > 100
    finally:
        s.free()


def closed_loop_with_inputs():
    """The four-bar with a crank torque, a spring-damper with an actuator
    between ground and rocker, and an applied force on the coupler."""
    scene = load_scene("four_bar")
    scene["joints"][0]["actuated"] = True
    scene["forces"] = [
        {"name": "spring", "type": "spring_damper", "body1": "ground", "point1": [3.0, 2.0, 0], "body2": "rocker",
         "point2": [2.8, 1.2, 0], "stiffness": 40.0, "damping": 2.0, "free_length": 0.5, "actuated": True},
        {"name": "push", "type": "applied_force", "body": "coupler", "point": [1.3, 1.7, 0]}]
    return scene


@pytest.mark.parametrize("method", ["generalized_alpha", "dormand_prince"])
def test_closed_loop_partials_agree_with_differences_and_model_structure(tmp_path, method):
    scene = closed_loop_with_inputs()
    scene["solver"]["method"] = method
    s = started(packed(scene, tmp_path))
    try:
        assert s.step(0.0, 0.1) == OK
        assert s.set("push.force.y", 2.0) == OK
        computed, nonzero, declared = check_partials(s)
        names = [v.name for v in inputs_of(s)]
        tension = [v.name for v in outputs_of(s)].index("spring.tension")
        # The tension is the actuator force plus terms of the state: factor 1, declared constant.
        assert computed[tension, names.index("spring.actuator_force")] == pytest.approx(1.0, abs=1e-12)
        kinds = {(u.variable.name, d.name): k for u in s.md.outputs
                 for d, k in zip(u.dependencies or [], u.dependenciesKind or [])}
        assert kinds[("spring.tension", "spring.actuator_force")] == "constant"
        assert kinds[("C.reaction_force.x", "A.torque")] == "dependent"
        assert ("C.reaction_force.x", "push.torque.z") in nonzero  # cut joint: multipliers
        assert ("spring.tension", "A.torque") not in declared
    finally:
        s.free()


def test_rate_input_drive_partials_are_zero_at_the_present_state(tmp_path):
    """A rate-input drive's rate sets the next step's motion, not the
    present state: no output moves when it is set without a step, so the
    partials are zero and ModelStructure declares none."""
    from test_drives import driven_double_pendulum
    scene = driven_double_pendulum(1.0)
    scene["joints"][1]["actuated"] = True
    s = started(packed(scene, tmp_path))
    try:
        assert s.step(0.0, 0.05) == OK
        computed, nonzero, declared = check_partials(s)
        assert not [p for p in declared if p[1] == "hinge1.drive_rate"]
        assert ("hinge1.drive_torque", "hinge2.torque") in nonzero
    finally:
        s.free()


def test_flexible_partials_agree_with_differences_and_model_structure(tmp_path):
    """Beams: joint torques through flexible body joints (flexible_robot_arm),
    and a tip load and a rate-driven support (whose rate is its node's
    angular velocity at once)."""
    s = started(FMUS / "flexible_robot_arm.fmu")
    try:
        assert s.step(0.0, 0.01) == OK
        check_partials(s, rtol=1e-8)
    finally:
        s.free()
    scene = load_scene("spin_up_beam")
    body = scene["flexible_bodies"][0]
    body["supports"] = [{"node": 0, "type": "driven", "axis": [0, 0, 1], "rate_input": True}]
    last = body["beam"]["elements"]
    body["loads"] = [{"node": last, "input": True}]
    body["outputs"] = {"nodes": [0, last], "energy": True}
    s = started(packed(scene, tmp_path))
    try:
        assert s.set("beam.node0.drive_rate", 0.7) == OK
        assert s.step(0.0, 0.01) == OK
        computed, nonzero, _ = check_partials(s, rtol=1e-8)
        assert ("beam.node0.angular_velocity.z", "beam.node0.drive_rate") in nonzero
        assert ("beam.kinetic_energy", "beam.node0.drive_rate") in nonzero
    finally:
        s.free()


def test_directional_derivative_refuses_knowns_that_are_not_inputs():
    s = started(FMUS / "pendulum.fmu")
    try:
        vr = s.vr
        assert s.refuses("'hinge.angle_rate' is an output; expected an input", "getDirectionalDerivative",
                         [vr["hinge.angle"]], [vr["hinge.angle_rate"]], [1.0]), s.messages()
        assert s.refuses("'mass' is a parameter; expected an input", "getDirectionalDerivative",
                         [vr["hinge.angle"]], [vr["mass"]], [1.0]), s.messages()
        assert s.refuses("'hinge.torque' is an input; expected an output", "getDirectionalDerivative",
                         [vr["hinge.torque"]], [vr["hinge.torque"]], [1.0]), s.messages()
        assert s.refuses("seed of 'hinge.torque'", "getDirectionalDerivative",
                         [vr["hinge.angle"]], [vr["hinge.torque"]], [math.nan]), s.messages()
        # NULL arrays with n = 0.
        assert s.fmu.fmi2GetDirectionalDerivative(s.fmu.component, None, 0, None, 0, None, None) == OK
        assert s.fmu.fmi2GetRealOutputDerivatives(s.fmu.component, None, 0, None, None) == OK
    finally:
        s.free()


def test_static_scenes_declare_no_derivatives_and_refuse_them():
    md = read_model_description(str(FMUS / "cantilever_moment.fmu"))
    assert md.coSimulation.maxOutputDerivativeOrder == 0
    assert md.coSimulation.providesDirectionalDerivative is False
    s = started(FMUS / "cantilever_moment.fmu")
    try:
        out = outputs_of(s)[0].valueReference
        assert s.refuses("static analysis", "getRealOutputDerivatives", [out], [1]), s.messages()
    finally:
        s.free()


@pytest.mark.parametrize("method", ["generalized_alpha", "dormand_prince"])
def test_derivative_calls_leave_the_run_bit_for_bit_unchanged(tmp_path, method):
    scene = closed_loop_with_inputs()
    scene["solver"]["method"] = method
    fmu = packed(scene, tmp_path)
    a, b = started(fmu), started(fmu)
    try:
        outs = [v.valueReference for v in outputs_of(a)]
        ins = [v.valueReference for v in inputs_of(a)]
        t = 0.0
        for k in range(20):
            values = [math.sin(0.7 * k + j) for j in range(len(ins))]
            a.fmu.setReal(ins, values)
            b.fmu.setReal(ins, values)
            a.fmu.getDirectionalDerivative(outs, ins, [1.0] * len(ins))
            a.fmu.getRealOutputDerivatives(outs, [1 + k % 2] * len(outs))
            assert a.step(t, 0.01) == OK and b.step(t, 0.01) == OK
            t += 0.01
            assert a.fmu.getReal(outs) == b.fmu.getReal(outs)
    finally:
        a.free()
        b.free()


def test_force_derivatives_follow_the_input_derivatives(tmp_path):
    """A hinge torque ramped at 50 N m/s (fmi2SetRealInputDerivatives) moves
    the pendulum's tangential reaction at 50 N/s (length 1 m) at once: the
    output derivative says so, as central differences of the output over
    two steps of 1e-4 s do; with the torque held it is ~0."""
    fmu = FMUS / "pendulum.fmu"

    def slave(ramp):
        s = Slave(fmu)
        s.start({"angle0": 0.3})
        s.set("hinge.torque", 2.0)
        if ramp:
            s.fmu.setRealInputDerivatives([s.vr["hinge.torque"]], [1], [ramp])
        return s

    h, reaction = 1e-4, "hinge.reaction_force.y"
    s = slave(50.0)
    values = [s.get(reaction)]
    for k in range(2):
        assert s.step(k * h, h) == 0
        s.set("hinge.torque", 2.0 + 50.0 * (k + 1) * h)
        s.fmu.setRealInputDerivatives([s.vr["hinge.torque"]], [1], [50.0])
        values.append(s.get(reaction))
    s.free()
    s = slave(50.0)
    assert s.step(0.0, h) == 0
    s.set("hinge.torque", 2.0 + 50.0 * h)
    s.fmu.setRealInputDerivatives([s.vr["hinge.torque"]], [1], [50.0])
    derivative = s.fmu.getRealOutputDerivatives([s.vr[reaction]], [1])[0]
    s.free()
    assert abs(derivative - (values[2] - values[0]) / (2 * h)) < 1e-6 * 50.0
    assert abs(derivative - 50.0) < 1e-3
    s = slave(0.0)
    assert s.step(0.0, h) == 0
    assert abs(s.fmu.getRealOutputDerivatives([s.vr[reaction]], [1])[0]) < 1e-6
    s.free()
