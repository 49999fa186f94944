#!/usr/bin/env python3
"""Simulate an MFBD-FMU through fmpy with its default experiment; write every
output to a CSV and plot joint coordinates, reactions and body positions.

    python examples/simulate.py build/fmus/pendulum.fmu --out out [--stop-time 10]
"""
import argparse
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from fmpy import read_model_description, simulate_fmu  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out"))
    parser.add_argument("--stop-time", type=float, default=None)
    parser.add_argument("--output-interval", type=float, default=None)
    args = parser.parse_args()

    md = read_model_description(str(args.fmu))
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    result = simulate_fmu(str(args.fmu), stop_time=args.stop_time, output_interval=args.output_interval,
                          output=outputs)
    name = args.fmu.stem
    args.out.mkdir(parents=True, exist_ok=True)
    csv = args.out / f"{name}.csv"
    np.savetxt(csv, np.column_stack([result[c] for c in result.dtype.names]), delimiter=",",
               header=",".join(result.dtype.names), comments="")

    groups = [
        ("joint coordinates", lambda n: n.split(".")[-1] in {"angle", "position", "x", "y", "z", "angle1", "angle2"}
         and n.count(".") == 1),
        ("joint reaction force [N]", lambda n: ".reaction_force." in n),
        ("body position [m]", lambda n: ".position." in n),
        ("body velocity [m/s]", lambda n: ".velocity." in n and "angular" not in n),
    ]
    fig, axes = plt.subplots(len(groups), 1, figsize=(9, 2.6 * len(groups)), sharex=True)
    t = result["time"]
    for ax, (title, pick) in zip(axes, groups):
        for n in outputs:
            if pick(n):
                ax.plot(t, result[n], label=n)
        ax.set_ylabel(title)
        ax.grid(True, alpha=0.3)
        if ax.lines:
            ax.legend(fontsize=7, loc="upper right", ncol=2)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(f"{md.modelName}: {md.description}", fontsize=9)
    fig.tight_layout()
    png = args.out / f"{name}.png"
    fig.savefig(png, dpi=110)
    print(f"simulate: {len(t)} output points, t = {t[0]:g} .. {t[-1]:g} s")
    print(f"simulate: wrote {csv.resolve()}")
    print(f"simulate: wrote {png.resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
