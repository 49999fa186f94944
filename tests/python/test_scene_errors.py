"""Bad scenes give one clear error naming the JSON path and what was
expected: at pack time (non-zero exit, stderr) and at fmi2Instantiate (NULL,
message through the logger)."""
import copy
import json
import math
import shutil
import subprocess
import zipfile

import pytest
from fmpy import extract

from conftest import FMUS, OK, PACKER, ROOT, Slave, load_scene, pack


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


def unactuated(joint_type, mass=None, inertia=None):
    """The pendulum's hinge as another joint type, its bob changed."""
    def change(s):
        s["joints"][0].update({"type": joint_type, "initial": {}, "actuated": False})
        if mass is not None:
            s["bodies"][0]["mass"] = mass
        if inertia is not None:
            s["bodies"][0]["inertia"] = inertia
    return change


def coaxial_hinges(s):
    """A massless link between two hinges on one axis: turning one against
    the other moves nothing with mass."""
    s["bodies"].insert(0, {"name": "link", "mass": 0, "inertia": [0, 0, 0], "position": [0.5, 0, 0]})
    s["joints"][0]["child"] = "link"
    s["joints"].append({"name": "hinge2", "type": "revolute", "parent": "link", "child": "bob", "position": [0, 0, 0]})


def spin_up(angle):
    """spin_up_beam with another law for its driven support's angle."""
    scene = load_scene("spin_up_beam")
    scene["flexible_bodies"][0]["supports"][0]["angle"] = angle
    return json.dumps(scene)


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
    # Expressions: nesting is limited (10,000 levels overflowed the stack).
    ("nested parentheses", edit(set_in(["bodies", 0, "mass"], "(" * 10000 + "1" + ")" * 10000)),
     ["bodies[0].mass: in expression \"(((", "nested deeper than 100 levels"]),
    ("nested signs", edit(set_in(["bodies", 0, "mass"], "-" * 10000 + "1")), ["nested deeper than 100 levels"]),
    # Numbers: 0 or normal doubles up to 1e20, the same for JSON numbers and expressions.
    ("subnormal number", edit(set_in(["bodies", 0, "mass"], 1e-320)),
     ["bodies[0].mass: expected 0 or a magnitude of at least 2.2250738585072014e-308", "got 1e-320"]),
    ("subnormal expression", edit(set_in(["bodies", 0, "mass"], "1e-320")),
     ["bodies[0].mass: expected 0 or a magnitude of at least 2.2250738585072014e-308", "got 1e-320"]),
    ("number beyond 1e20", edit(set_in(["gravity"], [0, "-1e21", 0])),
     ["gravity[1]: expected a magnitude of at most 1e+20, got -1e+21"]),
    ("parameter beyond 1e20", edit(set_in(["parameters", "length", "value"], 1e300)),
     ["parameters.length.value: expected a magnitude of at most 1e+20, got 1e+300"]),
    ("body at 1e308", edit(set_in(["bodies", 0, "position"], [1e308, 0, 0])),
     ["bodies[0].position[0]: expected a coordinate within +-1e+06, got 1e+308"]),
    ("coordinate from a parameter", edit(set_in(["parameters", "length", "value"], 1e7)),
     ["bodies[0].position[0]: expected a coordinate within +-1e+06, got 1e+07"]),
    ("axis whose length overflows", edit(set_in(["joints", 0, "axis"], [1e200, 1e200, 0])),
     ["joints[0].axis[0]: expected a magnitude of at most 1e+20, got 1e+200"]),
    ("initial coordinate beyond 1e6", edit(set_in(["joints", 0, "initial", "coordinates"], ["1e9"])),
     ["joints[0].initial.coordinates[0]: expected a coordinate within +-1e+06, got 1e+09"]),
    # sqrt(t): rate 1 / (2 sqrt(t)), infinite at t = 0.
    ("drive rate not finite", spin_up("omega*sqrt(t)"),
     ["flexible_bodies[0].supports[0].angle: expected a finite angle rate and acceleration at t = 0"]),
    # Integers: range-checked before any conversion (4294967300 is not 4).
    ("element count beyond 32 bits", with_beam(beam={"start": [0, 0, 0], "end": [1, 0, 0], "elements": 4294967300}),
     ["flexible_bodies[0].beam.elements: expected an element count in 1..1000000, got 4294967300"]),
    ("support node beyond 32 bits", with_beam(supports=[{"node": 4294967296, "type": "clamp"}]),
     ["flexible_bodies[0].supports[0].node: expected a node index in 0..4, got 4294967296"]),
    ("joint node beyond 32 bits", edit(lambda s: (hang_from_beam(s),
        s["joints"][0].update({"parent": {"flexible": "beam", "node": 4294967296}}))),
     ["joints[0].parent.node: expected a node index in 0..2147483647, got 4294967296"]),
    ("iterations beyond 32 bits", edit(set_in(["solver", "max_iterations"], 4294967297)),
     ["solver.max_iterations: expected an integer in 1..100, got 4294967297"]),
    ("fractional integer", edit(set_in(["solver", "max_iterations"], 2.5)),
     ["solver.max_iterations: expected an integer in 1..100, got 2.5"]),
    # Text for modelDescription.xml: XML 1.0 has no control characters.
    ("control character in the description", edit(set_in(["description"], "a\u0001b")),
     ["description: character U+0001 at byte 1 cannot be written to modelDescription.xml"]),
    ("NUL in a parameter description", edit(set_in(["parameters", "mass", "description"], "bob\u0000")),
     ["parameters.mass.description: character U+0000 at byte 3"]),
    ("non-character in a unit", edit(set_in(["parameters", "mass", "unit"], "kg\uffff")),
     ["parameters.mass.unit: character U+FFFF at byte 2"]),
    ("scene name too long", edit(set_in(["name"], "p" * 300)),
     ["name: expected at most 64 characters", "got 300"]),
    # A motion of the rigid tree that moves no mass and that nothing holds.
    ("massless pendulum", edit(set_in(["parameters", "mass", "value"], 0)),
     ["joints[0]: the mass matrix is singular at the initial configuration: joint 'hinge'",
      "its child 'bob' (bodies[0]) has mass 0", "expected mass or inertia that the joint's motion moves"]),
    ("pendulum bob on the hinge", edit(set_in(["parameters", "length", "value"], 0)),
     ["joints[0]: the mass matrix is singular", "centre of mass 0 m from the joint"]),
    ("point mass on a spherical joint", edit(unactuated("spherical")),
     ["joints[0]: the mass matrix is singular", "has mass 1, principal moments [0, 0, 0]"]),
    ("massless body on a free joint", edit(unactuated("free", mass=0, inertia=[0, 0, 0])),
     ["joints[0]: the mass matrix is singular", "'bob' (bodies[0]) has mass 0"]),
    ("massless link between coaxial hinges", edit(coaxial_hinges),
     ["the mass matrix is singular", "joint 'hinge' (together with 'hinge2')", "its child 'link' (bodies[0])"]),
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


def test_the_readme_counts_the_malformed_scenes():
    readme = (ROOT / "README.md").read_text()
    assert f"has {len(CASES)} such" in " ".join(readme.split())


def test_the_example_scene_itself_packs(tmp_path):
    result = pack(load_scene("pendulum"), tmp_path)
    assert result.returncode == 0, result.stderr
    assert "wrote" in result.stdout


def test_massless_motions_that_something_holds_pack(tmp_path):
    """The mass check refuses only what nothing holds: a massless bob on a
    driven hinge, a massless link closed by a cut joint."""
    driven = edit(lambda s: (set_in(["parameters", "mass", "value"], 0)(s), s["joints"][0].pop("actuated"),
                             s["joints"][0].update({"drive": "sin(t)"})))
    assert pack(driven, tmp_path).returncode == 0
    closed = load_scene("pendulum")
    closed["bodies"].insert(0, {"name": "link", "mass": 0, "inertia": [0, 0, 0], "position": [0.5, 0, 0]})
    closed["joints"][0]["child"] = "link"
    closed["joints"] += [{"name": "hinge2", "type": "revolute", "parent": "link", "child": "bob",
                          "position": [0.5, 0, 0]},
                         {"name": "pin", "type": "revolute", "parent": "ground", "child": "link",
                          "position": [0.5, 0, 0], "cut": True}]
    result = pack(closed, tmp_path)
    assert result.returncode == 0, result.stderr


def test_a_long_chain_is_not_taken_for_massless(tmp_path):
    """The mass check's pivots of a 1000-link pendulum chain of point masses
    are 3e-9 of their scale: far from the round-off of a massless motion."""
    n, length = 1000, 1e-3
    scene = {"format": "mfbd-scene/1", "name": "chain", "gravity": [0, -9.81, 0],
             "bodies": [{"name": f"b{i}", "mass": 1e-3, "inertia": [0, 0, 0], "position": [(i + 1) * length, 0, 0]}
                        for i in range(n)],
             "joints": [{"name": f"j{i}", "type": "revolute", "parent": f"b{i - 1}" if i else "ground",
                         "child": f"b{i}", "position": [i * length, 0, 0]} for i in range(n)]}
    result = pack(scene, tmp_path)
    assert result.returncode == 0, result.stderr


def test_model_description_carries_every_text_exactly(tmp_path):
    """Markup characters, quotes and tab/LF/CR reach the XML's attributes as
    written (a reader would turn literal tabs and line breaks into spaces)."""
    etree = pytest.importorskip("lxml.etree")
    text = "a & b < c > d \"e\" 'f'\tg\nh\ri \u00e9\u4e2d"
    scene = load_scene("pendulum")
    scene["description"] = text
    scene["parameters"]["mass"].update({"unit": "k<g>&'\"", "description": text})
    result = pack(scene, tmp_path)
    assert result.returncode == 0, result.stderr
    with zipfile.ZipFile(tmp_path / "scene.fmu") as fmu:
        root = etree.fromstring(fmu.read("modelDescription.xml"))  # raises if not well-formed
    assert root.get("description") == text
    mass = root.find("ModelVariables/ScalarVariable[@name='mass']")
    assert mass.get("description") == text
    assert mass.find("Real").get("unit") == "k<g>&'\""
    assert "k<g>&'\"" in [u.get("name") for u in root.iter("Unit")]


def test_markup_and_non_ascii_texts_validate_and_run(tmp_path):
    """Texts with markup characters, quotes and non-ASCII letters in every
    place the XML carries free text (the model's and each parameter's
    description, units; names are identifiers, checked by the parser): the
    XML parses to the same texts, fmpy validates the FMU and runs it."""
    etree = pytest.importorskip("lxml.etree")
    from fmpy import simulate_fmu
    from fmpy.validation import validate_fmu
    scene = load_scene("pendulum")
    scene["description"] = "<model> & \"pendulum\" 'A01' \u00e9\u4e2d"
    texts = {}
    for i, (name, p) in enumerate(scene["parameters"].items()):
        texts[name] = f"{name} <{i}> & \"{i}\" '\u00fc{i}'"
        p.update({"description": texts[name], "unit": p.get("unit", "1")})
    result = pack(scene, tmp_path)
    assert result.returncode == 0, result.stderr
    fmu = tmp_path / "scene.fmu"
    with zipfile.ZipFile(fmu) as z:
        root = etree.fromstring(z.read("modelDescription.xml"))  # raises if not well-formed
    assert root.get("description") == scene["description"]
    described = {v.get("name"): v.get("description") for v in root.iter("ScalarVariable")}
    assert all(described[name] == text for name, text in texts.items()), described
    assert validate_fmu(str(fmu)) == []
    assert len(simulate_fmu(str(fmu), stop_time=0.01)) > 0


@pytest.mark.parametrize("fmu,name,value,words", [
    ("pendulum", "mass", 0.0, "joints[0]: the mass matrix is singular"),
    ("pendulum", "length", 0.0, "joints[0]: the mass matrix is singular"),
    ("pendulum", "length", 1e300, "parameters.length: expected a magnitude of at most 1e+20"),
    ("pendulum", "length", 1e7, "bodies[0].position[0]: expected a coordinate within +-1e+06"),
    ("spin_up_beam", "omega", 1e300, "parameters.omega: expected a magnitude of at most 1e+20"),
])
def test_parameter_that_breaks_the_scene_is_refused_at_set_time(fmu, name, value, words):
    """fmi2SetReal re-checks the scene with the new value: refused with the
    field it breaks, and the FMU keeps the old value and runs as before."""
    s = Slave(FMUS / f"{fmu}.fmu")
    try:
        assert s.instantiate()
        assert s.call("setupExperiment", None, 0.0, None) == OK
        assert s.set(name, value) != OK
        errors = [m for status, _, m in s.log if status == 3]
        assert len(errors) == 1 and words in errors[0], errors
        assert s.call("enterInitializationMode") == OK, s.messages()
        start = next(v.start for v in s.md.modelVariables if v.name == name)
        assert s.get(name) == float(start)
        assert s.call("exitInitializationMode") == OK and s.step(0.0, 0.01) == OK, s.messages()
    finally:
        s.free()
        shutil.rmtree(s.unzip_dir, ignore_errors=True)


def test_a_spin_up_of_no_time_drives_at_full_rate_from_the_start():
    """spin_up_beam's law is if(T - t, ramp over T, omega T/2 + omega (t - T)).
    With T = 0 it is omega t wherever it is evaluated (t >= 0), with exact
    derivatives omega and 0: accepted, and the support turns at omega from
    the start. (Central differences of the law straddled t = 0, met the
    ramp's omega / T there and refused T = 0.)"""
    s = Slave(FMUS / "spin_up_beam.fmu")
    try:
        assert s.instantiate()
        assert s.call("setupExperiment", None, 0.0, None) == OK
        assert s.set("T", 0.0) == OK, s.messages()
        assert s.call("enterInitializationMode") == OK and s.call("exitInitializationMode") == OK, s.messages()
        omega = s.get("omega")
        assert s.get("beam.node0.angular_velocity.z") == pytest.approx(omega, rel=1e-12)
        for k in range(5):
            assert s.step(0.1 * k, 0.1) == OK, s.messages()
        w, z, rate = s.get("beam.node0.orientation.w", "beam.node0.orientation.z", "beam.node0.angular_velocity.z")
        assert rate == pytest.approx(omega, rel=1e-12)
        assert 2.0 * math.atan2(z, w) == pytest.approx(math.remainder(omega * 0.5, 2.0 * math.pi), abs=1e-12)
    finally:
        s.free()
        shutil.rmtree(s.unzip_dir, ignore_errors=True)
