"""Bad scenes give one clear error naming the JSON path and what was
expected: at pack time (non-zero exit, stderr) and at fmi2Instantiate (NULL,
message through the logger)."""
import copy
import json
import shutil
import subprocess

import pytest
from fmpy import extract

from conftest import PACKER, Slave, load_scene, pack


def edit(change):
    scene = load_scene("pendulum")
    change(scene)
    return json.dumps(scene)


def two_parents(s):
    s["bodies"].append({"name": "arm", "mass": 1, "inertia": [0, 0, 0], "position": [2, 0, 0]})
    s["joints"].append({"name": "j2", "type": "revolute", "parent": "bob", "child": "arm", "position": [1, 0, 0]})
    s["joints"].append({"name": "j3", "type": "revolute", "parent": "ground", "child": "arm", "position": [2, 0, 0]})


def parent_loop(s):
    s["bodies"].append({"name": "a", "mass": 1, "inertia": [0, 0, 0], "position": [2, 0, 0]})
    s["bodies"].append({"name": "b", "mass": 1, "inertia": [0, 0, 0], "position": [3, 0, 0]})
    s["joints"].append({"name": "ja", "type": "revolute", "parent": "b", "child": "a", "position": [2, 0, 0]})
    s["joints"].append({"name": "jb", "type": "revolute", "parent": "a", "child": "b", "position": [3, 0, 0]})


def hang_from_beam(s):
    """The pendulum's hinge on the tip of a clamped beam (a virtual body there)."""
    s["flexible_bodies"] = [{"name": "beam", "beam": {"start": [0, 0, 0], "end": [1, 0, 0], "elements": 4},
                             "section": {"shape": "circle", "d": 0.01}, "material": {"E": 2e11, "nu": 0.3, "rho": 7800},
                             "supports": [{"node": 0, "type": "clamp"}]}]
    s["joints"][0]["parent"] = {"flexible": "beam", "node": 4}


def set_in(path, value):
    def change(s):
        node = s
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
    return change


def remove(path):
    def change(s):
        node = s
        for key in path[:-1]:
            node = node[key]
        del node[path[-1]]
    return change


def with_beam(**fields):
    """The pendulum scene plus a small steel beam with the given extra fields."""
    body = {"name": "beam", "beam": {"start": [0, 0, 0], "end": [1, 0, 0], "elements": 4},
            "section": {"shape": "circle", "d": 0.01}, "material": {"E": 2e11, "nu": 0.3, "rho": 7800}}
    body.update(fields)
    return edit(lambda s: s.update({"flexible_bodies": [body]}))


# (id, scene text, expected words in the single error line)
CASES = [
    ("empty file", "", ["scene: empty file; expected a JSON object"]),
    ("not JSON", "{\"format\": ", ["scene: not valid JSON"]),
    ("not an object", "[1, 2]", ["expected an object, got an array"]),
    ("unknown top-level key", edit(set_in(["colour"], "red")), ["colour: unknown key; expected one of"]),
    ("unknown body key", edit(set_in(["bodies", 0, "colour"], 1)), ["bodies[0].colour: unknown key"]),
    ("missing field", edit(remove(["bodies", 0, "mass"])), ["bodies[0].mass: missing required field"]),
    ("wrong type", edit(set_in(["bodies", 0, "mass"], [1])),
     ["bodies[0].mass: expected a number or a parameter expression, got an array"]),
    ("NaN from an expression", edit(set_in(["bodies", 0, "mass"], "0/0")), ["bodies[0].mass: expected a finite number"]),
    ("Inf literal", edit(set_in(["gravity"], [0, 12345.678, 0])).replace("12345.678", "1e999"),
     ["scene: not valid JSON", "number overflow parsing '1e999'"]),
    ("negative mass", edit(set_in(["bodies", 0, "mass"], -2)), ["bodies[0].mass: expected a number >= 0"]),
    ("negative principal moment", edit(set_in(["bodies", 0, "inertia"], [-1, 1, 1])),
     ["bodies[0].inertia: expected an inertia tensor with principal moments >= 0"]),
    ("triangle inequality", edit(set_in(["bodies", 0, "inertia"], [1, 1, 3])),
     ["bodies[0].inertia: principal moments", "triangle inequality"]),
    ("zero-length axis", edit(set_in(["joints", 0, "axis"], [0, 0, 0])),
     ["joints[0].axis: expected a non-zero direction"]),
    ("unknown body", edit(set_in(["joints", 0, "child"], "bobb")),
     ["joints[0].child: joint 'hinge' names unknown body \"bobb\""]),
    ("actuated cut joint", edit(lambda s: (two_parents(s), s["joints"][2].update({"cut": True, "actuated": True}))),
     ["joints[2].actuated: joint 'j3' is a cut joint: it has no coordinates to actuate"]),
    ("flexible node out of range", edit(lambda s: s.update({"flexible_bodies": [
        {"name": "beam", "beam": {"start": [0, 0, 0], "end": [1, 0, 0], "elements": 4},
         "section": {"shape": "circle", "d": 0.01}, "material": {"E": 2e11, "nu": 0.3, "rho": 7800},
         "supports": [{"node": 5, "type": "clamp"}]}]})),
     ["flexible_bodies[0].supports[0].node: expected a node index in 0..4, got 5"]),
    ("unknown section shape", edit(lambda s: s.update({"flexible_bodies": [
        {"name": "beam", "beam": {"start": [0, 0, 0], "end": [1, 0, 0], "elements": 4},
         "section": {"shape": "hexagon"}, "material": {"E": 2e11, "nu": 0.3, "rho": 7800}}]})),
     ["flexible_bodies[0].section.shape: unknown shape \"hexagon\""]),
    ("driven support without angle", edit(lambda s: s.update({"flexible_bodies": [
        {"name": "beam", "beam": {"start": [0, 0, 0], "end": [1, 0, 0], "elements": 4},
         "section": {"shape": "circle", "d": 0.01}, "material": {"E": 2e11, "nu": 0.3, "rho": 7800},
         "supports": [{"node": 0, "type": "driven", "axis": [0, 0, 1]}]}]})),
     ["flexible_bodies[0].supports[0]: a driven support takes exactly one of"]),
    ("joint on a node of an unknown flexible body", edit(lambda s: (hang_from_beam(s),
        s["joints"][0].update({"parent": {"flexible": "rod", "node": 4}}))),
     ["joints[0].parent.flexible: unknown flexible body \"rod\""]),
    ("joint on a node out of range", edit(lambda s: (hang_from_beam(s),
        s["joints"][0].update({"parent": {"flexible": "beam", "node": 9}}))),
     ["joints[0].parent.node: expected a node index in 0..4 of 'beam', got 9"]),
    ("joint between nodes", edit(lambda s: (hang_from_beam(s),
        s["joints"][0].update({"parent": {"flexible": "beam", "at": 0.3}}))),
     ["joints[0].parent.at: no node of 'beam' lies at 0.3 m from node 0", "choose an element count"]),
    ("node end with node and at", edit(lambda s: (hang_from_beam(s),
        s["joints"][0].update({"parent": {"flexible": "beam", "node": 4, "at": 1.0}}))),
     ["joints[0].parent: expected exactly one of \"node\" (an index) or \"at\" (a distance)"]),
    ("unknown beam mass", with_beam(mass="diagonal"),
     ["flexible_bodies[0].mass: expected \"consistent\" or \"lumped\""]),
    ("table of one point", with_beam(loads=[{"node": 4, "force": [0, 1, 0], "scale": {"table": [[0, 1]]}}]),
     ["flexible_bodies[0].loads[0].scale.table: expected at least 2 [t, value] points, got 1"]),
    ("table times not increasing", with_beam(supports=[{"node": 0, "type": "driven", "axis": [0, 0, 1],
                                                        "angle": {"table": [[0, 0], [1, 1], [1, 2]]}}]),
     ["flexible_bodies[0].supports[0].angle.table[2][0]: expected times increasing, got 1 after 1"]),
    ("table value not finite", edit(set_in(["joints", 0, "drive"], {"table": [[0, 0], [1, "1/0"]]})),
     ["joints[0].drive.table[1][1]: expected a finite number"]),
    ("table point not a pair", edit(set_in(["joints", 0, "drive"], {"table": [[0, 0], [1, 2, 3]]})),
     ["joints[0].drive.table[1]: expected a [t, value] pair"]),
    ("time function object without table", edit(set_in(["joints", 0, "drive"], {"points": [[0, 0], [1, 1]]})),
     ["joints[0].drive.points: unknown key; expected one of: table"]),
    ("initial equilibrium not a boolean", edit(set_in(["solver", "initial_equilibrium"], "yes")),
     ["solver.initial_equilibrium: expected true or false, got a string"]),
    ("duplicate names", edit(set_in(["joints", 0, "name"], "bob")),
     ["joints[0].name: duplicate name \"bob\" (already used at bodies[0].name)"]),
    ("unknown joint type", edit(set_in(["joints", 0, "type"], "hinge")), ["joints[0].type: unknown joint type \"hinge\""]),
    ("unknown parameter", edit(set_in(["bodies", 0, "position"], ["lenght", 0, 0])),
     ["bodies[0].position[0]", "unknown parameter 'lenght'"]),
    ("wrong vector length", edit(set_in(["joints", 0, "position"], [0, 0])),
     ["joints[0].position: expected 3 numbers, got 2"]),
    ("spectral radius out of range", edit(set_in(["solver", "rho_inf"], 2)),
     ["solver.rho_inf: expected a spectral radius in [0, 1]"]),
    ("unknown Newton matrix form", edit(set_in(["solver", "newton_matrix"], "dense")),
     ['solver.newton_matrix: expected "automatic", "joint_space" or "recursive"']),
    ("body without a joint", edit(lambda s: s["bodies"].append(
        {"name": "loose", "mass": 1, "inertia": [1, 1, 1], "position": [0, 0, 0]})),
     ["bodies[1]: body 'loose' has no joint to a parent", "\"free\" joint"]),
    ("parent loop", edit(parent_loop), ["body 'a' is on a loop of parent joints that never reaches ground"]),
    ("wrong coordinate count", edit(set_in(["joints", 0, "initial", "coordinates"], [0, 0])),
     ["joints[0].initial.coordinates: a revolute joint has 1 coordinates, got 2"]),
    ("joint to itself", edit(set_in(["joints", 0, "parent"], "bob")),
     ["joints[0].child: joint 'hinge' connects a body to itself"]),
    ("wrong format", edit(set_in(["format"], "mfbd-scene/0")), ["format: expected \"mfbd-scene/1\""]),
    ("drive object without a rate input", edit(lambda s: (s["joints"][0].pop("actuated"),
                                                          s["joints"][0].update({"drive": {"rate_input": False}}))),
     ["joints[0].drive.rate_input: expected true (or give the drive as an expression of t)"]),
    ("rate-input drive on a two-DOF joint", edit(lambda s: (s["joints"][0].pop("actuated"), s["joints"][0].update(
        {"type": "universal", "initial": {}, "drive": {"rate_input": True}}))),
     ["joints[0].drive: joint 'hinge': a drive prescribes the coordinate of a one-DOF tree joint"]),
]


@pytest.mark.parametrize("text,expected", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_pack_time_error_names_the_field(tmp_path, text, expected):
    result = pack(text, tmp_path)
    assert result.returncode == 1
    assert not (tmp_path / "scene.fmu").exists()
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr  # one error, one line
    for words in expected:
        assert words in lines[0], lines[0]


@pytest.mark.parametrize("text,expected", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_instantiate_error_names_the_field(pendulum_fmu, tmp_path, text, expected):
    # An FMU whose resources/scene.json is bad but whose GUID matches it.
    unzip = tmp_path / "fmu"
    extract(str(pendulum_fmu), str(unzip))
    (unzip / "resources" / "scene.json").write_text(text)
    guid = subprocess.run([str(PACKER), "--guid", str(unzip / "resources" / "scene.json")],
                          capture_output=True, text=True, check=True).stdout.strip()
    s = Slave(pendulum_fmu, unzip_dir=str(unzip))
    try:
        assert not s.instantiate(guid=guid)
        errors = [m for status, _, m in s.log if status == 3]
        assert len(errors) == 1
        assert errors[0].startswith("fmi2Instantiate: resources/scene.json: ")
        for words in expected:
            assert words in errors[0], errors[0]
    finally:
        s.free()


def test_at_least_fifteen_malformed_scenes():
    assert len(CASES) >= 15


def test_the_example_scene_itself_packs(tmp_path):
    result = pack(load_scene("pendulum"), tmp_path)
    assert result.returncode == 0, result.stderr
    assert "wrote" in result.stdout
