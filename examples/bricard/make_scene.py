#!/usr/bin/env python3
"""Writes bricard.json: IFToMM A04, five uniform rods (1 kg, 1 m, 0.1 m square)
and six revolute joints at P1..P6 with axes y, z, x, y, z, x; gravity -y."""
import json
import pathlib

P = [(0, 0, 0), (1, 0, 0), (1, -1, 0), (1, -1, 1), (0, -1, 1), (0, 0, 1)]
AXES = [(0, 1, 0), (0, 0, 1), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 0)]
m, L, a = 1.0, 1.0, 0.1
along, across = m * 2 * a * a / 12, m * (L * L + a * a) / 12

bodies, joints = [], []
for i in range(5):
    start, end = P[i], P[i + 1]
    direction = [e - s for s, e in zip(start, end)]
    other = [0, 0, 1] if abs(direction[2]) < 0.5 else [1, 0, 0]
    bodies.append({"name": f"rod{i + 1}", "mass": m, "inertia": [along, across, across],
                   "position": [(s + e) / 2 for s, e in zip(start, end)],
                   "orientation": {"x_axis": direction, "z_axis": [o - d * sum(x * y for x, y in zip(other, direction))
                                                                for o, d in zip(other, direction)]}})
for i in range(6):
    parent = "ground" if i == 0 else f"rod{i}"
    child = f"rod{i + 1}" if i < 5 else "rod5"
    joint = {"name": f"J{i + 1}", "type": "revolute", "parent": parent, "child": child, "position": list(P[i]),
             "axis": list(AXES[i])}
    if i == 5:  # closes the loop back to ground
        joint.update({"parent": "ground", "child": "rod5", "cut": True})
    joints.append(joint)
scene = {"format": "mfbd-scene/1", "name": "bricard",
         "description": "R4: Bricard mechanism (IFToMM A04); Grubler count 0, true mobility 1: one redundant constraint",
         "gravity": [0, -9.81, 0], "solver": {"h_max": 1e-3, "rho_inf": 1.0},
         "experiment": {"stop_time": 10.0, "output_interval": 0.01}, "bodies": bodies, "joints": joints}
pathlib.Path(__file__).with_name("bricard.json").write_text(json.dumps(scene, indent=2) + "\n")
