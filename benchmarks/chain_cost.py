#!/usr/bin/env python3
"""Per-step cost of a rigid n-body pendulum chain against n (n = 2..200),
for both forms of the Newton matrix.

Runs the C++ benchmark benchmarks/chain_cost.cpp (n uniform bars of 1/n kg
on revolute joints, released from horizontal under gravity, advanced by
mfbd::Simulation::doStep with substeps h = 1e-3 and communication steps of
0.01 s over 0.2 s), compiling it first (g++ against build/libmfbd_solver.a)
when the binary is missing or older than its sources (flexible_cost's
compile_benchmark). C++ rather than the
FMU through fmpy, so that the FMI calls and the Python loop do not hide the
solver's own cost at small n.

Two chains and two forms (solver.newton_matrix):
- bars of 1 m: the motion over 0.2 s is alike for every n, so the cost per
  substep shows the algorithm's cost in n;
- bars of 1/n m (a 1 m chain): finer links whip faster as n grows
  (link angular rates ~ 1/length), so substeps are rejected and Newton
  needs more iterations: the problem gets harder with n, not only larger;
- joint_space: B^T M B with finite-difference derivatives (dense for a
  chain: tangent O(n^2), LU O(n^3));
- recursive: body-level unknowns eliminated leaf to root (O(n)).

Writes results/chain_cost.csv (chain, form, n, wall time per substep,
Newton iterations, factorizations and rejected substeps per run, and one
Newton iteration taken apart at the final state: residual, tangent,
assembly, factorization, solve) and results/chain_cost.png. A study, not a
test: nothing here asserts a time.
"""
import argparse
import csv
import io
import pathlib
import subprocess

from flexible_cost import ROOT, compile_benchmark

FORMS = ("joint_space", "recursive")
CHAINS = {"1 m bars": 1.0, "1/n m bars": 0.0}  # --bar-length (0: 1/n)


def slope(n, y):
    """Least-squares exponent of y ~ n^p over the larger half of n."""
    import numpy as np
    keep = n >= np.median(n)
    return np.polyfit(np.log(n[keep]), np.log(y[keep]), 1)[0]


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4.8), sharey=True)
    styles = {"joint_space": ("C0", "joint space (B^T M B, FD tangent)"), "recursive": ("C3", "recursive (O(n) elimination)")}
    for ax, chain in zip(axes, CHAINS):
        for form in FORMS:
            sel = [r for r in rows if r["chain"] == chain and r["form"] == form]
            if not sel:
                continue
            n = np.array([float(r["bodies"]) for r in sel])
            step = np.array([float(r["us_per_step"]) for r in sel])
            per_iteration = step / np.array([float(r["newton_per_step"]) for r in sel])
            colour, label = styles[form]
            ax.loglog(n, step, "o-", color=colour, label=f"{label}, per substep: ~n^{slope(n, step):.2f}")
            ax.loglog(n, per_iteration, "s:", color=colour, ms=4,
                      label=f"per Newton iteration: ~n^{slope(n, per_iteration):.2f}")
        top = max(float(r["us_per_step"]) for r in rows if r["chain"] == chain)
        n = np.array(sorted({float(r["bodies"]) for r in rows}))
        ax.loglog(n, top / n[-1] * n, "k--", lw=0.8, label="~n")
        ax.set_title(f"pendulum chain of {chain}, released from horizontal, h = 1e-3", fontsize=9)
        ax.set_xlabel("bodies n")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16))  # below: no data hidden
    axes[0].set_ylabel("wall time [µs]")
    fig.tight_layout()
    fig.savefig(path, dpi=120, bbox_inches="tight")
    print(f"wrote {path}")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bodies", type=int, nargs="+", default=[2, 5, 10, 20, 50, 100, 200])
    p.add_argument("--duration", type=float, default=0.2, help="simulated time per run [s]")
    p.add_argument("--h", type=float, default=1e-3, help="implicit substep (scene h_max) [s]")
    p.add_argument("--min-time", type=float, default=0.5, help="repeat each n until this much wall time [s]")
    p.add_argument("--build", type=pathlib.Path, default=ROOT / "build")
    p.add_argument("--out", type=pathlib.Path, default=ROOT / "benchmarks" / "results")
    p.add_argument("--replot", action="store_true", help="redraw the figure from chain_cost.csv in --out (no runs)")
    args = p.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    if args.replot:
        with open(args.out / "chain_cost.csv", newline="") as f:
            return plot(list(csv.DictReader(f)), args.out / "chain_cost.png")
    binary = compile_benchmark(args.build, "chain_cost")
    rows = []
    for chain, bar_length in CHAINS.items():
        for form in FORMS:
            command = [str(binary), "--bodies", ",".join(map(str, args.bodies)), "--duration", str(args.duration),
                       "--h", str(args.h), "--min-time", str(args.min_time), "--newton-matrix", form,
                       "--bar-length", str(bar_length)]
            text = subprocess.run(command, check=True, capture_output=True, text=True).stdout
            for r in csv.DictReader(io.StringIO(text)):
                rows.append({"chain": chain, "form": form, **r})
                print(f"{chain:>10}, {form:>11}, n = {r['bodies']:>4}: {float(r['us_per_step']):9.1f} us/substep, "
                      f"Newton {r['newton_per_step']}, factorizations {r['factorizations_per_step']} per substep, "
                      f"{r['rejected_substeps']} rejected")
    path = args.out / "chain_cost.csv"
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {path}")
    plot(rows, args.out / "chain_cost.png")


if __name__ == "__main__":
    main()
