#!/usr/bin/env python3
"""Simulates the N-four-bar (R3) through its FMU and plots the crank angle,
the largest cut-pivot violation |Phi| and the energy error against time;
writes n_four_bar.csv and n_four_bar.png into --out.

    python examples/n_four_bar/plot.py build/fmus/n_four_bar.fmu --out out
"""
import argparse
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from fmpy import read_model_description, simulate_fmu  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

G = 9.81


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out"))
    parser.add_argument("--stop-time", type=float, default=None)
    args = parser.parse_args()

    md = read_model_description(str(args.fmu))
    N = sum(1 for v in md.modelVariables if v.name.startswith("crank") and v.name.endswith(".position.x")) - 1
    outputs = [f"crank{i}.{q}.{c}" for i in range(N + 1) for q in ("position", "velocity") for c in "xy"]
    outputs += [f"crank{i}.angular_velocity.z" for i in range(N + 1)]
    outputs += [f"crank{i}.orientation.{c}" for i in range(N + 1) for c in "wxyz"]
    r = simulate_fmu(str(args.fmu), stop_time=args.stop_time, output=outputs)
    t = r["time"]

    def bar_energy(position, velocity, omega):  # uniform 1 m, 1 kg bar
        return 0.5 * np.sum(velocity ** 2, axis=1) + 0.5 / 12 * omega ** 2 + G * position[:, 1]

    axis, top, top_velocity, energy = [], [], [], 0.0
    for i in range(N + 1):
        a = Rotation.from_quat(np.column_stack([r[f"crank{i}.orientation.{c}"] for c in "xyzw"])).as_matrix()[:, :2, 0]
        p = np.column_stack([r[f"crank{i}.position.x"], r[f"crank{i}.position.y"]])
        v = np.column_stack([r[f"crank{i}.velocity.x"], r[f"crank{i}.velocity.y"]])
        w = r[f"crank{i}.angular_velocity.z"]
        axis.append(a)
        top.append(p + 0.5 * a)
        top_velocity.append(v + 0.5 * w[:, None] * np.column_stack([-a[:, 1], a[:, 0]]))
        energy = energy + bar_energy(p, v, w)
    for i in range(N):  # each coupler joins two crank tops
        d, dv = top[i + 1] - top[i], top_velocity[i + 1] - top_velocity[i]
        omega = (d[:, 0] * dv[:, 1] - d[:, 1] * dv[:, 0]) / np.sum(d * d, axis=1)
        energy = energy + bar_energy(0.5 * (top[i] + top[i + 1]), 0.5 * (top_velocity[i] + top_velocity[i + 1]), omega)
    # The bottom end of crank i must sit on its ground pivot (i, 0).
    phi = np.max([np.max(np.abs(top[i] - axis[i] - [i, 0.0]), axis=1) for i in range(1, N + 1)], axis=0)
    angle = np.unwrap(np.arctan2(axis[0][:, 1], axis[0][:, 0]))
    error = (energy - energy[0]) / energy[0]

    args.out.mkdir(parents=True, exist_ok=True)
    csv = args.out / "n_four_bar.csv"
    np.savetxt(csv, np.column_stack([t, angle, phi, energy]), delimiter=",",
               header="time,crank0_angle,max_pivot_violation,energy", comments="")
    fig, axes = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True)
    axes[0].plot(t, angle)
    for k in range(int(np.floor(angle.min() / np.pi)), int(np.ceil(angle.max() / np.pi)) + 1):
        axes[0].axhline(k * np.pi, color="grey", lw=0.5)  # cranks horizontal: singular
    axes[0].set_ylabel("crank 0 angle [rad]\n(grey: singular)")
    axes[1].semilogy(t, np.maximum(phi, 1e-17))
    axes[1].set_ylabel("max |Phi| of the\ncut pivots [m]")
    axes[2].plot(t, error)
    axes[2].set_ylabel("(E - E0) / E0")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"R3 N-four-bar, N = {N}: max |Phi| = {phi.max():.1e} m, "
                 f"max |dE|/E0 = {np.abs(error).max():.1e}", fontsize=10)
    fig.tight_layout()
    png = args.out / "n_four_bar.png"
    fig.savefig(png, dpi=110)
    print(f"n_four_bar: N = {N}, t = {t[0]:g} .. {t[-1]:g} s, max |Phi| = {phi.max():.2e} m, "
          f"max |E - E0|/E0 = {np.abs(error).max():.2e}, singular passes = {np.count_nonzero(np.diff(np.sign(axis[0][:, 1])))}")
    print(f"n_four_bar: wrote {csv.resolve()} and {png.resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
