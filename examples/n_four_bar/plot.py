#!/usr/bin/env python3
"""Simulates the N-four-bar (R3) through its FMU and plots the crank angle,
the largest cut-joint violation |Phi| (each coupler's end on the next
crank's top) and the energy error against time;
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
    bars = [f"crank{i}" for i in range(N + 1)] + [f"coupler{i}" for i in range(N)]
    outputs = [f"{b}.{q}.{c}" for b in bars for q in ("position", "velocity") for c in "xy"]
    outputs += [f"{b}.angular_velocity.z" for b in bars]
    outputs += [f"{b}.orientation.{c}" for b in bars for c in "wxyz"]
    r = simulate_fmu(str(args.fmu), stop_time=args.stop_time, output=outputs)
    t = r["time"]

    def bar_energy(position, velocity, omega):  # uniform 1 m, 1 kg bar
        return 0.5 * np.sum(velocity ** 2, axis=1) + 0.5 / 12 * omega ** 2 + G * position[:, 1]

    axis, centre, energy = {}, {}, 0.0
    for b in bars:
        # Body x axis: a crank's from its pivot to its top, a coupler's from its top to its end.
        axis[b] = Rotation.from_quat(np.column_stack([r[f"{b}.orientation.{c}"] for c in "xyzw"])).as_matrix()[:, :2, 0]
        centre[b] = np.column_stack([r[f"{b}.position.x"], r[f"{b}.position.y"]])
        v = np.column_stack([r[f"{b}.velocity.x"], r[f"{b}.velocity.y"]])
        energy = energy + bar_energy(centre[b], v, r[f"{b}.angular_velocity.z"])
    # The cut joints: coupler i's end must sit on crank i + 1's top.
    phi = np.max([np.max(np.abs(centre[f"coupler{i}"] + 0.5 * axis[f"coupler{i}"]
                                - centre[f"crank{i + 1}"] - 0.5 * axis[f"crank{i + 1}"]), axis=1)
                  for i in range(N)], axis=0)
    angle = np.unwrap(np.arctan2(axis["crank0"][:, 1], axis["crank0"][:, 0]))
    error = (energy - energy[0]) / energy[0]

    args.out.mkdir(parents=True, exist_ok=True)
    csv = args.out / "n_four_bar.csv"
    np.savetxt(csv, np.column_stack([t, angle, phi, energy]), delimiter=",",
               header="time,crank0_angle,max_cut_joint_violation,energy", comments="")
    fig, axes = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True)
    axes[0].plot(t, angle)
    for k in range(int(np.floor(angle.min() / np.pi)), int(np.ceil(angle.max() / np.pi)) + 1):
        axes[0].axhline(k * np.pi, color="grey", lw=0.5)  # cranks horizontal: singular
    axes[0].set_ylabel("crank 0 angle [rad]\n(grey: singular)")
    axes[1].semilogy(t, np.maximum(phi, 1e-17))
    axes[1].set_ylabel("max |Phi| of the\ncut joints [m]")
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
    passes = np.count_nonzero(np.diff(np.sign(axis["crank0"][:, 1])))
    print(f"n_four_bar: N = {N}, t = {t[0]:g} .. {t[-1]:g} s, max |Phi| = {phi.max():.2e} m, "
          f"max |E - E0|/E0 = {np.abs(error).max():.2e}, singular passes = {passes}")
    print(f"n_four_bar: wrote {csv.resolve()} and {png.resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
