"""solver.initial_equilibrium: fmi2ExitInitializationMode moves a dynamic
scene to its static equilibrium under gravity and loads, and the run starts
there at rest."""
import re

import numpy as np

from conftest import Slave, load_scene, packed
from test_flexible import with_elements


def hanging_cantilever(n, g, **solver):
    """The F3 cantilever (EI = rhoA = L = 1, shear-rigid) clamped at x = 0
    and loaded by its own weight, q = rhoA g, in -y."""
    scene = with_elements(load_scene("cantilever_vibration"), n)
    scene["flexible_bodies"][0]["loads"] = []
    scene["gravity"] = [0, -g, 0]
    scene["solver"] = {"h_max": 1e-3, "rho_inf": 0.9, "initial_equilibrium": True, **solver}
    return scene


def start(scene, tmp_path, name):
    s = Slave(packed(scene, tmp_path, name), instance_name=name)
    assert s.instantiate(logging_on=True)
    assert s.call("setupExperiment", None, 0.0, None) == 0
    assert s.call("enterInitializationMode") == 0, s.messages()
    assert s.call("exitInitializationMode") == 0, s.messages()
    return s


def test_cantilever_under_gravity_starts_at_rest_in_its_static_deflection(tmp_path):
    n, g = 16, 1e-3
    s = start(hanging_cantilever(n, g), tmp_path, "hanging")
    try:
        line = [m for m in s.messages().splitlines() if m.startswith("initial equilibrium")]
        assert len(line) == 1 and "in 1 load step" in line[0] and f"(node {n} of 'beam')" in line[0], line
        tip = f"beam.node{n}"
        y0 = s.get(f"{tip}.position.y")
        # Small deflection: q L^4 / (8 E I). The consistent mass carries the
        # weight as the consistent load (nodal forces and moments q h^2 / 12),
        # under which the cubic beam elements are exact at the nodes (nodal
        # forces alone would leave 1.6e-3 at 16 elements).
        exact = g / 8
        assert abs(-y0 / exact - 1) < 1e-6, (y0, exact)
        # At rest: no motion beyond round-off over 1 s (started straight, the
        # tip would swing at about q L^4/(8 EI) omega_1 = 4e-4 m/s).
        t, speed, drift = 0.0, 0.0, 0.0
        for _ in range(100):
            assert s.step(t, 0.01) == 0
            t += 0.01
            speed = max(speed, abs(s.get(f"{tip}.velocity.y")))
            drift = max(drift, abs(s.get(f"{tip}.position.y") - y0))
        assert speed < 1e-12 and drift < 1e-14, (speed, drift)
    finally:
        s.free()


def test_heavy_cantilever_reaches_the_same_equilibrium_by_load_steps(tmp_path):
    # Self-weight q L^3 / EI = 6 bends the beam far (tip 0.56 L below the
    # root). The full load takes 8 Newton iterations from the straight beam:
    # allowed 7 per solve, load stepping takes over (5 steps); it must land
    # on the equilibrium that the direct solve finds.
    n = 8
    tips = {}
    for name, iterations in (("direct", 30), ("stepped", 7)):
        s = start(hanging_cantilever(n, 6.0, max_iterations=iterations), tmp_path, name)
        try:
            steps = int(re.search(r"in (\d+) load step", s.messages()).group(1))
            assert (steps == 1) == (name == "direct"), s.messages()
            tips[name] = np.array(s.get(f"beam.node{n}.position.x", f"beam.node{n}.position.y"))
        finally:
            s.free()
    assert tips["direct"][1] < -0.5
    assert np.max(np.abs(tips["stepped"] - tips["direct"])) < 1e-10


def test_unreachable_equilibrium_is_an_error_at_exit_initialization_mode(tmp_path):
    # A free flexible body (no support) under gravity has no equilibrium.
    scene = hanging_cantilever(4, 1.0)
    scene["flexible_bodies"][0]["supports"] = []
    s = Slave(packed(scene, tmp_path, "falling"), instance_name="falling")
    try:
        assert s.instantiate(logging_on=True)
        assert s.call("setupExperiment", None, 0.0, None) == 0
        assert s.call("enterInitializationMode") == 0, s.messages()
        assert s.call("exitInitializationMode") == 3
        assert "fmi2ExitInitializationMode: initial equilibrium:" in s.messages()
    finally:
        s.free()
