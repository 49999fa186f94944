#!/usr/bin/env python3
"""Writes n_four_bar.json: IFToMM A02 with N = 40, 2N + 1 uniform links (1 m,
1 kg): N + 1 vertical cranks on ground pivots at x = 0..N, N horizontal
couplers; the top of crank 0 starts at 1 m/s. Tree: every crank on its
ground pivot, every coupler on its crank's top (two levels); each coupler's
joint to the next crank's top is a cut joint. (Cutting the pivots instead
makes a chain 81 bodies deep, whose joint-space Newton matrix is dense:
81 x 81 against a band of three rates per loop here.)

    python examples/n_four_bar/make_scene.py [N]
"""
import json
import math
import pathlib
import sys


def n_four_bar(N: int = 40, start_angle: float = 0.0) -> dict:
    """The scene as a dict. start_angle turns every crank from vertical
    (negative: the top towards +x); -pi/2 starts at the singular
    configuration, cranks and couplers all on the x axis."""
    m, L = 1.0, 1.0
    bar = [0.0, m * L * L / 12, m * L * L / 12]
    bodies, joints = [], []
    for i in range(N + 1):
        bodies.append({"name": f"crank{i}", "mass": m, "inertia": bar, "position": [i, 0.5, 0],
                       "orientation": {"x_axis": [0, 1, 0], "z_axis": [0, 0, 1]}})
        if i < N:
            bodies.append({"name": f"coupler{i}", "mass": m, "inertia": bar, "position": [i + 0.5, 1, 0]})

    def initial(angle, rate):
        return {"coordinates": [angle], "rates": [rate]} if angle else {"rates": [rate]}

    # Crank rates -1 rad/s (top moves +x at 1 m/s); couplers translate: relative rate +1.
    for i in range(N + 1):
        joints.append({"name": f"pivot{i}", "type": "revolute", "parent": "ground", "child": f"crank{i}",
                       "position": [i, 0, 0], "initial": initial(start_angle, -1.0)})
        if i < N:
            joints.append({"name": f"top{i}", "type": "revolute", "parent": f"crank{i}", "child": f"coupler{i}",
                           "position": [i, 1, 0], "initial": initial(-start_angle, 1.0)})
    for i in range(N):
        joints.append({"name": f"end{i}", "type": "revolute", "parent": f"coupler{i}", "child": f"crank{i + 1}",
                       "position": [i + 1, 1, 0], "cut": True})
    return {"format": "mfbd-scene/1", "name": "n_four_bar",
            "description": f"R3: N-four-bar (IFToMM A02), N = {N}; passes singular configurations "
                           "(cranks horizontal)",
            "gravity": [0, -9.81, 0], "solver": {"h_max": 1e-3, "rho_inf": 0.8},
            "experiment": {"stop_time": 20.0, "output_interval": 0.01}, "bodies": bodies, "joints": joints,
            "outputs": {"joints": ["pivot0", f"pivot{N}"]}}


if __name__ == "__main__":
    N = int(sys.argv[1]) if len(sys.argv) > 1 else 40
    path = pathlib.Path(__file__).with_name("n_four_bar.json")
    path.write_text(json.dumps(n_four_bar(N), indent=1) + "\n")
    print(f"wrote {path}")
