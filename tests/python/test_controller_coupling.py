"""The masters of the co-simulation study (benchmarks/cosim_coupling.py) on its
linear loop, two PID controller FMUs: a P controller (Kp = 20, setpoint 1)
and an integrator plant, x' = 20 (1 - x). Both FMUs step exactly for held or
ramped inputs, so each master is a known one-step method of that ODE and its
communication-point values follow that method's recurrence to round-off:
Gauss-Seidel with held inputs is explicit Euler, interpolation with slopes
extrapolated from the last two points is the second-order Adams-Bashforth
method, and the rollback master iterated to a fixed point with ramped inputs
is the trapezoidal rule."""
import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "benchmarks"))
import cosim_coupling  # noqa: E402

K, H, STOP = 20.0, 0.01, 0.2


def x_of(master, tmp_path):
    t, x, iterations, *_ = cosim_coupling.run(cosim_coupling.linear_system, master, H, STOP, tmp_path)
    return x[:, 0], iterations


def test_gauss_seidel_with_held_inputs_is_explicit_euler(tmp_path):
    x, iterations = x_of("zoh_gauss_seidel", tmp_path)
    n = np.arange(len(x))
    assert iterations == 1
    assert np.max(np.abs(x - (1 - (1 - K * H) ** n))) < 1e-14


def test_jacobi_with_held_inputs_lags_one_step(tmp_path):
    # The plant gets the command computed from x of the step before:
    # x_(n+1) = x_n + H K (1 - x_(n-1)), the first step Gauss-Seidel.
    x, _ = x_of("zoh_jacobi", tmp_path)
    expected = [0.0, H * K]
    while len(expected) < len(x):
        expected.append(expected[-1] + H * K * (1 - expected[-2]))
    assert np.max(np.abs(x - expected)) < 1e-14


def test_interpolation_with_extrapolated_slopes_is_adams_bashforth(tmp_path):
    # u_n = K (1 - x_n) ramped with slope (u_n - u_(n-1))/H: x_(n+1) = x_n +
    # H (3 u_n - u_(n-1))/2; the first step Euler.
    x, _ = x_of("interpolation", tmp_path)
    expected = [0.0, H * K]
    while len(expected) < len(x):
        u, u_before = K * (1 - expected[-1]), K * (1 - expected[-2])
        expected.append(expected[-1] + H * (3 * u - u_before) / 2)
    assert np.max(np.abs(x - expected)) < 1e-14


def test_rollback_to_a_fixed_point_is_the_trapezoidal_rule(tmp_path):
    x, iterations = x_of("rollback", tmp_path)
    n = np.arange(len(x))
    amplification = (1 - K * H / 2) / (1 + K * H / 2)
    assert np.max(np.abs(x - (1 - amplification ** n))) < 1e-10  # the iteration stops at 1e-10
    assert 2 < iterations < 15  # contraction K H / 2 = 0.1 a sweep


@pytest.mark.parametrize("master,order", [("zoh_gauss_seidel", 1), ("interpolation", 2), ("rollback", 2)])
def test_coupling_error_orders(master, order, tmp_path):
    errors = []
    for step in [2e-3, 1e-3]:
        t, x, *_ = cosim_coupling.run(cosim_coupling.linear_system, master, step, STOP, tmp_path)
        errors.append(np.max(np.abs(x - cosim_coupling.linear_exact(t))))
    assert abs(np.log2(errors[0] / errors[1]) - order) < 0.25, errors


def test_rollback_with_a_plant_that_holds_its_inputs_is_still_trapezoidal(tmp_path):
    # A plant without input derivatives gets the mean of the step's start and
    # end inputs, held: for this integrator the same trapezoidal rule.
    def holding_plant(workdir):
        system = cosim_coupling.linear_system(workdir)
        system.plant.can_interpolate = False
        return system

    t, x, *_ = cosim_coupling.run(holding_plant, "rollback", H, STOP, tmp_path)
    amplification = (1 - K * H / 2) / (1 + K * H / 2)
    assert np.max(np.abs(x[:, 0] - (1 - amplification ** np.arange(len(t))))) < 1e-10
