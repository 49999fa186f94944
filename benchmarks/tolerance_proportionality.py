#!/usr/bin/env python3
"""Tolerance proportionality (issue 18 item 4): the error our FMU reaches
against the relative tolerance given to fmi2SetupExperiment, over 1e-3 ..
1e-8, with the integrator the FMU chooses for the scene (README, Error
control). The error is measured in the units the tolerance is stated in:
a length over the scene's length scale L (rad over L / 1 m), an energy over
m g L; stopTime is passed, so the tolerance holds over the run.

  R1 pendulum: bob position at 10 s against its ODE (scipy DOP853, rtol 1e-13);
     L = 1 m; Dormand-Prince 5(4) (rigid, not stiff).
  R2 double pendulum: energy drift max |E(t) - E(0)| / (m g L) over 10 s,
     sampled every 0.1 s (h_max too); Dormand-Prince 5(4).
  R4 Bricard (redundant constraint): energy drift / (m g L) over 10 s, every 0.1 s;
     Dormand-Prince 5(4).
  R5 slider-crank: slider position against x(theta) of shared/benchmarks;
     a fully driven mechanism, so generalized-alpha or not, its error is
     round-off at every tolerance: shown, not a proportionality case.
  F3 cantilever (16 elements): tip deflection over 2 s (every 0.05 s)
     against the same mesh at h = 2.5e-5 and 1.25e-5 extrapolated
     (Richardson, order 2); L = 1 m; generalized-alpha. The tip pulse is
     0.25 s long with a peak of 0.1 EI/L^2 (tip swing 1.5e-2 L):
     the example's 0.02 s pulse of 0.01 EI/L^2 swings the tip by about
     1.3e-4 L, so at a tolerance of 1e-3 any answer, the beam at rest
     included, is within 0.13 times it, and a 0.02 s pulse needs substeps
     below the 0.05 s sampling to be seen at all (README, Error control).
  F4 spin-up beam (8 elements): tip position over 4 s (every 0.2 s)
     against the same mesh at h = 1e-4 and 5e-5 extrapolated; L = 10 m;
     generalized-alpha.
     F3 and F4 are sampled coarsely so that the tolerance, not the
     sampling, sizes the substeps: generalized-alpha lands on every
     communication point (h_max is the sampling interval in this study).
  F5 flexible slider-crank (8 elements): the rod's mid and end node
     positions over 0.4 s (every 1 ms) against the same mesh at h = 2.5e-6
     and 1.25e-6 extrapolated; L = 0.45 m; generalized-alpha; 1e-3 .. 1e-6
     only (its small high modes are resolved per unit step: 1e-7 takes
     millions of substeps).

The references of F3 and F4 are the time integration's (same mesh): the
tolerance is about the integrator's error, not the mesh's.

    python benchmarks/tolerance_proportionality.py --out benchmarks/results [--problems R1 F3]

Writes tolerance_proportionality.csv and .png (error / tolerance against
tolerance, the band [0.1, 10] shaded)."""
import argparse
import pathlib
import re
import shutil
import sys
import tempfile

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from peer_common import FmuRun, figure, load_scene, packed, save_figure, write_csv  # noqa: E402
import peer_r2_double_pendulum as r2  # noqa: E402
import peer_r4_bricard as r4  # noqa: E402
import peer_r5_slider_crank as r5  # noqa: E402

TOLERANCES = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
G = 9.81


def run(fmu, names, stop, output, tolerance=None, parameters=None):
    """Samples of `names` every `output` from 0 to `stop` (rows), wall time,
    statistics and the integrator's log line."""
    fmu_run = FmuRun(fmu, {"solver.h_max": output, **(parameters or {})}, tolerance=tolerance,
                     stop_time=stop if tolerance else None)
    fmu_run.slave.call("setDebugLogging", True, ["logEvents", "logStatistics"])
    samples, wall, statistics = fmu_run.sample(names, stop, output)
    line = next((m for _, c, m in fmu_run.slave.log if m.startswith("integrator: ")), "")
    return samples, wall, statistics, re.sub(r"^integrator: ([^:]*):.*", r"\1", line)


class Problem:
    """A scene, its outputs, and the error of a run against the reference."""
    example, stop, output, scale, tolerances = "", 10.0, 0.1, 1.0, TOLERANCES

    def __init__(self, folder):
        self.fmu = packed(self.scene(), folder, self.label)

    def scene(self):
        return load_scene(self.example)

    def error(self, samples):
        raise NotImplementedError

    parameters = {}  # start values of the scene's parameters

    def measure(self, tolerance):
        s, wall, statistics, integrator = run(self.fmu, self.names, self.stop, self.output, tolerance,
                                              self.parameters)
        return dict(error=self.error(s), wall_time_s=wall, integrator=integrator, **statistics)


class R1(Problem):
    label, example, stop, output = "R1", "pendulum", 10.0, 0.1
    names = ["bob.position.x", "bob.position.y"]

    def error(self, s):
        theta = solve_ivp(lambda t, y: [y[1], -G * np.cos(y[0])], (0, self.stop), [0.0, 0.0], method="DOP853",
                          rtol=1e-13, atol=1e-13).y[0, -1]
        return float(np.hypot(s[-1, 0] - np.cos(theta), s[-1, 1] - np.sin(theta)))


class R2(Problem):
    label, example, stop, output = "R2", "double_pendulum", 10.0, 0.1
    names = [f"bar{i}.{q}.{c}" for i in (1, 2) for q in ("position", "velocity") for c in "xy"]
    names += ["bar1.angular_velocity.z", "bar2.angular_velocity.z"]

    def error(self, s):
        p = s[:, [0, 1, 4, 5]].reshape(-1, 2, 2)
        v = s[:, [2, 3, 6, 7]].reshape(-1, 2, 2)
        e = r2.energy(p, v, s[:, 8:10])
        return float(np.max(np.abs(e - e[0]))) / r2.MGL


class R4(Problem):
    label, example, stop, output = "R4", "bricard", 10.0, 0.1
    rods = [f"rod{i}" for i in range(1, 6)]
    names = [f"{b}.{q}.{c}" for b in rods for q in ("position", "velocity", "angular_velocity") for c in "xyz"]
    names += [f"{b}.orientation.{c}" for b in rods for c in "xyzw"]

    def error(self, s):
        from scipy.spatial.transform import Rotation
        k = s[:, :45].reshape(len(s), 5, 3, 3)
        R = Rotation.from_quat(s[:, 45:].reshape(-1, 4)).as_matrix().reshape(len(s), 5, 3, 3)
        e = r4.energy(k[:, :, 0], k[:, :, 1], R, k[:, :, 2])
        return float(np.max(np.abs(e - e[0]))) / r4.MGL


class R5(Problem):
    label, example, stop, output = "R5", "slider_crank", 2.0, 0.01
    names = ["slider.position.x"]

    def error(self, s):
        t = self.output * np.arange(len(s))
        return float(np.max(np.abs(s[:, 0] - r5.exact(t)[0])))


class Extrapolated(Problem):
    """Reference: the same scene without a tolerance at substeps h and h/2,
    extrapolated to h = 0 with order 2; error: the largest difference over
    the samples of `names`, over L."""
    reference_step = 1e-4

    def reference(self):
        if not hasattr(self, "_reference"):
            h = self.reference_step
            coarse = run(self.fmu, self.names, self.stop, self.output, None, {**self.parameters, "solver.h_max": h})[0]
            fine = run(self.fmu, self.names, self.stop, self.output, None,
                       {**self.parameters, "solver.h_max": h / 2})[0]
            self._reference = fine + (fine - coarse) / 3.0
            self.reference_error = float(np.max(np.abs(fine - coarse))) / 3.0 / self.scale
        return self._reference

    def error(self, s):
        return float(np.max(np.abs(s - self.reference()))) / self.scale


class F3(Extrapolated):
    label, example, stop, output, scale, reference_step = "F3", "cantilever_vibration", 2.0, 0.05, 1.0, 2.5e-5
    names = ["beam.node16.position.x", "beam.node16.position.y"]
    parameters = {"pulse": 0.25, "peak": 0.1}


class F4(Extrapolated):
    label, example, stop, output, scale, reference_step = "F4", "spin_up_beam", 4.0, 0.2, 10.0, 1e-4
    names = ["beam.node8.position.x", "beam.node8.position.y"]


class F5(Extrapolated):
    label, example, stop, output, scale, reference_step = "F5", "flexible_slider_crank", 0.4, 1e-3, 0.45, 2.5e-6
    tolerances = TOLERANCES[:4]  # 1e-7: about 3 million substeps (see benchmarks/README.md)
    names = [f"rod.node{i}.position.{c}" for i in (4, 8) for c in "xy"]


PROBLEMS = {p.label: p for p in (R1, R2, R4, R5, F3, F4, F5)}


def plot(rows, path):
    fig, ax = figure()
    ax.axhspan(0.1, 10, color="0.9", label="[0.1, 10] x tolerance")
    for label in dict.fromkeys(r["problem"] for r in rows):
        mine = [r for r in rows if r["problem"] == label and r["error"] > 0]
        if not mine:
            continue
        ax.loglog([r["tolerance"] for r in mine], [r["error"] / r["tolerance"] for r in mine], "o-",
                  label=f"{label} ({mine[0]['integrator']})")
    ax.set_xlabel("relative tolerance (fmi2SetupExperiment)")
    ax.set_ylabel("error reached / tolerance")
    ax.set_title("Tolerance proportionality (errors in units of the scene's L, energies of m g L)")
    ax.invert_xaxis()
    ax.legend(fontsize=8)
    save_figure(fig, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="benchmarks/results")
    parser.add_argument("--problems", nargs="*", default=list(PROBLEMS))
    parser.add_argument("--tolerances", nargs="*", type=float, help="default: 1e-3 .. 1e-8 (F5 1e-3 .. 1e-6)")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    folder = pathlib.Path(tempfile.mkdtemp(prefix="mfbd-proportionality-"))  # the packed scenes
    rows = []
    for label in args.problems:
        problem = PROBLEMS[label](folder)
        for tolerance in args.tolerances or problem.tolerances:
            r = problem.measure(tolerance)
            row = dict(problem=label, tolerance=tolerance, error=r["error"], ratio=r["error"] / tolerance,
                       wall_time_s=r["wall_time_s"], substeps=r.get("steps", ""),
                       rejected=r.get("rejected_steps", ""), integrator=r["integrator"],
                       reference_error=getattr(problem, "reference_error", ""))
            rows.append(row)
            print(f"{label} tol {tolerance:.0e}: error {row['error']:.3g} ({row['ratio']:.3g} x tol), "
                  f"{row['wall_time_s'] * 1e3:.1f} ms, {row['substeps']} substeps ({row['rejected']} rejected), "
                  f"{row['integrator']}", flush=True)
    shutil.rmtree(folder, ignore_errors=True)
    write_csv(out / "tolerance_proportionality.csv", rows)
    plot(rows, out / "tolerance_proportionality.png")


if __name__ == "__main__":
    main()
