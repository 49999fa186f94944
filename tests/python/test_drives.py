"""Drives of rigid joints from an FMI input: the input is the coordinate's
rate, held over a communication step; the coordinate integrates it, a rate
that jumps makes the velocities jump by the drive's impulse, and the drive
torque output is checked against Newton-Euler by hand."""
import numpy as np
import pytest

from conftest import Slave, packed

G = 9.81
L1, L2, M1, M2 = 1.0, 0.8, 1.0, 0.5


def driven_double_pendulum(initial_rate):
    """Two point masses; the first hinge's angle follows the input
    hinge1.drive_rate, the second hinge swings freely."""
    return {
        "format": "mfbd-scene/1", "name": "driven_double_pendulum",
        "description": "first hinge driven by a rate input, second hinge free",
        "gravity": [0, -G, 0], "solver": {"h_max": 1e-3, "rho_inf": 0.8},
        "bodies": [{"name": "bob1", "mass": M1, "inertia": [0, 0, 0], "position": [L1, 0, 0]},
                   {"name": "bob2", "mass": M2, "inertia": [0, 0, 0], "position": [L1 + L2, 0, 0]}],
        "joints": [{"name": "hinge1", "type": "revolute", "parent": "ground", "child": "bob1", "position": [0, 0, 0],
                    "drive": {"rate_input": True}, "initial": {"rates": [initial_rate]}},
                   {"name": "hinge2", "type": "revolute", "parent": "bob1", "child": "bob2",
                    "position": [L1, 0, 0]}]}


def cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def hand_drive_torque(p1, p2, w1, w2):
    """Newton-Euler with the first hinge's angular acceleration zero (the rate
    is held): link 2's moment balance about hinge 2 gives its angular
    acceleration, and the drive torque is the rate of angular momentum about
    the origin minus the moment of gravity."""
    a1 = -w1 ** 2 * p1
    r = p2 - p1
    alpha2 = (-G * r[0] - cross(r, a1)) / (r @ r)
    a2 = a1 + alpha2 * np.array([-r[1], r[0]]) - w2 ** 2 * r
    return M2 * cross(p2, a2) + G * (M1 * p1[0] + M2 * p2[0])


def run(fmu, rates, H=0.01):
    s = Slave(fmu, instance_name="drive")
    rows = []
    try:
        s.start()
        t = 0.0
        for rate in rates:
            assert s.set("hinge1.drive_rate", rate) == 0
            assert s.step(t, H) == 0, s.messages()
            t += H
            p1, p2 = (np.array(s.get(f"{b}.position.x", f"{b}.position.y")) for b in ("bob1", "bob2"))
            w1, w2 = s.get("bob1.angular_velocity.z", "bob2.angular_velocity.z")
            rows.append((t, s.get("hinge1.angle"), s.get("hinge1.angle_rate"), s.get("hinge1.drive_torque"),
                         hand_drive_torque(p1, p2, w1, w2)))
    finally:
        s.free()
    return np.array(rows)


# Both integrators (the explicit one at the experiment's tolerance, 1e-4).
METHODS = ["generalized_alpha", "dormand_prince"]


def with_method(scene, method):
    scene["solver"]["method"] = method
    return scene


@pytest.mark.parametrize("method", METHODS)
def test_constant_rate_input_drive_torque_matches_newton_euler(tmp_path, method):
    omega = 3.0
    r = run(packed(with_method(driven_double_pendulum(omega), method), tmp_path), [omega] * 200)
    t, angle, rate, torque, hand = r.T
    assert np.max(np.abs(angle - omega * t)) < 1e-12
    assert np.max(np.abs(rate - omega)) < 1e-9
    assert np.ptp(hand) > 10.0  # gravity and the swinging second link both load the drive
    assert np.max(np.abs(torque - hand)) < 1e-8 * np.max(np.abs(hand))


@pytest.mark.parametrize("method", METHODS)
def test_rate_input_held_over_each_step_and_jumps_by_an_impulse(tmp_path, method):
    # The master changes the rate at every communication point. The angle is
    # the sum of the held rates times the step; right after each step the
    # joint turns at the rate just held (the velocities jumped at the step
    # start by the impulse that meets the new rate); the torque at the
    # communication points is again the hand Newton-Euler value.
    H = 0.01
    rates = 2.0 * np.sin(np.arange(300) * H) + 1.0
    r = run(packed(with_method(driven_double_pendulum(0.0), method), tmp_path), rates, H)
    t, angle, rate, torque, hand = r.T
    assert np.max(np.abs(angle - np.cumsum(rates) * H)) < 1e-12
    assert np.max(np.abs(rate - rates)) < 1e-9
    assert np.max(np.abs(torque - hand)) < 1e-8 * np.max(np.abs(hand))
