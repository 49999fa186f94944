#!/usr/bin/env python3
"""Drives the robot arm FMU with a PD controller plus gravity compensation,
the way a controller FMU or a master script would: set the six joint torques,
step, read the joint angles and rates. Writes a CSV and a plot.

    python examples/robot_arm/control.py build/fmus/robot_arm.fmu --out out
"""
import argparse
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from plotting import running_fmu  # noqa: E402

TARGET = np.array([0.8, -0.6, 1.0, 0.3, -0.5, 0.7])  # rad, from the design configuration
# Gains per joint: explicit feedback over a communication step dt is stable
# only while KD dt / J stays well below 1 for the inertia J the joint moves
# (the wrist rolls move about 1e-3 kg m^2).
KP, KD = np.array([400, 900, 500, 4, 20, 1.0]), np.array([60, 120, 60, 0.5, 2, 0.1])


def run(fmu_path, stop=3.0, step=1e-3, gravity_probe=1e-6):
    with running_fmu(fmu_path, "arm") as (fmu, vr):
        angles = [vr[f"j{i}.angle"] for i in range(1, 7)]
        rates = [vr[f"j{i}.angle_rate"] for i in range(1, 7)]
        torques = [vr[f"j{i}.torque"] for i in range(1, 7)]
        t, rows = 0.0, []
        while t < stop - 1e-12:
            q, qd = np.array(fmu.getReal(angles)), np.array(fmu.getReal(rates))
            tau = KP * (TARGET - q) - KD * qd
            fmu.setReal(torques, list(tau))
            fmu.doStep(t, step)
            t += step
            rows.append([t, *fmu.getReal(angles), *tau])
        return np.array(rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out"))
    args = parser.parse_args()
    data = run(args.fmu)
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
