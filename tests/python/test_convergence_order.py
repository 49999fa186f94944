"""Generalized-alpha keeps its order two as h shrinks, in closed loops and
trees, and whatever the Newton tolerance: the Newton error left in a substep
is bounded in q, v and vdot (a position error d is a velocity error ~d/h
and an acceleration error ~d/h^2), so it stays below the discretisation
error. Errors against an exact reference (R5 slider-crank kinematics), an
independent high-order solution (DOP853 on the double pendulum's
minimal-coordinate equations) or, for the four-bar's motion, energy and a
run at a much finer h. Runs of 1 s or less; h down to 1e-5 (benchmarks/
README.md has 1e-6)."""
import numpy as np
from fmpy import simulate_fmu
from scipy.integrate import solve_ivp

from conftest import FMUS

G = 9.81
FOUR_BAR = {"crank": 1.0, "coupler": 3.0, "rocker": 2.5}


def run(fmu, stop, h, outputs, tolerance=None):
    start = {"solver.h_max": h}
    if tolerance is not None:
        start["solver.tolerance"] = tolerance
    return simulate_fmu(FMUS / fmu, stop_time=stop, output_interval=0.01, start_values=start, output=outputs)


def four_bar(h, tolerance=None):
    """Largest energy change over 1 s and the crank angle at 1 s."""
    outputs = ["A.angle"] + [f"{b}.{q}.{c}" for b in FOUR_BAR for q in ("position", "velocity") for c in "xy"]
    outputs += [f"{b}.angular_velocity.z" for b in FOUR_BAR]
    r = run("four_bar.fmu", 1.0, h, outputs, tolerance)
    energy = sum(0.5 * (r[f"{b}.velocity.x"] ** 2 + r[f"{b}.velocity.y"] ** 2)
                 + 0.5 * L * L / 12 * r[f"{b}.angular_velocity.z"] ** 2 + G * r[f"{b}.position.y"]
                 for b, L in FOUR_BAR.items())
    return np.max(np.abs(energy - energy[0])), r["A.angle"][-1]


def test_four_bar_energy_and_motion_converge_as_h_squared():
    # Measured (energy over 1 s): 2.80e-6, 2.80e-8, 1.7e-10 J at h = 1e-3,
    # 1e-4, 1e-5 (before: 2.80e-6, 1.5e-7, 8.9e-6: the Newton error grew
    # as h shrank).
    steps = [1e-3, 1e-4, 1e-5]
    runs = [four_bar(h) for h in steps]
    fine = four_bar(2.5e-6)[1]
    energy = [e for e, _ in runs]
    angle = [abs(a - fine) for _, a in runs]
    # h^2: 100 per decade; order 2 +- 0.25 allows 56..316 (the angle at 1e-5,
    # 1.3e-10 off the run at 2.5e-6, measured 167 after 1e-4).
    for k in range(2):
        assert energy[k] / energy[k + 1] > 56, energy
        assert 56 < angle[k] / angle[k + 1] < 316, angle


def test_four_bar_motion_does_not_depend_on_the_newton_tolerance():
    # Tolerances 1e-10 .. 1e-16 land on the same motion to a small fraction
    # of the discretisation error (before: at h = 1e-4 the energy error was
    # 3.6e-6 J at 1e-10 and 1.5e-7 J at 1e-14).
    h = 1e-4
    reference = four_bar(h, 1e-16)
    fine = four_bar(1e-5)[1]
    discretisation = abs(reference[1] - fine)
    for tolerance in (1e-10, 1e-12, 1e-14):
        energy, angle = four_bar(h, tolerance)
        assert abs(angle - reference[1]) < 0.05 * discretisation, (tolerance, angle - reference[1], discretisation)
        assert abs(energy - reference[0]) < 0.05 * reference[0], (tolerance, energy, reference[0])


def test_slider_crank_velocity_and_drive_torque_converge_as_h_squared():
    # R5: crank driven at omega = 2 pi; the slider's velocity against the
    # derivative of the exact kinematics, the drive torque against a run at
    # a much finer h.
    outputs = ["crank_pin.angle", "slider.velocity.x", "crank_pin.drive_torque"]
    r_, l, e, omega = 0.5, 2.0, 0.1, 2 * np.pi

    def errors(h):
        r = run("slider_crank.fmu", 0.5, h, outputs)
        theta = r["crank_pin.angle"]
        s = r_ * np.sin(theta) - e
        exact = omega * (-r_ * np.sin(theta) - s * r_ * np.cos(theta) / np.sqrt(l * l - s * s))
        return np.max(np.abs(r["slider.velocity.x"] - exact)), r["crank_pin.drive_torque"]

    fine = errors(2.5e-6)[1]
    velocity, torque = zip(*[(v, np.max(np.abs(t - fine))) for v, t in map(errors, [1e-3, 1e-4, 1e-5])])
    for k in range(2):
        assert 60 < velocity[k] / velocity[k + 1] < 160, velocity
    # The torque at h = 1e-5 is within 5e-9 N m of the finest run's, the
    # round-off of the consistent solve it comes from (measured 6.7e-6,
    # 6.7e-8, 5.3e-9 N m at h = 1e-3, 1e-4, 1e-5).
    assert 60 < torque[0] / torque[1] < 160, torque
    assert torque[2] < 1e-8, torque


def double_pendulum_reference():
    """R2 (two uniform 1 kg, 1 m bars from horizontal, at rest) in the
    absolute angles p1, p2 of the bars: Lagrange's equations with
    T = 1/2 (m L^2/3) w1^2 + 1/2 m (L^2 w1^2 + L^2/4 w2^2 + L^2 w1 w2 cos(p1 - p2))
    + 1/2 (m L^2/12) w2^2 and V = m g (3L/2 sin p1 + L/2 sin p2)."""
    def rhs(t, y):
        p1, p2, w1, w2 = y
        c, s = np.cos(p1 - p2), np.sin(p1 - p2)
        M = np.array([[4 / 3, c / 2], [c / 2, 1 / 3]])
        f = -np.array([s * w2 ** 2 / 2 + 1.5 * G * np.cos(p1), -s * w1 ** 2 / 2 + 0.5 * G * np.cos(p2)])
        return [w1, w2, *np.linalg.solve(M, f)]
    return solve_ivp(rhs, (0, 2), [0, 0, 0, 0], method="DOP853", rtol=1e-13, atol=1e-13).y[:2, -1]


def tip(p1, p2):
    return np.array([np.cos(p1) + np.cos(p2), np.sin(p1) + np.sin(p2)])


def test_double_pendulum_tip_converges_as_h_squared_to_an_independent_solution():
    # Measured tip error at t = 2 s: 1.22e-6, 3.05e-7, 7.62e-8 m at
    # h = 2e-4, 1e-4, 5e-5 (before: 3.3e-7 at 1e-4 but 1.8e-7 at 5e-5).
    exact = tip(*double_pendulum_reference())
    error = []
    for h in (2e-4, 1e-4, 5e-5):
        r = run("double_pendulum.fmu", 2.0, h, ["shoulder.angle", "elbow.angle"])
        p1 = r["shoulder.angle"][-1]
        error.append(np.linalg.norm(tip(p1, p1 + r["elbow.angle"][-1]) - exact))
    for k in range(2):
        assert 3.6 < error[k] / error[k + 1] < 4.4, error
    assert error[-1] < 1e-7, error
