"""Flexible bodies through the FMU against shared/benchmarks F1-F4."""
import copy

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from conftest import Slave, load_scene, packed

# F2: inextensible elastica under a tip dead load, alpha = P L^2 / (E I).
F2 = {1: (0.05643, 0.30172), 2: (0.16064, 0.49346), 4: (0.32894, 0.66996), 6: (0.43459, 0.74457),
      8: (0.50483, 0.78498), 10: (0.55500, 0.81061)}


def with_elements(scene, n):
    s = copy.deepcopy(scene)
    body = s["flexible_bodies"][0]
    body["beam"]["elements"] = n
    for item in body.get("loads", []) + body.get("point_masses", []):
        if item["node"] != 0:
            item["node"] = n
    body["outputs"] = {"nodes": [n]}
    return s


def end_moment_tip_errors(tmp_path, n):
    fmu = packed(with_elements(load_scene("cantilever_moment"), n), tmp_path, f"moment{n}")
    r = simulate_fmu(fmu, output=[f"beam.node{n}.position.x", f"beam.node{n}.position.y"])
    errors = []
    for lam in (0.25, 0.5, 0.75, 1.0):
        i = int(np.argmin(np.abs(r["time"] - lam)))
        phi = 2 * np.pi * lam
        exact = (np.sin(phi) / phi, (1 - np.cos(phi)) / phi)
        errors.append(np.hypot(r[f"beam.node{n}.position.x"][i] - exact[0], r[f"beam.node{n}.position.y"][i] - exact[1]))
    return np.array(errors)


def test_end_moment_rolls_the_cantilever_into_a_circle(tmp_path):
    e16, e32, e64 = (end_moment_tip_errors(tmp_path, n) for n in (16, 32, 64))
    assert e16.max() < 1e-2 and e64.max() < 1e-3, (e16, e64)
    assert e16[-1] < 1e-9 and e64[-1] < 1e-9  # the full circle closes exactly (a regular polygon)
    # Fourth order (the issue asks for at least second): the shallow-arch
    # strain puts the nodes on the circle's chords to O(alpha^4) (the linear
    # local element kept the chords at L / n, second order).
    for coarse, fine in ((e16, e32), (e32, e64)):
        order = np.log2(coarse[:3] / fine[:3])
        assert np.all(np.abs(order - 4.0) < 0.1), order


def test_tip_dead_load_matches_the_elastica_table(tmp_path):
    scene = with_elements(load_scene("cantilever_moment"), 32)
    body = scene["flexible_bodies"][0]
    body["loads"] = [{"node": 32, "force": [0, "-10*EI/L^2", 0], "scale": "t"}]  # alpha = 10 t
    scene["experiment"] = {"stop_time": 1.0, "output_interval": 0.1}
    scene["solver"]["h_max"] = 0.02
    r = simulate_fmu(packed(scene, tmp_path), output=["beam.node32.position.x", "beam.node32.position.y"])
    for alpha, (u, w) in F2.items():
        i = int(np.argmin(np.abs(r["time"] - alpha / 10)))
        assert abs((1.0 - r["beam.node32.position.x"][i]) - u) < 1e-3, alpha
        assert abs(-r["beam.node32.position.y"][i] - w) < 1e-3, alpha


def mode_shape(x, beta_l):
    """Cantilever bending mode of a clamped-free Euler-Bernoulli beam, L = 1."""
    s = (np.sinh(beta_l) - np.sin(beta_l)) / (np.cosh(beta_l) + np.cos(beta_l))
    return np.cosh(beta_l * x) - np.cos(beta_l * x) - s * (np.sinh(beta_l * x) - np.sin(beta_l * x))


def fitted_frequencies(t, y, guesses):
    """Frequencies of a sum of undamped sinusoids (plus offset), least squares
    over the frequencies with the amplitudes solved linearly."""
    from scipy.optimize import least_squares

    y = (y - y.mean()) / y.std()  # unit scale, so the solver's tolerances mean something

    def residual(f):
        w = 2 * np.pi * np.asarray(f)
        basis = np.column_stack([np.ones_like(t)] + [g(wi * t) for wi in w for g in (np.cos, np.sin)])
        amplitudes = np.linalg.lstsq(basis, y, rcond=None)[0]
        return basis @ amplitudes - y

    fit = least_squares(residual, guesses, x_scale=0.01, xtol=1e-12, ftol=1e-12, gtol=1e-12)
    assert fit.success and np.all(fit.x != guesses)
    return fit.x


def released_response(fmu, outputs, hold=3.0, record=6.0, h=0.01):
    """Runs the FMU while its loads (scaled off at `hold`) and the beam's
    tunable damping settle it, switches the damping off at `hold`, and records
    `outputs` for `record` seconds of free response: (times, {name: values})."""
    s = Slave(fmu)
    try:
        s.start()
        t = 0.0
        for _ in range(int(round(hold / h))):
            assert s.step(t, h) == 0
            t += h
        assert s.set("beam.damping", 0.0) == 0
        ts, values = [], {name: [] for name in outputs}
        for _ in range(int(round(record / h))):
            assert s.step(t, h) == 0
            t += h
            ts.append(t)
            for name in outputs:
                values[name].append(s.get(name))
    finally:
        s.free()
    return np.array(ts), {name: np.array(v) for name, v in values.items()}


def free_vibration_frequency(tmp_path, n, beta_l):
    """Loads M phi (a static deflection in the mode's shape), released at
    t = 3 s; damping (tunable) holds until then. The frequency of that mode
    from a fit of the first two modes to the free response."""
    scene = with_elements(load_scene("cantilever_vibration"), n)
    body = scene["flexible_bodies"][0]
    x = np.arange(n + 1) / n
    mass = np.full(n + 1, 1.0 / n)
    mass[-1] /= 2
    body["loads"] = [{"node": int(i), "force": [0, float(1e-3 * mass[i] * mode_shape(x[i], beta_l)), 0],
                      "scale": "if(3 - t, 1, 0)"} for i in range(1, n + 1)]
    body["damping"] = 0.3
    scene["solver"] = {"h_max": 1e-3, "rho_inf": 0.9}
    ts, out = released_response(packed(scene, tmp_path, f"vibration{n}"), [f"beam.node{n}.position.y"])
    ys = out[f"beam.node{n}.position.y"]
    guesses = np.array([1.875104, 4.694091]) ** 2 / (2 * np.pi)
    f = fitted_frequencies(np.array(ts), np.array(ys), guesses)
    return f[0] if beta_l < 2 else f[1]


def test_first_two_bending_frequencies(tmp_path):
    exact = np.array([1.875104, 4.694091]) ** 2 / (2 * np.pi)  # EI = rhoA = L = 1
    # Consistent element mass (the default): -3e-6 and -5e-5 measured here
    # at 16 elements (the linear eigenvalues: -2e-6, -1e-5; lumped: -0.18 %,
    # -0.62 %).
    f1 = free_vibration_frequency(tmp_path, 16, 1.875104)
    assert abs(f1 / exact[0] - 1) < 5e-3, f1
    f2 = free_vibration_frequency(tmp_path, 16, 4.694091)
    assert abs(f2 / exact[1] - 1) < 5e-3, f2


def spin_up(tmp_path, n, h, stop, name, mass="consistent"):
    scene = load_scene("spin_up_beam")
    scene["flexible_bodies"][0]["beam"]["elements"] = n
    scene["flexible_bodies"][0]["mass"] = mass
    scene["flexible_bodies"][0]["outputs"] = {"nodes": "all", "elements": [0]}
    scene["solver"]["h_max"] = h
    fmu = packed(scene, tmp_path, name)
    outputs = [f"beam.node{i}.position.{c}" for i in range(n + 1) for c in "xy"] + ["beam.element0.end1.force.x"]
    r = simulate_fmu(fmu, stop_time=stop, output_interval=0.05, output=outputs)
    t = r["time"]
    p = np.stack([np.stack([r[f"beam.node{i}.position.x"], r[f"beam.node{i}.position.y"]], 1) for i in range(n + 1)], 1)
    hub = np.where(t <= 15, 6 / 15 * (t ** 2 / 2 + (15 / (2 * np.pi)) ** 2 * (np.cos(2 * np.pi * t / 15) - 1)),
                   45 + 6 * (t - 15))
    tip_rotating = -np.sin(hub) * p[:, -1, 0] + np.cos(hub) * p[:, -1, 1]
    length = np.sum(np.linalg.norm(np.diff(p, axis=1), axis=2), axis=1)
    return t, tip_rotating, length, r["beam.element0.end1.force.x"]


# F4 steady state at omega = 6 rad/s: elongation of the bar under its own
# centrifugal load, EA u'' + rhoA omega^2 (x + u) = 0, u(0) = 0, u'(L) = 0:
# u(L) = tan(k L)/k - L with k^2 = rhoA omega^2 / EA (first order:
# rhoA omega^2 L^3 / (3 EA) = 5.142857e-4); root force rhoA omega^2 L^2 / 2.
SPIN_K = np.sqrt(1.2 * 36 / 2.8e7)
SPIN_ELONGATION = np.tan(10 * SPIN_K) / SPIN_K - 10  # 5.143175e-4 m


def test_spin_up_beam_steady_elongation_and_root_force(tmp_path):
    t, _, length, root_force = spin_up(tmp_path, 8, 2e-3, 25.0, "spin8")
    steady = t > 18
    assert abs(np.mean(length[steady] - 10.0) - SPIN_ELONGATION) < 1e-7
    assert abs(np.mean(root_force[steady]) / 2160.0 - 1) < 1e-3


def test_consistent_mass_gets_the_spin_up_elongation_at_four_elements(tmp_path):
    # The consistent mass's axial part is the linear bar's
    # (flex/consistent_mass.hpp), so its centrifugal load is the Galerkin
    # load: a few 1e-9 m off at 4 elements in the steady linear problem;
    # lumped nodal masses load the bar 1.61e-5 m too much (3 %), falling as
    # 1/N^2.
    errors = {}
    for mass in ("consistent", "lumped"):
        t, _, length, _ = spin_up(tmp_path, 4, 2e-3, 25.0, f"spin4{mass}", mass)
        errors[mass] = np.mean(length[t > 18] - 10.0) - SPIN_ELONGATION
    assert abs(errors["consistent"]) < 1e-7, errors
    assert abs(errors["lumped"] / 1.608e-5 - 1) < 0.05, errors


def test_spin_up_tip_deflection_converges_in_time_and_space(tmp_path):
    def peak(n, h):
        t, tip, _, _ = spin_up(tmp_path, n, h, 10.0, f"spin{n}_{h}")
        return tip[np.argmin(np.abs(t - 7.0))]
    space = [peak(n, 2e-3) for n in (4, 8, 16)]
    time = [peak(8, h) for h in (8e-3, 4e-3, 2e-3)]
    for label, (a, b, c) in (("space", space), ("time", time)):
        assert abs(c - b) < 0.5 * abs(b - a), (label, a, b, c)  # differences shrink under refinement
    assert -0.6 < space[-1] < -0.5  # the deflection lags the hub by about half a metre


def test_a_scene_exposes_only_the_nodes_it_lists(tmp_path):
    scene = load_scene("cantilever_moment")
    body = scene["flexible_bodies"][0]
    body["beam"]["elements"] = 1000
    body["loads"][0]["node"] = 1000
    body["outputs"] = {"nodes": [500, 1000]}
    md = read_model_description(str(packed(scene, tmp_path)))
    nodes = {v.name.split(".")[1] for v in md.modelVariables if v.name.startswith("beam.node")}
    assert nodes == {"node500", "node1000"}
    body["outputs"] = {}
    md = read_model_description(str(packed(scene, tmp_path, "none")))
    assert not [v for v in md.modelVariables if v.causality == "output"]


def test_rate_input_drives_the_support_rotation(tmp_path):
    scene = load_scene("spin_up_beam")
    body = scene["flexible_bodies"][0]
    body["supports"] = [{"node": 0, "type": "driven", "axis": [0, 0, 1], "rate_input": True}]
    body["outputs"] = {"nodes": [0]}
    s = Slave(packed(scene, tmp_path))
    try:
        s.start()
        t = 0.0
        for rate, steps in ((0.5, 100), (-2.0, 50), (1.0, 30)):  # rad/s, held over 0.01 s steps
            assert s.set("beam.node0.drive_rate", rate) == 0
            for _ in range(steps):
                assert s.step(t, 0.01) == 0
                t += 0.01
        angle = 0.5 * 1.0 - 2.0 * 0.5 + 1.0 * 0.3
        w, z = s.get("beam.node0.orientation.w", "beam.node0.orientation.z")
        assert abs(2 * np.arctan2(z, w) - angle) < 1e-12
        assert abs(s.get("beam.node0.angular_velocity.z") - 1.0) < 1e-12
    finally:
        s.free()


def test_input_tip_load_deflects_a_static_cantilever(tmp_path):
    scene = with_elements(load_scene("cantilever_moment"), 8)
    body = scene["flexible_bodies"][0]
    body["loads"] = [{"node": 8, "input": True}]
    scene["experiment"] = {"stop_time": 1.0, "output_interval": 0.5}
    s = Slave(packed(scene, tmp_path))
    try:
        s.start()
        P = 1e-4  # small: linear, P L^3 / (3 EI) (shear-rigid section)
        assert s.set("beam.node8.force.y", P) == 0
        assert s.step(0.0, 0.5) == 0
        assert abs(s.get("beam.node8.position.y") / (P / 3.0) - 1) < 1e-6
        assert s.set("beam.node8.force.y", 0.0) == 0
        assert s.step(0.5, 0.5) == 0
        assert abs(s.get("beam.node8.position.y")) < 1e-14  # unloaded again
    finally:
        s.free()


def test_static_load_path_with_kinks_is_followed(tmp_path):
    # Load stepping predicts each step from the last one along the path; where
    # the path turns back (t = 0.5) or jumps (t = 0.775) the prediction is wrong
    # and Newton must still land on the equilibrium: linear, P L^3/(3 EI).
    scene = with_elements(load_scene("cantilever_moment"), 8)
    P = 1e-4
    scale = "if(0.5 - t, t, if(0.775 - t, 1 - t, 2))"
    scene["flexible_bodies"][0]["loads"] = [{"node": 8, "force": [0, P, 0], "scale": scale}]
    scene["experiment"] = {"stop_time": 1.0, "output_interval": 0.05}
    r = simulate_fmu(packed(scene, tmp_path), output=["beam.node8.position.y"])
    t = r["time"]
    factor = np.where(t <= 0.5, t, np.where(t <= 0.775, 1 - t, 2.0))
    assert np.max(np.abs(r["beam.node8.position.y"] - P / 3 * factor)) < 1e-6 * P / 3
