#!/usr/bin/env python3
"""Drives the flexible two-link arm FMU with a joint-space PD controller plus
gravity compensation computed from a rigid-link model, as a controller FMU or
a master script would: set the shoulder and elbow torques, step, read the
joint angles and rates. The forearm bends: the payload's distance from where
rigid links would put it shows the flexible motion. Writes a CSV and a plot.

    python examples/flexible_robot_arm/control.py build/fmus/flexible_robot_arm.fmu --out out
"""
import argparse
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from plotting import running_fmu, save_figure, save_table  # noqa: E402

L1, L2, M1, MH, MP, G = 0.5, 0.6, 2.0, 0.5, 0.5, 9.81
M2 = 2700 * np.pi * 0.006 ** 2 * L2  # forearm mass (aluminium rod, 12 mm)
START, GOAL, MOVE = np.zeros(2), np.array([0.8, -1.2]), 1.5  # rad, rad, s
KP, KD = np.array([300.0, 80.0]), np.array([25.0, 5.0])


def reference(t):
    """Quintic rest-to-rest move from START to GOAL over MOVE seconds."""
    s = min(t / MOVE, 1.0)
    return START + (GOAL - START) * (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)


def gravity_torque(q):
    """Static joint torques of rigid links holding themselves against gravity."""
    c1, c12 = np.cos(q[0]), np.cos(q[0] + q[1])
    elbow = G * (M2 * L2 / 2 + MP * L2) * c12
    return np.array([G * (M1 * L1 / 2 + (MH + M2 + MP) * L1) * c1 + elbow, elbow])


def run(fmu_path, stop=3.0, step=1e-3):
    with running_fmu(fmu_path, "arm") as (fmu, vr):
        angles, rates = [vr["shoulder.angle"], vr["elbow.angle"]], [vr["shoulder.angle_rate"], vr["elbow.angle_rate"]]
        torques = [vr["shoulder.torque"], vr["elbow.torque"]]
        payload = [vr["payload.position.x"], vr["payload.position.y"]]
        t, rows = 0.0, []
        while t < stop - 1e-12:
            q, qd = np.array(fmu.getReal(angles)), np.array(fmu.getReal(rates))
            tau = gravity_torque(q) + KP * (reference(t) - q) - KD * qd
            fmu.setReal(torques, list(tau))
            fmu.doStep(t, step)
            t += step
            q = np.array(fmu.getReal(angles))
            rigid = np.array([L1 * np.cos(q[0]) + L2 * np.cos(q[0] + q[1]), L1 * np.sin(q[0]) + L2 * np.sin(q[0] + q[1])])
            rows.append([t, *q, *reference(t), *tau, np.linalg.norm(np.array(fmu.getReal(payload)) - rigid)])
        return np.array(rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out"))
    args = parser.parse_args()
    d = run(args.fmu)
    names = ["time", "shoulder.angle", "elbow.angle", "shoulder.reference", "elbow.reference", "shoulder.torque",
             "elbow.torque", "payload_deflection"]
    save_table(args.out / "flexible_robot_arm.csv", dict(zip(names, d.T)))
    t = d[:, 0]
    save_figure(args.out / "flexible_robot_arm.png", t,
                [("joint angle [rad]", {"shoulder": d[:, 1], "elbow": d[:, 2], "shoulder ref": d[:, 3],
                                        "elbow ref": d[:, 4]}),
                 ("joint torque [N m]", {"shoulder": d[:, 5], "elbow": d[:, 6]}),
                 ("payload off rigid links [mm]", {"payload": 1e3 * d[:, 7]})],
                "Two-link arm with a flexible forearm under PD + gravity compensation")
    print(f"control: final angle errors {np.round(GOAL - d[-1, 1:3], 4)} rad, "
          f"payload deflection {1e3 * d[-1, 7]:.2f} mm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
