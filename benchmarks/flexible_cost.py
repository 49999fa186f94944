#!/usr/bin/env python3
"""Per-step cost of the flexible mesh against the element count.

Runs the C++ benchmark benchmarks/flexible_cost.cpp (a clamped cantilever of
N corotational beam elements, the F3 scene with its tip pulse, advanced by
mfbd::Simulation::doStep with implicit substeps h = 1e-3 and communication
steps of 0.01 s over 0.2 s), compiling it first by hand (g++) against
build/libmfbd_solver.a when the binary is missing or older than its sources.
The C++ benchmark is used rather than the FMU through fmpy so that the FMI
call overhead and the Python loop do not hide the solver's own cost at small N.

Writes results/flexible_cost.csv (elements, wall time per substep and per
element and substep, Newton iterations and factorizations per substep) and
results/flexible_cost.png (cost per substep against N, log-log, with a line
proportional to N through the measurements and the 0.5 us per element-step
target). With --phases also results/flexible_cost_phases.csv from
benchmarks/flexible_phases.cpp: one Newton iteration taken apart (residual,
tangent, assembly, factorization, solve, retraction), ns per element.
Newton stops at the increment tolerance of the precision-work studies
(peer_common.NEWTON_TOLERANCE, 1e-12, as Exudyn there; --tolerance); every
substep takes two corrections, as at the solver's default 1e-14.
A study, not a test: nothing here asserts a time.
"""
import argparse
import csv
import io
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
BENCHMARKS = ROOT / "benchmarks"
TARGET_US_PER_ELEMENT_STEP = 0.5  # the target
sys.path.insert(0, str(BENCHMARKS))
from peer_common import NEWTON_TOLERANCE  # noqa: E402


def compile_benchmark(build: pathlib.Path, name: str) -> pathlib.Path:
    """benchmarks/<name>.cpp -> <build>/<name>, linked with the solver library."""
    library = build / "libmfbd_solver.a"
    if not library.exists():
        sys.exit(f"{library} not found: build the project first (cmake --build {build})")
    source = BENCHMARKS / f"{name}.cpp"
    binary = build / name
    inputs = [source, BENCHMARKS / "cantilever_scene.hpp", library]
    if binary.exists() and binary.stat().st_mtime > max(p.stat().st_mtime for p in inputs):
        return binary
    # -flto: the library is built with link-time optimisation (CMakeLists.txt).
    command = ["g++", "-O3", "-flto=auto", "-DNDEBUG", "-std=c++17", "-I", str(ROOT / "solver"), "-isystem", "/usr/include/eigen3",
               str(source), str(library), str(build / "libmfbd_klu.a"), "-o", str(binary)]
    print(" ".join(command))
    subprocess.run(command, check=True)
    return binary


def run(binary, args, extra=()):
    command = [str(binary), "--elements", ",".join(map(str, args.elements)), "--duration", str(args.duration),
               "--h", str(args.h), "--communication", str(args.communication), *extra]
    out = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    return list(csv.DictReader(io.StringIO(out)))


def write_csv(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)
    print(f"wrote {path}")


def plot(rows, path, tolerance):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    n = np.array([float(r["elements"]) for r in rows])
    step = np.array([float(r["us_per_step"]) for r in rows])
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    ax.loglog(n, step, "o-", label="measured")
    # Linear reference: proportional to N, through the geometric mean of the points.
    c = np.exp(np.mean(np.log(step / n)))
    ax.loglog(n, c * n, "k--", lw=1, label=f"linear: {c:.2f} µs × N")
    ax.loglog(n, TARGET_US_PER_ELEMENT_STEP * n, ":", color="tab:green", label="target: 0.5 µs × N")
    for x, y, r in zip(n, step, rows):
        ax.annotate(f"{float(r['us_per_element_step']):.2f}", (x, y), textcoords="offset points", xytext=(4, -12),
                    fontsize=8)
    ax.set_xlabel("elements N")
    ax.set_ylabel("wall time per substep [µs]")
    ax.set_title(f"Flexible cantilever, modified Newton to {tolerance:g} (labels: µs per element-step)", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


def cost_arguments(doc, min_time, extra=()):
    """The command line of the cost studies (this one and coupled_cost.py):
    element counts, run length, substep, doStep, repeats, --phases, build and
    output folders; `extra` adds (flags, keyword arguments) pairs. The output
    folder is created."""
    p = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--elements", type=int, nargs="+", default=[10, 20, 50, 100, 200, 500, 1000, 2000])
    p.add_argument("--duration", type=float, default=0.2, help="simulated time per run [s]")
    p.add_argument("--h", type=float, default=1e-3, help="implicit substep (scene h_max) [s]")
    p.add_argument("--communication", type=float, default=0.01, help="doStep size [s]")
    p.add_argument("--min-time", type=float, default=min_time, help="repeat each N until this much wall time [s]")
    p.add_argument("--phases", action="store_true", help="also time the parts of one Newton iteration")
    p.add_argument("--tolerance", type=float, default=NEWTON_TOLERANCE, help="Newton increment tolerance")
    for flags, options in extra:
        p.add_argument(*flags, **options)
    p.add_argument("--build", type=pathlib.Path, default=ROOT / "build")
    p.add_argument("--out", type=pathlib.Path, default=ROOT / "benchmarks" / "results")
    p.add_argument("--replot", action="store_true", help="redraw the figure from the study's CSV in --out (no runs)")
    args = p.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    return args


def main():
    args = cost_arguments(__doc__, min_time=1.0)
    if args.replot:
        with open(args.out / "flexible_cost.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        return plot(rows, args.out / "flexible_cost.png", float(rows[0].get("newton_tolerance", args.tolerance)))

    rows = run(compile_benchmark(args.build, "flexible_cost"), args,
               ["--min-time", str(args.min_time), "--tolerance", str(args.tolerance)])
    header = ["elements", "us_per_step", "us_per_element_step", "newton_iterations_per_step",
              "factorizations_per_step", "unknowns", "substeps", "communication_step_s", "newton_tolerance",
              "repeats"]
    write_csv(args.out / "flexible_cost.csv", header,
              [[r["elements"], r["us_per_step"], r["us_per_element_step"], r["newton_per_step"],
                r["factorizations_per_step"], r["unknowns"], r["substeps"], args.communication, args.tolerance,
                r["repeats"]] for r in rows])
    for r in rows:
        print(f"N = {r['elements']:>5}: {float(r['us_per_step']):9.1f} us/step, "
              f"{float(r['us_per_element_step']):6.3f} us/element-step, Newton {r['newton_per_step']}/step, "
              f"factorizations {r['factorizations_per_step']}/step")
    plot(rows, args.out / "flexible_cost.png", args.tolerance)
    if args.phases:
        phases = run(compile_benchmark(args.build, "flexible_phases"), args)
        write_csv(args.out / "flexible_cost_phases.csv", list(phases[0].keys()), [list(r.values()) for r in phases])


if __name__ == "__main__":
    main()
