#!/usr/bin/env python3
"""Simulates the stiff flyball governor (R6) through its FMU at a large step
(h = 1e-2, far above the couplers' stiff time scales) and at a small one
(h = 1e-4), and plots the slider height, the rod angle, the coupler stretch
and the shaft drive torque; writes flyball_governor.csv and .png into --out.

    python examples/flyball_governor/plot.py build/fmus/flyball_governor.fmu --out out
"""
import argparse
import pathlib
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from fmpy import simulate_fmu  # noqa: E402

OUTPUTS = ["guide.position", "hinge1.angle", "coupler1.length", "coupler1.tension", "shaft_drive.drive_torque"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out"))
    parser.add_argument("--stop-time", type=float, default=10.0)
    args = parser.parse_args()

    runs = {}
    for h in (1e-2, 1e-4):
        start = time.perf_counter()
        runs[h] = simulate_fmu(str(args.fmu), stop_time=args.stop_time, output=OUTPUTS,
                               start_values={"solver.h_max": h})
        print(f"flyball_governor: h = {h:g}: {time.perf_counter() - start:.2f} s wall")
    t = runs[1e-2]["time"]
    args.out.mkdir(parents=True, exist_ok=True)
    csv = args.out / "flyball_governor.csv"
    columns = [t] + [runs[h][n] for h in runs for n in OUTPUTS]
    header = ["time"] + [f"{n}@h={h:g}" for h in runs for n in OUTPUTS]
    np.savetxt(csv, np.column_stack(columns), delimiter=",", header=",".join(header), comments="")

    fig, axes = plt.subplots(4, 1, figsize=(9, 9), sharex=True)
    panels = [("slider height [m]", lambda r: 0.5 + r["guide.position"]),
              ("rod angle below\nhorizontal [deg]", lambda r: 30.0 + np.degrees(r["hinge1.angle"])),
              ("coupler stretch [m]", lambda r: r["coupler1.length"] - 0.5),
              ("shaft drive torque [N m]", lambda r: r["shaft_drive.drive_torque"])]
    for ax, (label, value) in zip(axes, panels):
        for h, style in ((1e-4, "-"), (1e-2, "--")):
            ax.plot(runs[h]["time"], value(runs[h]), style, label=f"h = {h:g}")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("time [s]")
    error = np.max(np.abs(runs[1e-2]["guide.position"] - runs[1e-4]["guide.position"]))
    fig.suptitle(f"R6 stiff flyball governor (k = 8e5 N/m, c = 4e4 N s/m), shaft at 2 pi rad/s: "
                 f"slider at h = 1e-2 within {error:.1e} m of h = 1e-4", fontsize=9)
    fig.tight_layout()
    png = args.out / "flyball_governor.png"
    fig.savefig(png, dpi=110)
    print(f"flyball_governor: wrote {csv.resolve()} and {png.resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
