#!/usr/bin/env python3
"""Per-step cost of a rigid n-body pendulum chain against n (n = 2..200).

Runs the C++ benchmark benchmarks/chain_cost.cpp (n uniform bars of 1/n m and
1/n kg on revolute joints, released from horizontal, advanced by
mfbd::Simulation::doStep with substeps h = 1e-3 and communication steps of
0.01 s over 0.2 s), compiling it first (g++ against build/libmfbd_solver.a)
when the binary is missing or older than its sources. C++ rather than the
FMU through fmpy, so that the FMI calls and the Python loop do not hide the
solver's own cost at small n.

Writes results/chain_cost.csv (n, wall time per substep, Newton iterations
and factorizations per substep, and one Newton iteration taken apart at the
final state: residual, tangent, assembly with factorization, solve) and
results/chain_cost.png (log-log against n, with lines proportional to n and
to n^2). A study, not a test: nothing here asserts a time.
"""
import argparse
import csv
import io
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
BENCHMARKS = ROOT / "benchmarks"


def compile_benchmark(build: pathlib.Path) -> pathlib.Path:
    library = build / "libmfbd_solver.a"
    if not library.exists():
        sys.exit(f"{library} not found: build the project first (cmake --build {build})")
    source, binary = BENCHMARKS / "chain_cost.cpp", build / "chain_cost"
    if binary.exists() and binary.stat().st_mtime > max(source.stat().st_mtime, library.stat().st_mtime):
        return binary
    command = ["g++", "-O2", "-DNDEBUG", "-std=c++17", "-I", str(ROOT / "solver"), "-isystem", "/usr/include/eigen3",
               "-I", "/usr/include/suitesparse", str(source), str(library), "-lklu", "-o", str(binary)]
    print(" ".join(command))
    subprocess.run(command, check=True)
    return binary


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

    n = np.array([float(r["bodies"]) for r in rows])
    fig, ax = plt.subplots(figsize=(6.8, 5.0))
    series = [("us_per_step", "per substep (all)", "o-"), ("tangent_us", "one tangent (FD over n rates)", "s--"),
              ("assembly_factorization_us", "tangent + assembly + LU", "^--"),
              ("residual_us", "one residual", "v-"), ("solve_us", "one solve", "d-")]
    for key, label, style in series:
        y = np.array([float(r[key]) for r in rows])
        ax.loglog(n, y, style, label=f"{label}: ~n^{slope(n, y):.1f}")
    step = np.array([float(r["us_per_step"]) for r in rows])
    for power, style in ((1, "k:"), (2, "k-.")):
        c = step[-1] / n[-1] ** power
        ax.loglog(n, c * n ** power, style, lw=0.8, label=f"~n^{power}")
    ax.set_xlabel("bodies n")
    ax.set_ylabel("wall time [us]")
    ax.set_title("Pendulum chain, joint coordinates, modified Newton", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bodies", type=int, nargs="+", default=[2, 5, 10, 20, 50, 100, 200])
    p.add_argument("--duration", type=float, default=0.2, help="simulated time per run [s]")
    p.add_argument("--h", type=float, default=1e-3, help="implicit substep (scene h_max) [s]")
    p.add_argument("--min-time", type=float, default=0.5, help="repeat each n until this much wall time [s]")
    p.add_argument("--build", type=pathlib.Path, default=ROOT / "build")
    p.add_argument("--out", type=pathlib.Path, default=ROOT / "benchmarks" / "results")
    args = p.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    command = [str(compile_benchmark(args.build)), "--bodies", ",".join(map(str, args.bodies)),
               "--duration", str(args.duration), "--h", str(args.h), "--min-time", str(args.min_time)]
    text = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    rows = list(csv.DictReader(io.StringIO(text)))
    path = args.out / "chain_cost.csv"
    path.write_text(text)
    print(f"wrote {path}")
    for r in rows:
        print(f"n = {r['bodies']:>4}: {float(r['us_per_step']):10.1f} us/substep, Newton {r['newton_per_step']}, "
              f"factorizations {r['factorizations_per_step']} per substep; tangent {float(r['tangent_us']):.0f} us, "
              f"residual {float(r['residual_us']):.1f} us")
    plot(rows, args.out / "chain_cost.png")


if __name__ == "__main__":
    main()
