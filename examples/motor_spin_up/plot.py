#!/usr/bin/env python3
"""Motor-driven spin-up (F4 with a rigid hub): simulates the FMU and plots
the tip deflection in the hub's rotating frame, the motor torque, and the
torque the fixed joint passes from hub to beam.

    python examples/motor_spin_up/plot.py build/fmus/motor_spin_up.fmu --out out
"""
import argparse
import pathlib
import sys

import numpy as np
from fmpy import simulate_fmu

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from plotting import save_figure, save_table  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out"))
    args = parser.parse_args()
    r = simulate_fmu(str(args.fmu), output_interval=0.02)
    t, hub = r["time"], r["motor.angle"]
    tip = -np.sin(hub) * r["beam.node8.position.x"] + np.cos(hub) * r["beam.node8.position.y"]
    columns = {"time": t, "motor.angle": hub, "tip_deflection": tip, "motor.drive_torque": r["motor.drive_torque"],
               "root.reaction_torque.z": r["root.reaction_torque.z"]}
    save_table(args.out / "motor_spin_up.csv", columns)
    save_figure(args.out / "motor_spin_up.png", t,
                [("tip deflection, hub frame [m]", {"tip": tip}),
                 ("torque [N m]", {"motor drive": r["motor.drive_torque"], "hub -> beam (fixed joint)":
                                   r["root.reaction_torque.z"]})],
                "Motor-driven spin-up of a flexible beam (F4 with a rigid hub)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
