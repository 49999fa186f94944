"""Scene authoring: joint frames set by x_axis or a full orientation, applied
forces and torques given as functions of time, the bushing frame's x axis,
and the schema agreeing with what the parser accepts."""
import json
import math
import re

import numpy as np
import pytest
from fmpy import simulate_fmu

from conftest import ROOT, pack, packed

SCHEMA = json.loads((ROOT / "solver" / "scene" / "scene.schema.json").read_text())
G = 9.81


def scene(bodies, joints, forces=(), gravity=(0, -G, 0), stop=1.0, **extra):
    s = {"format": "mfbd-scene/1", "name": "authoring", "gravity": list(gravity),
         "solver": {"h_max": 1e-3}, "experiment": {"stop_time": stop, "output_interval": 0.1},
         "bodies": bodies, "joints": joints}
    if forces:
        s["forces"] = list(forces)
    s.update(extra)
    return s


def run(tmp_path, s, outputs, stop=1.0, name="scene"):
    r = simulate_fmu(str(packed(s, tmp_path, name)), stop_time=stop, output_interval=0.1, output=outputs)
    return r


BOB = {"name": "bob", "mass": 2.0, "inertia": [0.1, 0.1, 0.1], "position": [1, 0, 0]}


def hinge(**frame):
    return {"name": "hinge", "type": "revolute", "parent": "ground", "child": "bob", "position": [0, 0, 0],
            **frame}


def test_joint_x_axis_turns_the_reaction_frame(tmp_path):
    """A hinge's reaction is given in its child marker frame: with x_axis
    along world Y the frame is the default one turned by 90 degrees about z,
    so (fx, fy) becomes (fy, -fx) for the same motion; a quaternion giving
    that frame is the same joint, bit for bit."""
    out = ["hinge.angle", "hinge.reaction_force.x", "hinge.reaction_force.y"]
    default = run(tmp_path, scene([BOB], [hinge(axis=[0, 0, 1])]), out, name="default")
    turned = run(tmp_path, scene([BOB], [hinge(axis=[0, 0, 1], x_axis=[0, 1, 0])]), out, name="turned")
    s = math.sqrt(0.5)
    quaternion = run(tmp_path, scene([BOB], [hinge(orientation={"quaternion": [s, 0, 0, s]})]), out, name="q")
    scale = np.abs(default["hinge.reaction_force.x"]).max()
    assert scale > 10.0  # a swinging 2 kg bob
    assert np.abs(turned["hinge.angle"] - default["hinge.angle"]).max() < 1e-12
    assert np.abs(turned["hinge.reaction_force.x"] - default["hinge.reaction_force.y"]).max() < 1e-9 * scale
    assert np.abs(turned["hinge.reaction_force.y"] + default["hinge.reaction_force.x"]).max() < 1e-9 * scale
    assert np.abs(quaternion["hinge.reaction_force.x"] - turned["hinge.reaction_force.x"]).max() < 1e-9 * scale


def test_planar_joint_slides_along_its_x_axis(tmp_path):
    """A planar joint's first coordinate slides along the joint frame's x:
    with x_axis along world Y and gravity along -Y it falls freely,
    x(t) = -g t^2 / 2 (constant acceleration: exact in generalized-alpha)."""
    s = scene([BOB], [{"name": "plane", "type": "planar", "parent": "ground", "child": "bob",
                       "position": [1, 0, 0], "axis": [0, 0, 1], "x_axis": [0, 1, 0]}])
    r = run(tmp_path, s, ["plane.x", "plane.y", "bob.position.y"])
    t = r["time"]
    assert np.abs(r["plane.x"] + 0.5 * G * t**2).max() < 1e-9
    assert np.abs(r["plane.y"]).max() < 1e-12
    assert np.abs(r["bob.position.y"] - r["plane.x"]).max() < 1e-12


@pytest.mark.parametrize("joint, message", [
    (hinge(axis=[0, 0, 1], x_axis=[0, 0, 2]), "joints[0].x_axis: expected a direction not parallel to the z axis"),
    (hinge(axis=[0, 0, 1], orientation={"z_axis": [0, 0, 1]}), "joints[0].axis: give either orientation or axis"),
    (hinge(x_axis=[1, 0, 0], orientation={"z_axis": [0, 0, 1]}), "joints[0].x_axis: give either orientation"),
])
def test_joint_frame_errors_name_the_field(tmp_path, joint, message):
    result = pack(scene([BOB], [joint]), tmp_path)
    assert result.returncode != 0
    assert message in result.stderr, result.stderr


FREE = {"name": "free", "type": "free", "parent": "ground", "child": "bob", "position": [1, 0, 0]}


def test_constant_applied_force(tmp_path):
    """A constant force on a free body without gravity: z = F t^2 / (2 m),
    exact for a constant acceleration."""
    force = {"name": "push", "type": "applied_force", "body": "bob", "point": [1, 0, 0], "force": [0, 0, 3.0]}
    r = run(tmp_path, scene([BOB], [FREE], [force], gravity=(0, 0, 0)), ["free.z", "free.x"])
    t = r["time"]
    assert np.abs(r["free.z"] - 3.0 * t**2 / (2 * 2.0)).max() < 1e-10
    assert np.abs(r["free.x"]).max() < 1e-12


def test_applied_force_and_torque_follow_their_scale(tmp_path):
    """force * scale(t) with scale = t: z = F t^3 / (6 m), second order in h;
    a body-frame torque about the body's z (kept along world z as the body
    turns about it) times the same scale: angle = T t^3 / (6 I)."""
    force = {"name": "push", "type": "applied_force", "body": "bob", "point": [1, 0, 0], "frame": "body",
             "force": [0, 0, 3.0], "torque": [0, 0, 0.05], "scale": "t"}
    s = scene([BOB], [FREE], [force], gravity=(0, 0, 0))
    s["solver"]["h_max"] = 1e-4
    r = run(tmp_path, s, ["free.z", "free.rotation_z"])
    t = r["time"]
    assert np.abs(r["free.z"] - 3.0 * t**3 / (6 * 2.0)).max() < 1e-7
    assert np.abs(r["free.rotation_z"] - 0.05 * t**3 / (6 * 0.1)).max() < 1e-7


def test_applied_force_inputs_stay_without_force(tmp_path):
    """Without force or torque an applied force keeps its six FMI inputs;
    with them it has none."""
    from fmpy import read_model_description
    inputs = {"name": "push", "type": "applied_force", "body": "bob", "point": [1, 0, 0]}
    given = dict(inputs, name="given", force=[1, 0, 0])
    md = read_model_description(str(packed(scene([BOB], [FREE], [inputs, given]), tmp_path)))
    names = {v.name for v in md.modelVariables if v.causality == "input"}
    assert {f"push.{k}.{c}" for k in ("force", "torque") for c in "xyz"} <= names
    assert not any(n.startswith("given.") for n in names)


@pytest.mark.parametrize("change, message", [
    ({"force": [1, 0, 0], "input": True}, "forces[0]: an input force takes its force and torque from FMI inputs"),
    ({"input": False}, "forces[0]: expected a force, a torque, or \"input\": true"),
    ({"scale": "t"}, "forces[0]: an input force takes its force and torque from FMI inputs"),
])
def test_applied_force_errors(tmp_path, change, message):
    force = {"name": "push", "type": "applied_force", "body": "bob", "point": [1, 0, 0], **change}
    result = pack(scene([BOB], [FREE], [force]), tmp_path)
    assert result.returncode != 0
    assert message in result.stderr, result.stderr


def test_bushing_frame_takes_its_x_axis(tmp_path):
    """A bushing's stiffness acts in its frame: with x_axis along world Y,
    gravity along -Y is carried by the x stiffness; static sag m g / k_x
    (the y stiffness, ten times larger, would give a tenth of it)."""
    bushing = {"name": "mount", "type": "bushing", "body1": "ground", "body2": "bob", "position": [1, 0, 0],
               "orientation": {"z_axis": [0, 0, 1], "x_axis": [0, 1, 0]},
               "stiffness": [1e4, 1e5, 1e5, 1e3, 1e3, 1e3]}
    body = dict(BOB, inertia=[0.1, 0.1, 0.1])
    s = scene([body], [FREE], [bushing], analysis="static")
    r = run(tmp_path, s, ["bob.position.y", "bob.position.x"])
    assert abs(r["bob.position.y"][-1] + 2.0 * G / 1e4) < 1e-9
    assert abs(r["bob.position.x"][-1] - 1.0) < 1e-9


# --- the schema documents what the parser accepts -------------------------

def accepted_keys(tmp_path, s, path):
    """The keys the parser accepts at `path`, from its error for an unknown key."""
    target = s
    for p in path:
        target = target[p]
    target["zz_unknown"] = 1
    result = pack(s, tmp_path)
    assert result.returncode != 0
    match = re.search(r"zz_unknown: unknown key; expected one of: (.*)", result.stderr)
    assert match, result.stderr
    return set(re.findall(r"[a-z_0-9]+", match.group(1)))


def schema_keys(definition):
    if "$ref" in definition:
        definition = SCHEMA["$defs"][definition["$ref"].split("/")[-1]]
    return set(definition.get("properties", {}))


def force_schema(kind):
    return next(f for f in SCHEMA["$defs"]["force"]["oneOf"] if f["properties"]["type"].get("const") == kind)


@pytest.mark.parametrize("what", ["joint", "body", "applied_force", "bushing", "spring_damper", "top level"])
def test_schema_lists_every_key_the_parser_accepts(tmp_path, what):
    spring = {"name": "spring", "type": "spring_damper", "body1": "ground", "point1": [0, 1, 0],
              "body2": "bob", "point2": [1, 0, 0]}
    bushing = {"name": "mount", "type": "bushing", "body1": "ground", "body2": "bob", "position": [1, 0, 0],
               "stiffness": [1, 1, 1, 1, 1, 1]}
    applied = {"name": "push", "type": "applied_force", "body": "bob", "point": [1, 0, 0]}
    s = scene([dict(BOB)], [hinge(axis=[0, 0, 1])], [spring, bushing, applied])
    path, schema = {
        "joint": (["joints", 0], schema_keys(SCHEMA["$defs"]["joint"])),
        "body": (["bodies", 0], schema_keys(SCHEMA["$defs"]["body"])),
        "spring_damper": (["forces", 0], schema_keys(force_schema("spring_damper"))),
        "bushing": (["forces", 1], schema_keys(force_schema("bushing"))),
        "applied_force": (["forces", 2], schema_keys(force_schema("applied_force"))),
        "top level": ([], set(SCHEMA["properties"])),
    }[what]
    assert accepted_keys(tmp_path, s, path) == schema


# --- initial rates the user keeps -------------------------------------------

def four_bar_with_rates(rates, keep):
    from conftest import load_scene
    s = load_scene("four_bar")
    for j in s["joints"]:
        if j["name"] in rates:
            j["initial"] = {"rates": [rates[j["name"]]], **({"keep_rates": True} if j["name"] in keep else {})}
    return s


def first_rates(tmp_path, s, name):
    r = simulate_fmu(str(packed(s, tmp_path, name)), stop_time=0.01, output_interval=0.01,
                     output=["A.angle_rate", "B.angle_rate", "D.angle_rate"])
    return {k: r[f"{k}.angle_rate"][0] for k in "ABD"}


def test_kept_initial_rate_is_the_crank_rate(tmp_path):
    """The four-bar's crank given 6 rad/s: the least-change projection over
    all rates changes it; kept, it starts at 6 rad/s to round-off and the
    coupler and rocker take what the loop needs (the same motion as the
    crank rate the projection chose, scaled: the loop's velocity constraint
    is linear in the rates, so every rate scales with the crank's)."""
    free = first_rates(tmp_path, four_bar_with_rates({"A": 6.0}, keep=()), "free")
    kept = first_rates(tmp_path, four_bar_with_rates({"A": 6.0}, keep=("A",)), "kept")
    assert abs(free["A"] - 6.0) > 0.1  # the projection moved it
    assert abs(kept["A"] - 6.0) < 1e-12
    for k in "BD":
        assert abs(kept[k] - free[k] * 6.0 / free["A"]) < 1e-9 * abs(kept[k]) + 1e-12


def test_kept_rates_that_break_the_loop_are_refused(tmp_path):
    """Keeping the crank's and the rocker's rates, both 1 rad/s, cannot meet
    the loop's velocity constraint: fmi2EnterInitializationMode (where the
    mechanism is assembled) fails and
    names the kept joints and the cut joint."""
    from conftest import ERROR, OK, Slave
    slave = Slave(packed(four_bar_with_rates({"A": 1.0, "D": 1.0}, keep=("A", "D")), tmp_path))
    try:
        assert slave.instantiate(), slave.messages()
        assert slave.call("setupExperiment", None, 0.0, None) == OK
        assert slave.call("enterInitializationMode") == ERROR
        assert "cannot keep the initial rates of joint 'A', 'D' (initial.keep_rates): the velocity constraint of cut joint 'C'" \
            in slave.messages(), slave.messages()
    finally:
        slave.free()


def initialization_log(tmp_path, s, name):
    from conftest import OK, Slave
    slave = Slave(packed(s, tmp_path, name))
    try:
        assert slave.instantiate(logging_on=False), slave.messages()
        assert slave.call("setupExperiment", None, 0.0, None) == OK
        status = slave.fmu.fmi2EnterInitializationMode(slave.fmu.component)
        return status, slave.log
    finally:
        slave.free()


def test_changed_given_rates_are_a_warning_with_logging_off(tmp_path):
    """The crank's given 6 rad/s changed by the velocity projection: the
    FMU says so at warning level, with the amount and the new rate, even
    with logging off (fmi2EnterInitializationMode returns fmi2Warning).
    Kept, or not given at all, nothing is said."""
    free = first_rates(tmp_path, four_bar_with_rates({"A": 6.0}, keep=()), "rates")
    status, log = initialization_log(tmp_path, four_bar_with_rates({"A": 6.0}, keep=()), "free")
    assert status == 1, log  # fmi2Warning
    warnings = [(c, m) for st, c, m in log if st == 1]
    assert len(warnings) == 1 and warnings[0][0] == "logStatusWarning", log
    match = re.search(r"initial rates of joint 'A' \(initial.rates\) by (\S+) to \[(\S+)\]", warnings[0][1])
    assert match, warnings
    assert float(match.group(1)) == pytest.approx(abs(6.0 - free["A"]), rel=1e-5)
    assert float(match.group(2)) == pytest.approx(free["A"], rel=1e-5)
    for s, name in ((four_bar_with_rates({"A": 6.0}, keep=("A",)), "kept"), (four_bar_with_rates({}, keep=()), "none")):
        status, log = initialization_log(tmp_path, s, name)
        assert status == 0 and not log, log
