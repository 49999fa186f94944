#!/usr/bin/env python3
"""Per-step cost against the element count with rigid bodies attached (issue 5).

Runs the C++ benchmark benchmarks/flexible_cost.cpp (built as in
flexible_cost.py) on four scenes of benchmarks/cantilever_scene.hpp, the
same beam (L = 1, EI = 1, EA = 1e6, rho A = 1, N corotational elements) held
four ways:
  * cantilever: clamped at node 0, tip force pulse (flexible_cost.py's
    scene: no rigid body, small motion);
  * driven: node 0's rotation prescribed (a "driven" support, as F4), a
    smooth spin-up to 2 rad/s over 0.2 s: no rigid body, the motion of the
    next two, so their baseline;
  * hub: node 0 welded by a fixed joint to a rigid hub (1 kg) on a revolute
    joint to ground whose angle is driven the same way: one virtual body,
    one flexible body joint, one drive row;
  * coupled: the hub, and a rigid tip body (1 kg) on a fixed joint at the
    beam's end: two virtual bodies and flexible body joints.
Each advanced by mfbd::Simulation::doStep with implicit substeps h = 1e-3
and communication steps of 0.01 s over 0.2 s, Newton to the tolerance of
flexible_cost.py (1e-12). Timed twice: the wall time of
the fastest of repeated runs (as flexible_cost.py), and the least process
CPU time of the same runs, which is what the plot and the fitted exponents
use: on a machine shared with other jobs (2 cores, load 4) the wall time of
a run scatters by a factor up to 2 while its CPU time does not count the
time the process waited. With --phases also one Newton iteration taken
apart (benchmarks/flexible_phases.cpp, CPU time) for each scene at a few N.
Then the cost of a communication step: driven and hub at N = 100 with
doStep sizes 1e-3 (= h), 1e-2 and 0.2 s (coupled_cost_communication.csv).

Writes results/coupled_cost.csv (scene, elements, CPU and wall time per
substep and per element and substep, Newton iterations and factorizations
per substep, unknowns), results/coupled_cost_phases.csv (with --phases) and
results/coupled_cost_communication.csv and results/coupled_cost.png (CPU
time per substep against N, log-log, with a line proportional to N through
each scene's points). A study, not a test:
nothing here asserts a time.
"""
import argparse
import csv

import numpy as np

from flexible_cost import compile_benchmark, cost_arguments, run, write_csv

SCENES = ["cantilever", "driven", "hub", "coupled"]
LABELS = {"cantilever": "clamped cantilever, tip pulse (no rigid body)",
          "driven": "spun up by a driven node (no rigid body)", "hub": "spun up by a driven hub + fixed joint",
          "coupled": "driven hub + tip body on a fixed joint"}
COMMUNICATION = [1e-3, 1e-2, 0.2]  # doStep sizes of the communication study (h = 1e-3)


def slope(n, us):
    """Least-squares exponent p of us ~ N^p over the points."""
    return float(np.polyfit(np.log(n), np.log(us), 1)[0])


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    for i, scene in enumerate(SCENES):
        sel = [r for r in rows if r["scene"] == scene]
        n = np.array([float(r["elements"]) for r in sel])
        step = np.array([float(r["cpu_us_per_step"]) for r in sel])
        c = np.exp(np.mean(np.log(step / n)))
        ax.loglog(n, step, "osv^"[i] + "-", color=f"C{i}",
                  label=f"{LABELS[scene]}: slope {slope(n, step):.2f}")
        ax.loglog(n, c * n, "--", color=f"C{i}", lw=0.8)
        for x, y, r in zip(n, step, sel if i in (0, len(SCENES) - 1) else []):  # the middle ones overlap
            ax.annotate(f"{float(r['cpu_us_per_element_step']):.1f}", (x, y), textcoords="offset points",
                        xytext=(4, -11 + 8 * i), fontsize=7, color=f"C{i}")
    ax.set_xlabel("elements N")
    ax.set_ylabel("CPU time per substep [µs]")
    ax.set_title("Beam with rigid bodies attached: CPU time per substep (dashed: proportional to N;\n"
                 "labels: µs per element-step, first and last series)", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16))  # below: no data hidden
    fig.tight_layout()
    fig.savefig(path, dpi=120, bbox_inches="tight")
    print(f"wrote {path}")


def main():
    args = cost_arguments(__doc__, min_time=0.3,
                          extra=[(("--phases-elements",), dict(type=int, nargs="+", default=[100, 1000]))])
    if args.replot:
        with open(args.out / "coupled_cost.csv", newline="") as f:
            return plot(list(csv.DictReader(f)), args.out / "coupled_cost.png")

    binary = compile_benchmark(args.build, "flexible_cost")
    rows = []
    for scene in SCENES:
        for r in run(binary, args, ["--min-time", str(args.min_time), "--scene", scene,
                                      "--tolerance", str(args.tolerance)]):
            rows.append(dict(scene=scene, **r))
            print(f"{scene:10s} N = {r['elements']:>5}: CPU {float(r['cpu_us_per_step']):9.1f} us/step, "
                  f"{float(r['cpu_us_per_element_step']):6.3f} us/element-step (wall "
                  f"{float(r['us_per_element_step']):6.3f}), Newton {r['newton_per_step']}/step, "
                  f"factorizations {r['factorizations_per_step']}/step", flush=True)
    header = ["scene", "elements", "cpu_us_per_step", "cpu_us_per_element_step", "us_per_step",
              "us_per_element_step", "newton_iterations_per_step", "factorizations_per_step", "unknowns", "substeps",
              "communication_step_s", "newton_tolerance", "repeats"]
    write_csv(args.out / "coupled_cost.csv", header,
              [[r["scene"], r["elements"], r["cpu_us_per_step"], r["cpu_us_per_element_step"], r["us_per_step"],
                r["us_per_element_step"], r["newton_per_step"], r["factorizations_per_step"], r["unknowns"],
                r["substeps"], args.communication, args.tolerance, r["repeats"]] for r in rows])
    for scene in SCENES:
        sel = [r for r in rows if r["scene"] == scene]
        n = np.array([float(r["elements"]) for r in sel])
        us = np.array([float(r["cpu_us_per_step"]) for r in sel])
        big = n >= 100
        if big.sum() >= 2:
            print(f"{scene:10s} CPU time per step ~ N^{slope(n, us):.2f} over all N, "
                  f"N^{slope(n[big], us[big]):.2f} for N >= 100")
    plot(rows, args.out / "coupled_cost.png")
    # The cost of a communication step: constrained scenes solve consistent
    # accelerations and multipliers for their outputs at every doStep.
    table = []
    for scene in ("driven", "hub"):
        for communication in COMMUNICATION:
            single = argparse.Namespace(**{**vars(args), "elements": [100], "communication": communication})
            r = run(binary, single, ["--min-time", str(args.min_time), "--scene", scene,
                                     "--tolerance", str(args.tolerance)])[0]
            table.append([scene, r["elements"], communication, r["cpu_us_per_step"], r["cpu_us_per_element_step"],
                          r["newton_per_step"], r["factorizations_per_step"]])
            print(f"{scene:7s} N = 100, doStep {communication:5.3f} s: CPU {float(r['cpu_us_per_step']):8.1f} us/substep, "
                  f"Newton {r['newton_per_step']}/substep, factorizations {r['factorizations_per_step']}/substep")
    write_csv(args.out / "coupled_cost_communication.csv",
              ["scene", "elements", "communication_step_s", "cpu_us_per_step", "cpu_us_per_element_step",
               "newton_iterations_per_step", "factorizations_per_step"], table)
    if args.phases:
        phases_binary = compile_benchmark(args.build, "flexible_phases")
        table = []
        phase_args = argparse.Namespace(**{**vars(args), "elements": args.phases_elements})
        for scene in SCENES:
            table += [dict(scene=scene, **r) for r in run(phases_binary, phase_args, ["--scene", scene, "--cpu", "1"])]
        write_csv(args.out / "coupled_cost_phases.csv", list(table[0].keys()), [list(r.values()) for r in table])


if __name__ == "__main__":
    main()
