#!/usr/bin/env python3
"""Writes flyball_governor.json: R6, the stiff flyball governor (IFToMM A05).
A vertical shaft (1 x 0.01 x 0.01 m, density 3000) turns at a prescribed
speed Omega about z (gravity -z); at its top, 0.05 m either side of the axis,
two rods of the same section hang on hinges, 30 degrees below horizontal,
each with a 5 kg point mass at its tip; a slider (0.1 m cube, density 3000)
runs along the shaft on a prismatic joint, its centre at 0.5 m. The coupler
rods of the classic governor are spring-dampers (k = 8e5 N/m, c = 4e4 N s/m,
free length 0.5 m) from each rod's midpoint to the slider, 0.05 m off its
centre: at the start they are exactly at their free length.

    python examples/flyball_governor/make_scene.py
"""
import json
import math
import pathlib

DENSITY, SECTION, LENGTH = 3000.0, 0.01, 1.0
ROD_MASS = DENSITY * SECTION * SECTION * LENGTH  # 0.3 kg
CUBE = 0.1
SLIDER_MASS = DENSITY * CUBE ** 3  # 3 kg
BALL_MASS = 5.0
HINGE_OFFSET = 0.05  # hinges and spring attachments, either side of the axis
ALPHA = math.radians(30.0)  # rods below horizontal at the start
SLIDER_HEIGHT = 0.5
STIFFNESS, DAMPING, FREE_LENGTH = 8e5, 4e4, 0.5


def bar_inertia(mass):
    """Uniform bar along its body x axis."""
    return [mass * 2 * SECTION ** 2 / 12, mass * (LENGTH ** 2 + SECTION ** 2) / 12,
            mass * (LENGTH ** 2 + SECTION ** 2) / 12]


def flyball_governor() -> dict:
    bodies = [
        {"name": "shaft", "mass": ROD_MASS, "inertia": bar_inertia(ROD_MASS), "position": [0, 0, LENGTH / 2],
         "orientation": {"x_axis": [0, 0, 1], "z_axis": [1, 0, 0]}},
        {"name": "slider", "mass": SLIDER_MASS, "inertia": [SLIDER_MASS * CUBE ** 2 / 6] * 3,
         "position": [0, 0, SLIDER_HEIGHT]},
    ]
    joints = [
        {"name": "shaft_drive", "type": "revolute", "parent": "ground", "child": "shaft", "position": [0, 0, 0],
         "axis": [0, 0, 1], "drive": "Omega * t"},
        {"name": "guide", "type": "prismatic", "parent": "shaft", "child": "slider",
         "position": [0, 0, SLIDER_HEIGHT], "axis": [0, 0, 1]},
    ]
    forces = []
    for k, side in ((1, 1.0), (2, -1.0)):
        direction = [side * math.cos(ALPHA), 0.0, -math.sin(ALPHA)]  # from the hinge down and out
        hinge = [side * HINGE_OFFSET, 0.0, LENGTH]
        point = lambda s: [h + s * d for h, d in zip(hinge, direction)]  # noqa: E731
        bodies.append({"name": f"rod{k}", "mass": ROD_MASS, "inertia": bar_inertia(ROD_MASS),
                       "position": point(LENGTH / 2), "orientation": {"x_axis": direction, "z_axis": [0, 1, 0]}})
        bodies.append({"name": f"ball{k}", "mass": BALL_MASS, "inertia": [0, 0, 0], "position": point(LENGTH)})
        # Axis so that a positive hinge angle lowers the rod on either side.
        joints.append({"name": f"hinge{k}", "type": "revolute", "parent": "shaft", "child": f"rod{k}",
                       "position": hinge, "axis": [0, side, 0]})
        joints.append({"name": f"ball{k}_mount", "type": "fixed", "parent": f"rod{k}", "child": f"ball{k}",
                       "position": point(LENGTH)})
        forces.append({"name": f"coupler{k}", "type": "spring_damper", "body1": f"rod{k}", "point1": point(LENGTH / 2),
                       "body2": "slider", "point2": [side * HINGE_OFFSET, 0.0, SLIDER_HEIGHT],
                       "stiffness": STIFFNESS, "damping": DAMPING, "free_length": FREE_LENGTH})
    return {"format": "mfbd-scene/1", "name": "flyball_governor",
            "description": "R6: stiff flyball governor (IFToMM A05), shaft driven at Omega; "
                           "coupler rods as stiff spring-dampers (k = 8e5 N/m, c = 4e4 N s/m)",
            "parameters": {"Omega": {"value": 2 * math.pi, "unit": "rad/s", "description": "shaft speed"}},
            "gravity": [0, 0, -9.81], "solver": {"h_max": 1e-2, "rho_inf": 0.8},
            "experiment": {"stop_time": 10.0, "output_interval": 0.01},
            "bodies": bodies, "joints": joints, "forces": forces,
            "outputs": {"bodies": ["slider", "ball1", "ball2"], "joints": ["shaft_drive", "guide", "hinge1", "hinge2"]}}


if __name__ == "__main__":
    path = pathlib.Path(__file__).with_name("flyball_governor.json")
    path.write_text(json.dumps(flyball_governor(), indent=1) + "\n")
    print(f"wrote {path}")
