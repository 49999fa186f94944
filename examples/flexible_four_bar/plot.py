#!/usr/bin/env python3
"""F6: simulates the flexible four-bar with a 5 degree defect through one
revolution of bar 1 and plots the section forces and moments at the root of
bar 1 and of bar 3 (element frame), and the drive torque.

    python examples/flexible_four_bar/plot.py build/fmus/flexible_four_bar.fmu --out out
"""
import argparse
import pathlib
import sys

from fmpy import simulate_fmu

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from plotting import save_figure, save_table  # noqa: E402

SECTION = {"force.x": "N", "force.y": "Vy", "force.z": "Vz", "moment.x": "T", "moment.y": "My", "moment.z": "Mz"}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out"))
    args = parser.parse_args()
    r = simulate_fmu(str(args.fmu), output_interval=0.02)
    t = r["time"]
    columns = {"time": t, "A.drive_torque": r["A.drive_torque"]}
    panels = []
    for bar in ("bar1", "bar3"):
        for kind, unit in (("force", "N"), ("moment", "N m")):
            curves = {SECTION[f"{kind}.{c}"]: r[f"{bar}.element0.end1.{kind}.{c}"] for c in "xyz"}
            columns.update({f"{bar}.root.{k}": v for k, v in curves.items()})
            panels.append((f"{bar} root {kind} [{unit}]", curves))
    panels.append(("drive torque [N m]", {"A": r["A.drive_torque"]}))
    save_table(args.out / "flexible_four_bar.csv", columns)
    save_figure(args.out / "flexible_four_bar.png", t, panels,
                "F6 flexible four-bar, joint C tilted 5 deg: section forces through one revolution of bar 1")
    return 0


if __name__ == "__main__":
    sys.exit(main())
