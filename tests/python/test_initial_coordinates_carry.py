"""A joint's initial coordinates carry what hangs from the moved link,
flexible bodies included: they start moved rigidly with it, unstrained and
at rest relative to it."""
import numpy as np

from conftest import Slave, packed

G, RHO_A, LENGTH = 9.81, 2.0, 1.0


def scene(angle, rate):
    """A rigid link (1 m along x, hinged at the origin about z) with a
    flexible rod (1 m, 4 elements) welded to its tip, hanging along -y in
    the design configuration; the hinge starts at `angle` and `rate`."""
    return {
        "format": "mfbd-scene/1", "name": "carried_rod", "gravity": [0, -G, 0],
        "solver": {"h_max": 1e-3, "rho_inf": 0.8},
        "bodies": [{"name": "link", "mass": 1.0, "inertia": [1e-3, 0.1, 0.1], "position": [0.5, 0, 0]}],
        "flexible_bodies": [{
            "name": "rod", "beam": {"start": [1, 0, 0], "end": [1, -LENGTH, 0], "elements": 4, "section_y": [1, 0, 0]},
            "section": {"EA": 1e7, "GJ": 50, "EIy": 100, "EIz": 100, "rhoA": RHO_A, "rhoJ": [1e-4, 5e-5, 5e-5]},
            "outputs": {"nodes": [0, 4], "energy": True}}],
        "joints": [
            {"name": "hinge", "type": "revolute", "parent": "ground", "child": "link", "position": [0, 0, 0],
             "axis": [0, 0, 1], "initial": {"coordinates": [angle], "rates": [rate]}},
            {"name": "weld", "type": "fixed", "parent": "link", "child": {"flexible": "rod", "node": 0}}],
    }


def test_rod_hanging_from_a_raised_link_starts_unstrained_and_moving_with_it(tmp_path):
    angle, rate = 0.6, 2.0
    s = Slave(packed(scene(angle, rate), tmp_path), instance_name="carried").start()
    try:
        weight_times_length = RHO_A * LENGTH * G * LENGTH
        assert s.get("rod.strain_energy") < 1e-9 * weight_times_length
        c, sn = np.cos(angle), np.sin(angle)
        R = np.array([[c, -sn, 0], [sn, c, 0], [0, 0, 1]])
        omega = np.array([0, 0, rate])
        for k, design in ((0, [1, 0, 0]), (4, [1, -LENGTH, 0])):
            r = R @ design
            assert np.allclose(s.get(*[f"rod.node{k}.position.{c}" for c in "xyz"]), r, atol=1e-12)
            assert np.allclose(s.get(*[f"rod.node{k}.velocity.{c}" for c in "xyz"]), np.cross(omega, r), atol=1e-10)
            assert np.allclose(s.get(*[f"rod.node{k}.angular_velocity.{c}" for c in "xyz"]), omega, atol=1e-10)
        # The first steps are ordinary ones (before: 835 Newton iterations and
        # 42 rejected substeps in the first 0.01 s).
        assert s.step(0.0, 0.01) == 0, s.messages()
        assert s.get("rod.strain_energy") < 1e-3 * weight_times_length
    finally:
        s.free()


def chain_scene(angle, rate):
    """The scene above with a second rod (0.5 m, 2 elements) hanging from
    the first rod's tip and a payload fixed to the second rod's tip: both
    welded to nodes only (their virtual bodies have free joints). The
    joints list the lowest link first, so the carry must wait for the rods
    above it."""
    s = scene(angle, rate)
    s["name"] = "carried_chain"
    s["bodies"].append({"name": "payload", "mass": 0.2, "inertia": [1e-4, 1e-4, 1e-4],
                        "position": [1, -LENGTH - 0.5, 0]})
    s["flexible_bodies"].append({
        "name": "rod2", "beam": {"start": [1, -LENGTH, 0], "end": [1, -LENGTH - 0.5, 0], "elements": 2,
                                 "section_y": [1, 0, 0]},
        "section": s["flexible_bodies"][0]["section"], "outputs": {"nodes": [0, 2], "energy": True}})
    s["joints"][1:1] = [
        {"name": "hold", "type": "fixed", "parent": {"flexible": "rod2", "node": 2}, "child": "payload"},
        {"name": "link2", "type": "fixed", "parent": {"flexible": "rod", "node": 4},
         "child": {"flexible": "rod2", "node": 0}}]
    return s


def test_what_hangs_below_a_carried_rod_is_carried_too(tmp_path):
    """A second flexible body and a payload below the carried rod, held by
    welds to its nodes only, move with the link as well (before: the carry
    stopped at the first rod, and the assembly pulled the rest after it)."""
    angle, rate = 0.6, 2.0
    s = Slave(packed(chain_scene(angle, rate), tmp_path), instance_name="chain").start()
    try:
        for rod, length in (("rod", LENGTH), ("rod2", 0.5)):
            assert s.get(f"{rod}.strain_energy") < 1e-9 * RHO_A * length * G * length, rod
        c, sn = np.cos(angle), np.sin(angle)
        R = np.array([[c, -sn, 0], [sn, c, 0], [0, 0, 1]])
        omega = np.array([0, 0, rate])
        for name, design in (("rod2.node0", [1, -LENGTH, 0]), ("rod2.node2", [1, -LENGTH - 0.5, 0]),
                             ("payload", [1, -LENGTH - 0.5, 0])):
            r = R @ design
            assert np.allclose(s.get(*[f"{name}.position.{c}" for c in "xyz"]), r, atol=1e-12), name
            assert np.allclose(s.get(*[f"{name}.velocity.{c}" for c in "xyz"]), np.cross(omega, r), atol=1e-10), name
            assert np.allclose(s.get(*[f"{name}.angular_velocity.{c}" for c in "xyz"]), omega, atol=1e-10), name
        assert s.step(0.0, 0.01) == 0, s.messages()
    finally:
        s.free()
