"""Rigid trees through the FMU: conservation and steady motions with
analytic references (double pendulum R2, free body, heavy top)."""
import numpy as np
from fmpy import simulate_fmu
from scipy.spatial.transform import Rotation

from conftest import FMUS, simulate_fixed_step

G = 9.81


def double_pendulum_energy_drift(h):
    outputs = [f"bar{i}.{q}.{c}" for i in (1, 2) for q in ("position", "velocity") for c in "xy"]
    outputs += ["bar1.angular_velocity.z", "bar2.angular_velocity.z"]
    r = simulate_fixed_step(FMUS / "double_pendulum.fmu", start_values={"solver.h_max": h, "solver.rho_inf": 1.0},
                     output=outputs)
    energy = sum(0.5 * (r[f"bar{i}.velocity.x"] ** 2 + r[f"bar{i}.velocity.y"] ** 2)
                 + 0.5 / 12.0 * r[f"bar{i}.angular_velocity.z"] ** 2 + G * r[f"bar{i}.position.y"] for i in (1, 2))
    return np.max(np.abs(energy - energy[0])) / G  # in units of m g L (m = L = 1)


def test_double_pendulum_energy_drift_is_small_and_second_order():
    coarse, fine = double_pendulum_energy_drift(2e-4), double_pendulum_energy_drift(1e-4)
    assert fine < 1e-5, fine
    assert 3.0 < coarse / fine < 5.0, (coarse, fine)  # h^2


def test_free_body_near_its_intermediate_axis_keeps_energy_and_momentum_and_flips():
    r = simulate_fmu(FMUS / "tumbling_body.fmu",
                     output=[f"body.orientation.{c}" for c in "wxyz"] + [f"body.angular_velocity.{c}" for c in "xyz"])
    A = Rotation.from_quat(np.column_stack([r[f"body.orientation.{c}"] for c in "xyzw"])).as_matrix()
    w = np.einsum("nji,nj->ni", A, np.column_stack([r[f"body.angular_velocity.{c}"] for c in "xyz"]))  # body frame
    J = np.diag([1.0, 2.0, 3.0])
    kinetic = 0.5 * np.einsum("ni,ij,nj->n", w, J, w)
    momentum = np.linalg.norm(w @ J, axis=1)
    assert np.max(np.abs(kinetic / kinetic[0] - 1)) < 1e-5
    assert np.max(np.abs(momentum / momentum[0] - 1)) < 1e-5
    # The intermediate (y) axis turns over: it points backwards at some time.
    assert A[:, 1, 1].min() < -0.99


def test_heavy_top_precesses_at_the_steady_rate():
    r = simulate_fmu(FMUS / "spinning_top.fmu", output=["top.position.x", "top.position.y", "top.position.z"])
    m, l, I1, I3, tilt, spin = 1.0, 0.1, 0.01, 0.008, 0.5, 100.0
    # Slow root of m g l = W I3 (spin + W cos tilt) - W^2 (I1 + m l^2) cos tilt (I1 about the pivot).
    a, b, c = (I3 - I1 - m * l * l) * np.cos(tilt), I3 * spin, -m * G * l
    steady = 2 * c / (-b - np.sqrt(b * b - 4 * a * c))
    azimuth = np.unwrap(np.arctan2(r["top.position.y"], r["top.position.x"]))
    rate = np.polyfit(r["time"], azimuth, 1)[0]
    assert abs(rate / steady - 1) < 1e-4, (rate, steady)
    assert np.ptp(np.arccos(r["top.position.z"] / l)) < 1e-5  # no nutation
