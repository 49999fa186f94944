"""Rigid and flexible bodies together (issue 5): joints and force elements on
flexible nodes through virtual bodies and flexible body joints, one Newton
solve. Each test against an analytic value or an equivalent model."""
import copy

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from scipy.optimize import brentq

from conftest import EXAMPLES, Slave, load_scene, packed, simulate_fixed_step
from test_flexible import fitted_frequencies, released_response


def cantilever(n, EI=10.0, rhoA=1.0, damping=0.0):
    """A clamped beam of length 1 along x, slender (EA = 1e6 EI)."""
    return {"name": "beam", "beam": {"start": [0, 0, 0], "end": [1, 0, 0], "elements": n, "section_y": [0, 1, 0]},
            "section": {"EA": 1e6 * EI, "GJ": EI, "EIy": EI, "EIz": EI, "rhoA": rhoA,
                        "rhoJ": [2e-6 * rhoA, 1e-6 * rhoA, 1e-6 * rhoA]},
            "supports": [{"node": 0, "type": "clamp"}], "damping": damping}


def tip_mass_frequencies(mu, EI=10.0):
    """First two bending frequencies (Hz) of a clamped Euler-Bernoulli beam
    (L = rhoA = 1) with a tip point mass mu rhoA L: roots of
    1 + cos l cosh l + mu l (cos l sinh l - sin l cosh l) = 0."""
    g = lambda l: 1 + np.cos(l) * np.cosh(l) + mu * l * (np.cos(l) * np.sinh(l) - np.sin(l) * np.cosh(l))
    roots = [brentq(g, 0.5, 1.87), brentq(g, 3.0, 4.6)]
    return np.array(roots) ** 2 * np.sqrt(EI) / (2 * np.pi)


def tip_body_frequencies(tmp_path, n):
    """A rigid tip body (mass 1, no rotary inertia) on a fixed joint at the
    beam's end: deflected by a tip load held with damping until 3 s, then
    free; both frequencies fitted to the tip body's response."""
    scene = {"format": "mfbd-scene/1", "name": "tip_body", "solver": {"h_max": 1e-3, "rho_inf": 0.9},
             "bodies": [{"name": "tip", "mass": 1.0, "inertia": [0, 0, 0], "position": [1, 0, 0]}],
             "joints": [{"name": "weld", "type": "fixed", "parent": {"flexible": "beam", "at": 1.0}, "child": "tip"}],
             "flexible_bodies": [dict(cantilever(n, damping=0.1),
                                      loads=[{"node": n, "force": [0, 1e-3, 0], "scale": "if(3 - t, 1, 0)"}])]}
    weld = "weld.parent_flexible_body_joint.violation"
    ts, out = released_response(packed(scene, tmp_path, f"tip{n}"), ["tip.position.y", weld])
    ys, violation = out["tip.position.y"], out[weld].max()
    exact = tip_mass_frequencies(1.0)
    return fitted_frequencies(np.array(ts), np.array(ys), exact * 1.01) / exact - 1, violation


def test_tip_body_on_a_fixed_joint_has_the_tip_mass_frequency(tmp_path):
    # The consistent mass (cubic across the element) and the shallow-arch element
    # converge at fourth order: f1 +1.5e-5 at 2 elements, -1.3e-6 at 4
    # (the time step's -2.5e-6 below that); f2 8.5e-3 and 4.0e-4.
    e2, v2 = tip_body_frequencies(tmp_path, 2)
    e4, v4 = tip_body_frequencies(tmp_path, 4)
    assert abs(e2[0]) < 3e-5 and abs(e4[0]) < 5e-6, (e2, e4)
    assert 12.0 < e2[1] / e4[1] < 32.0, (e2, e4)  # 2^4 = 16 in the mesh
    assert max(v2, v4) < 1e-10


def hung_body_energy_drift(tmp_path, joint, h):
    """A rigid body hung from the tip of a flexible cantilever, released
    swinging; rho_inf = 1. Returns the largest change of the total energy
    relative to the largest kinetic energy, and the largest weld violation."""
    spherical = joint == "spherical"
    beam = dict(cantilever(8, EI=50.0), outputs={"energy": True})
    beam["section"].update({"EA": 1e5, "GAy": 3e4, "GAz": 3e4, "GJ": 40, "rhoJ": [2e-4, 1e-4, 1e-4]})
    scene = {"format": "mfbd-scene/1", "name": "hung", "gravity": [0, -9.81, 0],
             "solver": {"h_max": h, "rho_inf": 1.0}, "experiment": {"stop_time": 2.0, "output_interval": 0.01},
             "bodies": [{"name": "bob", "mass": 1.0, "inertia": [0.01, 0.01, 0.01], "position": [1, -0.5, 0]}],
             "joints": [{"name": "hang", "type": joint, "parent": {"flexible": "beam", "at": 1.0}, "child": "bob",
                         "axis": [0, 0, 1],
                         "initial": {"coordinates": [0.6, 0.0, 0.4] if spherical else [0.8],
                                     "rates": [0, 2.0, 0] if spherical else [1.0]}}],
             "flexible_bodies": [beam]}
    r = simulate_fixed_step(packed(scene, tmp_path, f"hung_{joint}"))
    v = np.column_stack([r[f"bob.velocity.{c}"] for c in "xyz"])
    w = np.column_stack([r[f"bob.angular_velocity.{c}"] for c in "xyz"])
    kinetic = 0.5 * (v ** 2).sum(1) + 0.5 * 0.01 * (w ** 2).sum(1) + r["beam.kinetic_energy"]
    total = kinetic + 9.81 * r["bob.position.y"] + r["beam.strain_energy"] + r["beam.potential_energy"]
    assert r["beam.strain_energy"].max() > 1.0  # the beam takes part: energy moves through the weld
    return np.abs(total - total[0]).max() / kinetic.max(), r["hang.parent_flexible_body_joint.violation"].max()


# The step where each drifts below 1e-6, and twice it. The drift is the
# integrator's O(h^2) down to about 3e-7, where the Newton corrections'
# round-off (1e-14 m per substep, 2e4 substeps) takes over: the revolute case
# drifts 2.1e-6, 5.4e-7, 3.1e-7 at h = 4, 2, 1 (1e-4 s).
@pytest.mark.parametrize("joint, h", [("spherical", 1e-4), ("revolute", 2e-4)])
def test_body_hung_from_a_beam_conserves_energy(tmp_path, joint, h):
    coarse, _ = hung_body_energy_drift(tmp_path, joint, 2 * h)
    drift, violation = hung_body_energy_drift(tmp_path, joint, h)
    assert drift < 1e-6, drift
    assert coarse / drift > 3.0, (coarse, drift)  # an O(h^2) integration error, not a modelling one
    assert violation < 1e-10


def test_motor_driven_hub_reproduces_the_prescribed_root_node(tmp_path):
    """F4 twice: the root node's rotation prescribed, and a rigid hub on a
    driven revolute joint with the beam's root welded to it by a fixed joint
    (a virtual body, child of the hub). Same motion of the root node, so the
    same tip deflection, to the Newton tolerance, at the same substeps
    (under a tolerance each run sizes its own: their error sums run through
    different coordinates)."""
    prescribed = load_scene("spin_up_beam")
    beam = prescribed["flexible_bodies"][0]
    beam["outputs"] = {"nodes": [8]}
    motor = copy.deepcopy(prescribed)
    angle = motor["flexible_bodies"][0].pop("supports")[0]["angle"]
    motor["bodies"] = [{"name": "hub", "mass": 10.0, "inertia": [1, 1, 2], "position": [0, 0, 0]}]
    motor["joints"] = [
        {"name": "motor", "type": "revolute", "parent": "ground", "child": "hub", "position": [0, 0, 0],
         "axis": [0, 0, 1], "drive": angle},
        {"name": "root", "type": "fixed", "parent": "hub", "child": {"flexible": "beam", "node": 0}}]
    a = simulate_fixed_step(packed(prescribed, tmp_path, "prescribed"), stop_time=10.0, output_interval=0.05)
    b = simulate_fixed_step(packed(motor, tmp_path, "motor"), stop_time=10.0, output_interval=0.05)
    for c in "xy":
        tip_a, tip_b = a[f"beam.node8.position.{c}"], b[f"beam.node8.position.{c}"]
        assert np.abs(tip_a - tip_b).max() < 1e-6 * np.abs(tip_a).max()  # measured 2.7e-12 relative
    assert b["root.child_flexible_body_joint.violation"].max() < 1e-10
    # The drive torque turns the hub (I = 2) and, through the fixed joint and
    # the weld, the beam: drive = I thetaddot + the root joint's torque.
    t = b["time"]
    thetaddot = np.where(t < 15, 6 / 15 * (1 - np.cos(2 * np.pi * t / 15)), 0.0)
    balance = b["motor.drive_torque"] - (2.0 * thetaddot + b["root.reaction_torque.z"])
    assert np.abs(balance).max() < 1e-6 * np.abs(b["motor.drive_torque"]).max(), np.abs(balance).max()


def test_virtual_bodies_are_not_outputs_and_are_logged(tmp_path):
    scene = {"format": "mfbd-scene/1", "name": "logged",
             "bodies": [{"name": "tip", "mass": 1.0, "inertia": [0, 0, 0], "position": [1, 0, 0]}],
             "joints": [{"name": "weld", "type": "fixed", "parent": {"flexible": "beam", "node": 4}, "child": "tip"}],
             "flexible_bodies": [cantilever(4)]}
    fmu = packed(scene, tmp_path)
    names = [v.name for v in read_model_description(str(fmu)).modelVariables]
    assert not any("virtual_body" in n for n in names)
    assert {f"weld.parent_flexible_body_joint.{q}.{c}" for q in ("force", "torque") for c in "xyz"} <= set(names)
    s = Slave(fmu)
    try:
        assert s.instantiate(logging_on=True)
        assert "virtual body 'weld.parent_virtual_body' at node 4 of 'beam', welded by flexible body joint " \
               "'weld.parent_flexible_body_joint'" in s.messages()
    finally:
        s.free()


def slider_crank_midspan_deflection(tmp_path, n, h):
    """F5: transverse deflection of the rod's mid node from the chord of its
    end nodes, 0..0.4 s (spin-up to 150 rad/s over 0.15 s, then steady)."""
    scene = load_scene("flexible_slider_crank")
    scene["flexible_bodies"][0]["beam"]["elements"] = n
    scene["flexible_bodies"][0]["outputs"] = {"nodes": [0, n // 2, n]}
    scene["solver"]["h_max"] = h
    r = simulate_fixed_step(packed(scene, tmp_path, f"f5_{n}_{h}"), output_interval=1e-3)
    p = {i: np.column_stack([r[f"rod.node{i}.position.x"], r[f"rod.node{i}.position.y"]]) for i in (0, n // 2, n)}
    chord = p[n] - p[0]
    chord /= np.linalg.norm(chord, axis=1)[:, None]
    offset = p[n // 2] - 0.5 * (p[0] + p[n])
    assert r["crank_pin.child_flexible_body_joint.violation"].max() < 1e-10
    assert r["slider_pin.child_flexible_body_joint.violation"].max() < 1e-10
    return chord[:, 0] * offset[:, 1] - chord[:, 1] * offset[:, 0]


def test_flexible_slider_crank_converges_in_time_and_space(tmp_path):
    space = [slider_crank_midspan_deflection(tmp_path, n, 1e-4) for n in (4, 8, 16)]
    time = [slider_crank_midspan_deflection(tmp_path, 8, h) for h in (2e-4, 1e-4, 5e-5)]
    for label, (a, b, c) in (("space", space), ("time", time)):
        coarse, fine = np.abs(b - a).max(), np.abs(c - b).max()
        # measured ratios 14 (space: 8e-6 -> 5.5e-7 m, fourth order with the consistent mass), 3.7 (time: second)
        assert fine < coarse / 3, (label, coarse, fine)
    assert 3e-3 < np.abs(space[-1]).max() < 6e-3  # a few millimetres at 150 rad/s (measured 4.1 mm)


def test_flexible_four_bar_with_a_joint_defect_turns_a_full_revolution(tmp_path):
    """F6: a rigid four-bar would lock with joint C tilted by 5 degrees; the
    flexible one turns through a full revolution of bar 1, bending and
    twisting its bars, and comes back to where it started (quasi-static)."""
    period = 2 * np.pi / 0.6
    r = simulate_fmu(packed(load_scene("flexible_four_bar"), tmp_path),
                     output_interval=period / 200)
    assert abs(r["time"][-1] - period) < 1e-9 and abs(r["A.angle"][-1] - 2 * np.pi) < 1e-9
    violations = [r[k].max() for k in r.dtype.names if k.endswith("flexible_body_joint.violation")]
    assert len(violations) == 6 and max(violations) < 1e-10
    tip = np.column_stack([r[f"bar3.node0.position.{c}"] for c in "xyz"])
    # Back to the start within the tolerance (1e-3 L, L = 0.27 m), with the
    # bars' undamped vibration from the start of the drive (measured 3.5e-5
    # m; 7e-10 m under the earlier rule that held the whole error estimate
    # per step, whose positions at 1 s were as far from a fine-step
    # reference, 7.5e-5 m: the return measures the numerical damping).
    assert np.abs(tip[-1] - tip[0]).max() < 1e-4
    assert 1e-3 < np.abs(tip[:, 1]).max() < 1e-2  # the defect pushes joint C out of the plane by millimetres
    assert np.abs(r["bar1.element0.end1.moment.z"]).max() > 50.0  # the bars carry the locking moment (~159 N m)


def test_flexible_arm_under_joint_torque_inputs_sags_as_a_cantilever(tmp_path):
    """The two-link arm with a flexible forearm, driven by a master's PD loop
    through the joint-torque inputs (examples/flexible_robot_arm/control.py),
    comes to rest at its goal; there the payload sits below where rigid links
    would put it by the cantilever deflection of the forearm under the
    payload and its own weight, P L^3 / (3 EI) + q L^4 / (8 EI) (transverse
    parts of gravity, Euler-Bernoulli)."""
    import importlib.util
    path = EXAMPLES / "flexible_robot_arm" / "control.py"
    spec = importlib.util.spec_from_file_location("flexible_arm_control", path)
    control = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(control)
    data = control.run(packed(load_scene("flexible_robot_arm"), tmp_path))
    assert np.abs(data[-1, 1:3] - control.GOAL).max() < 1e-3
    EI = 7e10 * np.pi * 0.012 ** 4 / 64
    transverse = 9.81 * np.cos(control.GOAL.sum())
    sag = control.MP * transverse * 0.6 ** 3 / (3 * EI) + control.M2 / 0.6 * transverse * 0.6 ** 4 / (8 * EI)
    assert abs(data[-1, 7] / sag - 1) < 1e-2, (data[-1, 7], sag)  # measured 5.18 mm against 5.19 mm


def test_force_element_on_a_node_acts_as_the_nodal_load(tmp_path):
    """An applied_force element on a flexible node (through its virtual body)
    and the flexible body's own nodal load input move the beam alike: the
    virtual body's weld passes the force on unchanged."""
    def run(extra, loads, inputs, name):
        beam = dict(cantilever(4, damping=0.01), loads=loads, outputs={"nodes": [4]})
        scene = {"format": "mfbd-scene/1", "name": name, "solver": {"h_max": 1e-3},
                 "experiment": {"stop_time": 0.5, "output_interval": 0.01},
                 "flexible_bodies": [beam], "forces": extra}
        return simulate_fmu(packed(scene, tmp_path, name), start_values=inputs,
                            output=[f"beam.node4.position.{c}" for c in "xyz"])
    force = {"z": 0.02, "y": -0.01}
    element = run([{"name": "push", "type": "applied_force", "body": {"flexible": "beam", "node": 4},
                    "point": [1, 0, 0]}], [], {f"push.force.{c}": v for c, v in force.items()}, "element")
    nodal = run([], [{"node": 4, "input": True}], {f"beam.node4.force.{c}": v for c, v in force.items()}, "nodal")
    for c in "xyz":
        assert np.abs(element[f"beam.node4.position.{c}"] - nodal[f"beam.node4.position.{c}"]).max() < 1e-10
    assert np.abs(nodal["beam.node4.position.z"]).max() > 1e-3  # it does move
