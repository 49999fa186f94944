"""The explicit Dormand-Prince 5(4) integrator (solver.method): errors
against independent references fall with the tolerance (R1, R2), closed
loops keep their constraints and follow generalized-alpha at a tiny step,
the Lie-group chart keeps order 5 on SO(3) (heavy top, analytic), the
automatic choice says which integrator and why, and a forced explicit run
on a stiff scene is right or discarded."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from conftest import DISCARD, FMUS, OK, Slave, load_scene, packed
from test_error_control import mass_chain, pendulum_positions, spring_pendulum

G = 9.81


def with_method(scene, method, **solver):
    scene.setdefault("solver", {})["method"] = method
    scene["solver"].update(solver)
    return scene


def run(fmu, stop, H, outputs, tolerance=None, start_values=None, each_step=None):
    """Outputs at the end (and each_step(slave) after every step), with the log."""
    s = Slave(fmu)
    try:
        assert s.instantiate(logging_on=True), s.messages()
        assert s.call("setDebugLogging", True, ["logEvents"]) == OK
        assert s.call("setupExperiment", tolerance, 0.0, None) == OK
        for name, value in (start_values or {}).items():
            assert s.set(name, value) == OK, s.messages()
        assert s.call("enterInitializationMode") == OK and s.call("exitInitializationMode") == OK, s.messages()
        t = 0.0
        for _ in range(int(round(stop / H))):
            assert s.step(t, H) == OK, s.messages()
            t += H
            if each_step:
                each_step(s)
        return np.array(s.get(*outputs)), s.messages()
    finally:
        s.free()


def integrator_line(log):
    return next(line for line in log.splitlines() if line.startswith("integrator: "))


def test_r1_pendulum_error_falls_with_the_tolerance():
    # Bob position at 10 s against the pendulum's ODE solved by scipy's
    # DOP853 at rtol 1e-13. h_max = the communication step 0.1 s: the
    # tolerance sizes the substeps, and the automatic choice is explicit.
    exact = solve_ivp(lambda t, y: [y[1], -G * np.cos(y[0])], (0, 10.0), [0.0, 0.0], method="DOP853",
                      rtol=1e-13, atol=1e-13).y[0, -1]
    errors = []
    for tolerance in (1e-4, 1e-6, 1e-8):
        p, log = run(FMUS / "pendulum.fmu", 10.0, 0.1, ["bob.position.x", "bob.position.y"], tolerance,
                     {"solver.h_max": 0.1})
        assert integrator_line(log).startswith("integrator: Dormand-Prince 5(4): rigid scene"), log
        errors.append(np.hypot(p[0] - np.cos(exact), p[1] - np.sin(exact)))
    # Measured: 2.1e-4 (substeps capped at 0.1 s), 1.1e-6, 1.8e-8 m: error
    # per step against tol L (1 s / T), T = 10 s the scene's experiment.
    assert errors[0] > 10 * errors[1] > 100 * errors[2], errors
    assert 0.1e-6 < errors[1] < 10e-6 and 0.1e-8 < errors[2] < 10e-8, errors


def double_pendulum_reference(stop):
    """R2's second bar's centre at `stop` (double_pendulum_path)."""
    return double_pendulum_path([stop])[0]


def double_pendulum_path(times):
    """R2's two uniform bars (1 kg, 1 m, I = 1/12 about the centre) from
    Lagrange's equations in absolute angles, scipy DOP853 at rtol 1e-13:
    the second bar's centre at `times` (rows)."""
    def rhs(t, y):
        p1, p2, w1, w2 = y
        d = p1 - p2
        M = np.array([[4 / 3, 0.5 * np.cos(d)], [0.5 * np.cos(d), 1 / 3]])
        f = -np.array([0.5 * np.sin(d) * w2 ** 2 + 1.5 * G * np.cos(p1), -0.5 * np.sin(d) * w1 ** 2 + 0.5 * G * np.cos(p2)])
        return [w1, w2, *np.linalg.solve(M, f)]
    p1, p2 = solve_ivp(rhs, (0, times[-1]), [0, 0, 0, 0], t_eval=times, method="DOP853", rtol=1e-13,
                       atol=1e-13).y[:2]
    return np.column_stack([np.cos(p1) + 0.5 * np.cos(p2), np.sin(p1) + 0.5 * np.sin(p2)])


def test_r2_double_pendulum_follows_lagranges_equations():
    exact = double_pendulum_reference(2.0)
    for tolerance in (1e-6, 1e-8):  # measured: 6.0e-7, 9.3e-9 m
        p, _ = run(FMUS / "double_pendulum.fmu", 2.0, 0.1, ["bar2.position.x", "bar2.position.y"], tolerance,
                   {"solver.h_max": 0.1})
        assert np.linalg.norm(p - exact) < 10 * tolerance, (tolerance, np.linalg.norm(p - exact))


def sampled(fmu, stop, H, outputs, tolerance, start_values, inputs=None, state_at=None):
    """Outputs at every communication point of a run sampled every H, the
    substeps taken, and the log. inputs: {time: {name: value}} set at those
    communication points. state_at: a time at which the FMU state is saved,
    the run finished, the state restored and the rest run again (the rows
    of the second pass are returned with the first pass's, for comparison)."""
    s = Slave(fmu)
    try:
        s.start(start_values, tolerance=tolerance)
        assert s.call("setDebugLogging", True, ["logStep"]) == OK
        count = int(round(stop / H))

        def run_from(first, rows):
            for k in range(first, count):
                for name, value in (inputs or {}).get(round(k * H, 9), {}).items():
                    assert s.set(name, value) == OK, s.messages()
                if k == saved[0] and saved[1] is None:
                    saved[1] = s.fmu.getFMUstate()
                assert s.step(k * H, H) == OK, s.messages()
                rows.append(s.get(*outputs))
            return rows

        saved = [None if state_at is None else int(round(state_at / H)), None]
        rows = run_from(0, [])
        again = []
        if saved[1] is not None:
            s.fmu.setFMUstate(saved[1])
            again = run_from(saved[0], [])
        substeps = [int(m.split(": substeps ")[1].split(",")[0]) for _, _, m in s.log if ": substeps " in m]
        return np.array(rows), np.array(again), substeps[-1], s.messages()
    finally:
        s.free()


def test_substeps_follow_the_motion_past_communication_points():
    # R2 sampled every 0.01 s with h_max = 0.1 s: while the inputs are held
    # the substeps step past the communication points and the FMU answers
    # there from the method's dense output (order 4, projected like a
    # substep's end). Every sample against Lagrange's equations: the
    # answers are as accurate as the substeps'.
    tolerance = 1e-6
    rows, _, substeps, log = sampled(FMUS / "double_pendulum.fmu", 2.0, 0.01,
                                     ["bar2.position.x", "bar2.position.y"], tolerance, {"solver.h_max": 0.1})
    exact = double_pendulum_path(0.01 * np.arange(1, 201))
    error = np.linalg.norm(rows - exact, axis=1).max()
    # Measured: 1.5e-7 m in 129 substeps (landing on each of the 200
    # communication points: 1.5e-8 m in 212).
    assert error < 10 * tolerance, error
    assert substeps < 160, substeps


def test_the_communication_grid_does_not_shape_the_substeps():
    # With the inputs held the substeps run free of the communication
    # points: sampled every 0.1 s or every 0.025 s, R1 takes the same
    # substeps and answers alike where both sample (only the time
    # arithmetic of the answers differs, at round-off).
    outputs = ["bob.position.x", "bob.position.y"]
    coarse, _, coarse_substeps, _ = sampled(FMUS / "pendulum.fmu", 3.0, 0.1, outputs, 1e-6, {"solver.h_max": 0.5})
    fine, _, fine_substeps, _ = sampled(FMUS / "pendulum.fmu", 3.0, 0.025, outputs, 1e-6, {"solver.h_max": 0.5})
    assert coarse_substeps == fine_substeps
    assert np.abs(coarse - fine[3::4]).max() < 1e-13


def pendulum_with_torque(times, torque, at):
    """R1's bob (1 kg, massless 1 m link, angle from horizontal) with a
    hinge torque from time `at`: theta'' = -g cos(theta) + tau."""
    def rhs(tau):
        return lambda t, y: [y[1], -G * np.cos(y[0]) + tau]
    before = solve_ivp(rhs(0.0), (0, at), [0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    theta = solve_ivp(rhs(torque), (at, times[-1]), before, t_eval=times, method="DOP853", rtol=1e-13,
                      atol=1e-13).y[0]
    return np.column_stack([np.cos(theta), np.sin(theta)])


def test_an_input_change_restarts_from_the_communication_point():
    # The substep taken past t = 0.5 s used the old torque: when the master
    # sets a new one there, the FMU goes on from its answer at 0.5 s, not
    # from that substep (which would keep 0 N m for up to 0.3 s, 1e-2 m).
    torque, at, tolerance = 4.0, 0.5, 1e-8
    rows, _, _, _ = sampled(FMUS / "pendulum.fmu", 1.0, 0.01, ["bob.position.x", "bob.position.y"], tolerance,
                            {"solver.h_max": 0.3}, inputs={at: {"hinge.torque": torque}})
    times = 0.01 * np.arange(1, 101)
    exact = pendulum_with_torque(times[times > at], torque, at)
    # Measured: 3.7e-10 m after the change (49 substeps for 100 points).
    assert np.linalg.norm(rows[times > at] - exact, axis=1).max() < 10 * tolerance


def test_inputs_set_at_every_point_keep_the_landing_substeps():
    # A controller sets a new torque at every communication point: each
    # step lands its substeps there (stepping past, every step would restart
    # from the dense output's answer and add its error, of the order of the
    # estimate: measured 1.9e-6 and 2.3e-8 m at tolerances 1e-6 and 1e-8).
    # Against the exact motion under that piecewise constant torque.
    H, stop = 0.01, 1.0
    times = H * np.arange(int(round(stop / H)))
    torque = 3.0 * np.sin(5 * times)
    state, exact = [0.0, 0.0], []
    for t, tau in zip(times, torque):
        state = solve_ivp(lambda _, y: [y[1], -G * np.cos(y[0]) + tau], (t, t + H), state, method="DOP853",
                          rtol=1e-13, atol=1e-13).y[:, -1]
        exact.append([np.cos(state[0]), np.sin(state[0])])
    for tolerance in (1e-6, 1e-8):  # measured: 9.6e-8, 2.0e-9 m
        rows, _, _, _ = sampled(FMUS / "pendulum.fmu", stop, H, ["bob.position.x", "bob.position.y"], tolerance,
                                {"solver.h_max": 0.3},
                                inputs={round(t, 9): {"hinge.torque": u} for t, u in zip(times, torque)})
        assert np.linalg.norm(rows - np.array(exact), axis=1).max() < tolerance, tolerance


def test_a_state_saved_between_substep_and_answer_repeats_the_run():
    # fmi2GetFMUstate at a communication point inside a substep taken past
    # it saves that substep too: the run after fmi2SetFMUstate is the same
    # to the bit.
    outputs = ["bar2.position.x", "bar2.position.y", "bar2.velocity.x"]
    rows, again, _, _ = sampled(FMUS / "double_pendulum.fmu", 1.0, 0.01, outputs, 1e-6, {"solver.h_max": 0.1},
                                state_at=0.37)
    assert len(again) == 63 and np.array_equal(rows[37:], again)


def x_axis(s, body):
    return Rotation.from_quat(s.get(*[f"{body}.orientation.{c}" for c in "xyzw"])).as_matrix()[:, 0]


def position(s, body):
    return np.array(s.get(*[f"{body}.position.{c}" for c in "xyz"]))


# The cut joint's two ends from the outputs (body frames: x along the bar,
# origin at its centre): four_bar's C is 1.5 m along the coupler and 1.25 m
# along the rocker; slider_crank's pin is the coupler's end (1 m) at the
# slider's origin.
LOOPS = {
    "four_bar": (lambda s: position(s, "coupler") + 1.5 * x_axis(s, "coupler") -
                 position(s, "rocker") - 1.25 * x_axis(s, "rocker"), ["coupler", "rocker"]),
    "slider_crank": (lambda s: position(s, "coupler") + 1.0 * x_axis(s, "coupler") - position(s, "slider"),
                     ["coupler", "slider"]),
}


@pytest.mark.parametrize("name", sorted(LOOPS))
def test_closed_loop_keeps_its_constraint_and_follows_generalized_alpha(name):
    closure, bodies = LOOPS[name]
    outputs = [f"{b}.position.{c}" for b in bodies for c in "xyz"]
    reference, _ = run(FMUS / f"{name}.fmu", 2.0, 0.1, outputs, None, {"solver.h_max": 1e-5})
    tolerance = 1e-6
    drift = []
    p, log = run(FMUS / f"{name}.fmu", 2.0, 0.1, outputs, tolerance, {"solver.h_max": 0.1},
                 each_step=lambda s: drift.append(np.linalg.norm(closure(s))))
    assert integrator_line(log).startswith("integrator: Dormand-Prince"), log
    # Measured (four_bar, slider_crank): drift 4.0e-14, 1.6e-15 m (projected
    # to round-off); off the generalized-alpha run at h = 1e-5 by 7.8e-8 and
    # 9e-16 m (the slider-crank has no freedom: its motion is the drive's).
    assert max(drift) < tolerance, max(drift)
    assert np.abs(p - reference).max() < 10 * tolerance, np.abs(p - reference).max()


def test_bricard_redundant_constraint_keeps_the_motion(tmp_path):
    # R4 with one row redundant along the whole motion. Its right-hand sides
    # were solved as a move along the free motion in every stage: 3.6e-3 m
    # off at tolerance 1e-6 with every step fmi2OK. Now the dependent row is
    # made consistent with the others (measured 3.6e-7 m against
    # generalized-alpha at h = 1e-4, itself about 2e-7 m from converged).
    outputs = [f"rod{i}.position.{c}" for i in range(1, 6) for c in "xyz"]
    reference, _ = run(FMUS / "bricard.fmu", 10.0, 0.1, outputs, None, {"solver.h_max": 1e-4})
    scene = with_method(load_scene("bricard"), "dormand_prince", h_max=0.1)
    p, log = run(packed(scene, tmp_path), 10.0, 0.1, outputs, 1e-6)
    assert integrator_line(log).startswith("integrator: Dormand-Prince"), log
    assert np.abs(p - reference).max() < 1e-5, np.abs(p - reference).max()


def test_slider_crank_drive_is_met_and_the_crank_turns_at_its_rate():
    # The drive omega t as a constraint row: the explicit method integrates
    # its acceleration (zero) exactly but for the round-off of the index-1
    # solve (1e-11 of the accelerations), far below the projections' target
    # (measured: 5e-11 rad, 8e-10 rad/s).
    omega = 2 * np.pi
    angles = []
    run(FMUS / "slider_crank.fmu", 1.0, 0.1, ["crank_pin.angle"], 1e-6, {"solver.h_max": 0.1},
        each_step=lambda s: angles.append(s.get("crank_pin.angle", "crank_pin.angle_rate")))
    t = 0.1 * np.arange(1, 11)
    angles = np.array(angles)
    assert np.abs(angles[:, 0] - omega * t).max() < 1e-9
    assert np.abs(angles[:, 1] - omega).max() < 1e-8


def test_n_four_bar_passes_its_singular_configurations_with_the_explicit_method(tmp_path):
    # R3 with four loops for 3 s (two passes of the cranks through the
    # horizontal, where the loops lose a row each): the positions and
    # velocities projected to round-off after every substep keep the
    # parallelogram branch. (Projected only to a hundredth of the tolerance,
    # the index-1 equations amplified the velocity violation near the
    # singular configuration: off the branch at tolerance 1e-6, 46 J gained.)
    import sys
    from conftest import EXAMPLES
    from test_closed_loops import n_four_bar_checks, n_four_bar_outputs
    sys.path.insert(0, str(EXAMPLES / "n_four_bar"))
    from make_scene import n_four_bar
    N = 4
    fmu = packed(with_method(n_four_bar(N), "dormand_prince", h_max=0.01), tmp_path)
    outputs = n_four_bar_outputs(N)
    for tolerance in (1e-6, 1e-8):
        rows = []
        run(fmu, 3.0, 0.01, outputs, tolerance, each_step=lambda s: rows.append(s.get(*outputs)))
        r = {name: np.array(rows)[:, i] for i, name in enumerate(outputs)}
        phi, branch, energy = n_four_bar_checks(r, N)
        assert np.count_nonzero(np.diff(np.sign(r["crank0.position.y"]))) >= 2  # through the singular position
        # Measured at 1e-6: 2.2e-14 m, 1.1e-12, 5.3e-9 J.
        assert phi < 1e-10 and branch < 1e-8, (tolerance, phi, branch)
        assert np.max(np.abs(energy - energy[0])) < 1e-6 * abs(energy[0]), tolerance


def heavy_top_position(stop):
    """The spinning top's centre of mass in steady precession, exact: it
    turns about the vertical at the slow root W of m g l = W I3 w3 - W^2 (I1
    + m l^2) cos(tilt), from the azimuth -pi/2, at a fixed tilt."""
    m, l, I1, I3, tilt, spin = 1.0, 0.1, 0.01, 0.008, 0.5, 100.0
    a, b, c = (I3 - I1 - m * l * l) * np.cos(tilt), I3 * spin, -m * G * l
    rate = 2 * c / (-b - np.sqrt(b * b - 4 * a * c))
    azimuth = -np.pi / 2 + rate * stop
    return l * np.array([np.sin(tilt) * np.cos(azimuth), np.sin(tilt) * np.sin(azimuth), np.cos(tilt)])


def test_lie_group_chart_keeps_fifth_order_on_a_spherical_joint(tmp_path):
    # A heavy top spinning at 100 rad/s, at substeps of exactly h (a
    # tolerance of 0.9 accepts every one): every stage turns its rotation by
    # the chart's exponential. Halving the substep divides the error by 2^5.
    fmu = packed(with_method(load_scene("spinning_top"), "dormand_prince"), tmp_path)
    errors = []
    for h in (1e-3, 5e-4):
        p, _ = run(fmu, 1.0, 0.01, ["top.position.x", "top.position.y", "top.position.z"], 0.9,
                   {"solver.h_max": h})
        errors.append(np.linalg.norm(p - heavy_top_position(1.0)))
    # Measured: 2.4e-10, 7.4e-12 m (ratio 32.1).
    assert 24 < errors[0] / errors[1] < 40, errors
    assert errors[0] < 1e-9, errors


def test_free_body_under_a_tolerance_follows_eulers_equations(tmp_path):
    # The tumbling body (free joint, intermediate-axis flip) against Euler's
    # equations and R' = R [w] integrated by scipy at rtol 1e-13.
    J = np.array([1.0, 2.0, 3.0])

    def rhs(t, y):
        R, w = y[:9].reshape(3, 3), y[9:]
        return np.concatenate([(R @ np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])).ravel(),
                               -np.cross(w, J * w) / J])
    stop = 4.0
    y = solve_ivp(rhs, (0, stop), np.concatenate([np.eye(3).ravel(), [0.01, 2.0, 0.01]]), method="DOP853",
                  rtol=1e-13, atol=1e-13).y[:, -1]
    exact = y[:9].reshape(3, 3)
    fmu = packed(with_method(load_scene("tumbling_body"), "automatic", h_max=0.1), tmp_path)
    q, log = run(fmu, stop, 0.1, [f"body.orientation.{c}" for c in "xyzw"], 1e-8)
    assert integrator_line(log).startswith("integrator: Dormand-Prince"), log
    error = np.abs(Rotation.from_quat(q).as_matrix() - exact).max()
    assert error < 1e-6, error  # measured: 4.4e-8


def choice(fmu, tolerance, start_values=None):
    s = Slave(fmu)
    try:
        assert s.instantiate(logging_on=True)
        assert s.call("setDebugLogging", True, ["logEvents"]) == OK
        assert s.call("setupExperiment", tolerance, 0.0, None) == OK
        for name, value in (start_values or {}).items():
            assert s.set(name, value) == OK
        assert s.call("enterInitializationMode") == OK, s.messages()
        return integrator_line(s.messages())
    finally:
        s.free()


def test_automatic_choice_logs_which_integrator_and_why(tmp_path):
    pendulum = FMUS / "pendulum.fmu"
    assert choice(pendulum, 1e-6, {"solver.h_max": 0.01}).startswith(
        "integrator: Dormand-Prince 5(4): rigid scene, not stiff: fastest mode at the start")
    assert choice(pendulum, None, {"solver.h_max": 0.01}).startswith(
        "integrator: generalized-alpha: no error tolerance")
    assert choice(pendulum, 1e-6).startswith("integrator: generalized-alpha: h_max = 0.001 s caps the substeps")
    # With flexible bodies the log names where the error estimate is split.
    assert choice(FMUS / "cantilever_vibration.fmu", 1e-4, {"solver.h_max": 0.002}) == (
        "integrator: generalized-alpha: flexible bodies (stiff); the error of modes slower than h_max = 0.002 s "
        "is held per unit step, of faster ones per step (README, Error control)")
    # Stiff springs at h_max = 1e-2: the spring pendulum of k = 1e9 N/m on
    # 1e-3 kg (omega = sqrt(k/m) = 1e6 rad/s) and the chain of 1e6 / 1e-6 kg
    # masses on 1e6 N/m springs (a light mass between two springs: sqrt(2
    # k/m) = 1.41e6 rad/s); the log's three digits.
    for scene, omega in ((spring_pendulum(1e9, 1e-3, 1e-2), 1e6), (mass_chain(1e-2), np.sqrt(2e12))):
        line = choice(packed(scene, tmp_path, scene["name"]), 1e-6)
        assert line.startswith("integrator: generalized-alpha: stiff: fastest mode at the start"), line
        rate = float(line.split("|lambda| = ")[1].split(" ")[0])
        assert abs(rate / omega - 1) < 0.01, line
    assert choice(FMUS / "flyball_governor.fmu", 1e-6).startswith("integrator: generalized-alpha: stiff")
    forced = packed(with_method(load_scene("pendulum"), "dormand_prince"), tmp_path, "forced")
    assert choice(forced, None) == ("integrator: Dormand-Prince 5(4): solver.method, tolerance 1e-04 "
                                    "(experiment.tolerance: none from fmi2SetupExperiment)")


def test_forced_explicit_method_on_a_stiff_spring_is_right_or_discarded(tmp_path):
    # The spring pendulum of test_error_control (k = 1e9 on 1e-3 kg, h_max
    # = 1e-2) forced explicit: substeps at its stability limit (~1e-6 s),
    # bounded by solver.max_substeps per communication step.
    fmu = packed(with_method(spring_pendulum(1e9, 1e-3, 1e-2), "dormand_prince"), tmp_path)
    s = Slave(fmu)
    try:
        s.start(tolerance=1e-4)
        rows, t = [], 0.0
        for _ in range(5):
            status = s.step(t, 0.01)
            if status == DISCARD:
                assert "substeps" in s.messages(), s.messages()
                return
            assert status == OK
            t += 0.01
            rows.append(s.get("block.position.x", "block.position.y", "block.position.z"))
        exact = pendulum_positions(np.arange(1, 6) * 0.01)
        assert np.abs(np.array(rows) - exact).max() < 2e-3
    finally:
        s.free()


def test_forced_explicit_method_on_the_stiff_mass_chain_keeps_its_energy_or_is_discarded(tmp_path):
    # The chain of 1e6 / 1e-6 kg masses (fast mode 1.4e6 rad/s) forced
    # explicit at tolerance 1e-6: its energy (scale 5e3 J) within 1e-3 of it
    # at every communication point, or a discard.
    from test_error_control import chain_energy
    fmu = packed(with_method(mass_chain(1e-3), "dormand_prince"), tmp_path)
    names = [f"s{i}.{q}" for i in range(4) for q in ("position", "position_rate")]
    s = Slave(fmu)
    try:
        s.start(tolerance=1e-6)
        rows, t = [dict(zip(names, s.get(*names)))], 0.0
        for _ in range(5):
            status = s.step(t, 0.01)
            if status == DISCARD:
                assert "substeps" in s.messages(), s.messages()
                return
            assert status == OK
            t += 0.01
            rows.append(dict(zip(names, s.get(*names))))
    finally:
        s.free()
    energy = np.array([chain_energy({k: np.array([r[k]]) for k in r} | {"time": np.zeros(1)})[0] for r in rows])
    assert np.max(np.abs(energy - energy[0])) < 1e-3 * energy[0], energy


def test_forced_explicit_method_on_a_flexible_beam_is_right(tmp_path):
    # The cantilever (F3) forced explicit: its axial modes limit the
    # substeps (a third of them rejected at the stability limit); the tip
    # moves as with generalized-alpha at h = 5e-7 (tolerance 1e-8, L = 1 m:
    # within 1e-8 m and m/s; measured 3e-14 m, 3.2e-10 m/s).
    outputs = ["beam.node16.position.y", "beam.node16.velocity.y"]
    reference, _ = run(FMUS / "cantilever_vibration.fmu", 0.02, 0.01, outputs, None, {"solver.h_max": 5e-7})
    fmu = packed(with_method(load_scene("cantilever_vibration"), "dormand_prince"), tmp_path)
    p, log = run(fmu, 0.02, 0.01, outputs, 1e-8)
    assert "flexible bodies are stiff" in integrator_line(log)
    assert np.abs(p - reference).max() < 1e-8, (p, reference)
