"""Force elements against closed-form motions: spring-damper, applied force
from inputs, bushing, rotational spring-damper."""
import numpy as np
from fmpy import simulate_fmu

from conftest import Slave, packed


def scene(bodies, joints, forces, gravity=(0, 0, 0), h=1e-4, stop=2.0):
    return {"format": "mfbd-scene/1", "name": "forces", "gravity": list(gravity),
            "solver": {"h_max": h, "rho_inf": 1.0}, "experiment": {"stop_time": stop, "output_interval": 0.01},
            "bodies": bodies, "joints": joints, "forces": forces}


BLOCK = {"name": "block", "mass": 2.0, "inertia": [0.1, 0.1, 0.1], "position": [1, 0, 0]}


def test_spring_on_a_slider_oscillates_at_sqrt_k_over_m(tmp_path):
    k, m, free = 50.0, 2.0, 0.8
    s = scene([BLOCK], [{"name": "slide", "type": "prismatic", "parent": "ground", "child": "block",
                         "position": [1, 0, 0], "axis": [1, 0, 0]}],
              [{"name": "spring", "type": "spring_damper", "body1": "ground", "point1": [0, 0, 0],
                "body2": "block", "point2": [1, 0, 0], "stiffness": k, "free_length": free}])
    r = simulate_fmu(packed(s, tmp_path), output=["block.position.x", "spring.tension", "spring.length"])
    t = r["time"]
    exact = free + (1.0 - free) * np.cos(np.sqrt(k / m) * t)
    assert np.max(np.abs(r["block.position.x"] - exact)) < 1e-6
    assert np.max(np.abs(r["spring.tension"] - k * (r["spring.length"] - free))) < 1e-9


def test_applied_force_input_accelerates_a_free_body(tmp_path):
    s = scene([BLOCK], [{"name": "float", "type": "free", "parent": "ground", "child": "block", "position": [1, 0, 0]}],
              [{"name": "push", "type": "applied_force", "body": "block", "point": [1, 0, 0]}], h=1e-2)
    slave = Slave(packed(s, tmp_path))
    try:
        slave.start()
        F = np.array([1.0, -2.0, 0.5])
        for c, f in zip("xyz", F):
            assert slave.set(f"push.force.{c}", f) == 0
        t = 0.0
        for _ in range(100):
            assert slave.step(t, 0.01) == 0
            t += 0.01
        position = np.array(slave.get("block.position.x", "block.position.y", "block.position.z"))
        # Constant acceleration: generalized-alpha integrates it exactly.
        assert np.max(np.abs(position - ([1, 0, 0] + F / 2.0 * t * t / 2))) < 1e-12
        assert np.max(np.abs(slave.get("block.angular_velocity.x", "block.angular_velocity.y",
                                       "block.angular_velocity.z"))) < 1e-14  # through the centre of mass
    finally:
        slave.free()


def test_bushing_holds_a_body_against_gravity(tmp_path):
    k = np.array([1e4, 2e4, 3e4, 500, 600, 700])
    s = scene([BLOCK], [{"name": "float", "type": "free", "parent": "ground", "child": "block", "position": [1, 0, 0]}],
              [{"name": "mount", "type": "bushing", "body1": "ground", "body2": "block", "position": [1, 0, 0],
                "stiffness": list(k), "damping": list(0.05 * k)}], gravity=(0, -9.81, 0), h=1e-3, stop=3.0)
    r = simulate_fmu(packed(s, tmp_path), output=["block.position.y", "block.position.x"])
    # Static deflection m g / k_y once the damping has settled the motion.
    assert abs(r["block.position.y"][-1] - (-2.0 * 9.81 / 2e4)) < 1e-9
    assert abs(r["block.position.x"][-1] - 1.0) < 1e-12


def test_rotational_spring_stiffens_the_pendulum(tmp_path):
    # Small oscillation about hanging down: omega^2 = (k + m g L) / (m L^2).
    k, m, L, g = 5.0, 1.0, 1.0, 9.81
    s = scene([{"name": "bob", "mass": m, "inertia": [0, 0, 0], "position": [0, -L, 0]}],
              [{"name": "hinge", "type": "revolute", "parent": "ground", "child": "bob", "position": [0, 0, 0],
                "initial": {"coordinates": [1e-3]}}],
              [{"name": "torsion", "type": "rotational_spring_damper", "joint": "hinge", "stiffness": k}],
              gravity=(0, -g, 0), stop=3.0)
    r = simulate_fmu(packed(s, tmp_path), output=["hinge.angle"])
    omega = np.sqrt((k + m * g * L) / (m * L * L))
    # Amplitude 1e-3 rad: the pendulum's nonlinearity is 1e-7 relative.
    assert np.max(np.abs(r["hinge.angle"] - 1e-3 * np.cos(omega * r["time"]))) < 1e-8
