#!/usr/bin/env python3
"""Drives the robot arm FMU with a PD controller plus gravity compensation,
the way a controller FMU or a master script would: set the six joint torques,
step, read the joint angles and rates. Writes a CSV and a plot.

The gravity compensation is a static model of the arm read from the FMU
itself (its resources/scene.json: masses, centres of mass, joint positions
and axes, gravity): at the present angles q, each joint gets the torque
that holds the bodies beyond it against gravity,
G_i(q) = -sum_j (a_i x (c_j - p_i)) . m_j g, with the axis a_i, the joint
origin p_i and the centres c_j turned by the joints (revolute joints in a
tree). Without it the PD loop sags under gravity (--no-gravity).

    python examples/robot_arm/control.py build/fmus/robot_arm.fmu --out out
"""
import argparse
import json
import pathlib
import sys
import zipfile

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from plotting import running_fmu  # noqa: E402

TARGET = np.array([0.8, -0.6, 1.0, 0.3, -0.5, 0.7])  # rad, from the design configuration
# Gains per joint: explicit feedback over a communication step dt is stable
# only while KD dt / J stays well below 1 for the inertia J the joint moves
# (the wrist rolls move about 1e-3 kg m^2).
KP, KD = np.array([400, 900, 500, 4, 20, 1.0]), np.array([60, 120, 60, 0.5, 2, 0.1])


def rotation(axis, angle):
    """Rotation matrix about a unit axis (Rodrigues)."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


class GravityModel:
    """Static gravity torques of a tree of revolute joints, from the scene
    packed in the FMU (numbers only, bodies' centres of mass at their
    frames' origins plus center_of_mass in the design orientation)."""

    def __init__(self, fmu_path):
        with zipfile.ZipFile(fmu_path) as z:
            scene = json.loads(z.read("resources/scene.json"))
        self.g = np.array(scene["gravity"], dtype=float)
        self.joints = scene["joints"]
        if any(j["type"] != "revolute" for j in self.joints):
            raise ValueError("GravityModel: revolute joints only")
        self.bodies = {b["name"]: (float(b["mass"]), np.add(b["position"], b.get("center_of_mass", [0, 0, 0])))
                       for b in scene["bodies"]}

    def torques(self, q):
        """-sum over the bodies beyond each joint of (a x (c - p)) . m g, posed at q."""
        pose = {"ground": (np.eye(3), np.zeros(3))}  # body -> (R, t): design point x is at R x + t
        frames = []
        for joint, angle in zip(self.joints, q):  # scene order: parents before children
            R0, t0 = pose[joint["parent"]]
            p = np.array(joint["position"], dtype=float)
            a = np.array(joint["axis"], dtype=float) / np.linalg.norm(joint["axis"])
            Rj = rotation(a, angle)
            pose[joint["child"]] = (R0 @ Rj, R0 @ (p - Rj @ p) + t0)
            frames.append((R0 @ a, R0 @ p + t0, joint["child"]))
        children = {j["child"]: j["parent"] for j in self.joints}
        G = np.zeros(len(self.joints))
        for name, (m, c) in self.bodies.items():
            R, t = pose[name]
            weight_arm = R @ c + t
            for i, (axis, origin, child) in enumerate(frames):
                body = name
                while body != "ground" and body != child:
                    body = children[body]
                if body == child:
                    G[i] -= np.cross(axis, weight_arm - origin) @ (m * self.g)
        return G


def run(fmu_path, stop=3.0, step=1e-3, gravity=True):
    model = GravityModel(fmu_path)
    with running_fmu(fmu_path, "arm") as (fmu, vr):
        angles = [vr[f"j{i}.angle"] for i in range(1, 7)]
        rates = [vr[f"j{i}.angle_rate"] for i in range(1, 7)]
        torques = [vr[f"j{i}.torque"] for i in range(1, 7)]
        t, rows = 0.0, []
        while t < stop - 1e-12:
            q, qd = np.array(fmu.getReal(angles)), np.array(fmu.getReal(rates))
            tau = KP * (TARGET - q) - KD * qd + (model.torques(q) if gravity else 0.0)
            fmu.setReal(torques, list(tau))
            fmu.doStep(t, step)
            t += step
            rows.append([t, *fmu.getReal(angles), *tau])
        return np.array(rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out"))
    parser.add_argument("--no-gravity", action="store_true", help="PD alone: the arm sags")
    args = parser.parse_args()
    data = run(args.fmu, gravity=not args.no_gravity)
    args.out.mkdir(parents=True, exist_ok=True)
    header = "time," + ",".join(f"j{i}.angle" for i in range(1, 7)) + "," + ",".join(f"j{i}.torque" for i in range(1, 7))
    np.savetxt(args.out / "robot_arm.csv", data, delimiter=",", header=header, comments="")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for i in range(6):
        a.plot(data[:, 0], data[:, 1 + i], label=f"j{i + 1}")
        a.axhline(TARGET[i], color=a.lines[-1].get_color(), ls=":", lw=0.8)
        b.plot(data[:, 0], data[:, 7 + i], label=f"j{i + 1}")
    a.set_ylabel("joint angle [rad]")
    b.set_ylabel("joint torque [N m]")
    b.set_xlabel("time [s]")
    a.legend(ncol=6, fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out / "robot_arm.png", dpi=110)
    print(f"control: final angle errors {np.round(TARGET - data[-1, 1:7], 4)} rad")
    print(f"control: wrote {(args.out / 'robot_arm.csv').resolve()} and {(args.out / 'robot_arm.png').resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
