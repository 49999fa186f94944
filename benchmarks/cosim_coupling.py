#!/usr/bin/env python3
"""Co-simulation study: the coupling error of a closed loop against the
communication step H, for four masters, and the cost of FMU state save and
restore per step. Not a test: nothing asserts a time.

Masters (every one exchanges values only at communication points t_k = k H):
  zoh_jacobi        every FMU steps with the others' outputs of t_k held over
                    the step; the controller's command at t_k is the one it
                    computed from the measurement of t_(k-1) (libcosim,
                    fmpy's SSP simulator)
  zoh_gauss_seidel  the plant's outputs of t_k go to the controller first, whose
                    command (direct feedthrough) goes to the plant, held
                    (examples/ssp_master.py)
  interpolation     Gauss-Seidel values plus their slopes extrapolated from
                    t_(k-1) and t_k, given to both FMUs by
                    fmi2SetRealInputDerivatives (inputs ramped over the step)
  rollback          every step is iterated: the states of t_k are saved
                    (fmi2GetFMUstate), the inputs ramped from their values at
                    t_k to a guess of those at t_(k+1) (a plant that cannot
                    ramp its inputs gets their mean over the step, held), the
                    step taken, the guess replaced by the outputs at t_(k+1),
                    the states restored (fmi2SetFMUstate), until the guess
                    settles (relative change 1e-10)

Systems:
  linear     two PID controller FMUs: one a P controller (Kp = 20, setpoint
             1), the other an integrator plant (Ki = 1): x' = 20 (1 - x),
             x(0) = 0, so x = 1 - exp(-20 t) exactly; both FMUs have FMU
             state and input derivatives, so every master runs
  robot_arm  build/ssp/robot_arm_pid.ssp (six joints, a setpoint step that
             saturates the torques), over 1 s with the plant's substep fixed
             at 5e-5 s for every H (the same discretisation of the plant:
             the differences are the coupling's). Reference: the rollback
             master at H = 5e-5 (second order, the trapezoidal rule of the
             coupling) where the plant can run it, else Richardson's
             extrapolation 2 G(h) - G(2h) of Gauss-Seidel runs at h = 5e-5
             (G(h) is 8.1e-4 rad from it, as first order makes it: errors of
             second-order masters near that level are the reference's).
             interpolation needs the plant to declare canInterpolateInputs,
             rollback canGetAndSetFMUstate; where it does not, their rows
             say so and carry no numbers.

    python benchmarks/cosim_coupling.py --out benchmarks/results [--quick] [--systems linear robot_arm] [--replot]
-> cosim_coupling.csv (system, master, H, error, order, iterations per step,
   wall time, state save and restore per step, doStep per step) and
   cosim_coupling.png.
"""
import argparse
import csv
import ctypes
import functools
import math
import pathlib
import shutil
import sys
import tempfile
import time

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.ssp.ssd import read_ssd, read_ssv

ROOT = pathlib.Path(__file__).resolve().parents[1]
BUILD = ROOT / "build"
MASTERS = ["zoh_jacobi", "zoh_gauss_seidel", "interpolation", "rollback"]
PLANT_SUBSTEP = 5e-5


class Fmu:
    """One FMU instance, initialized at t = 0, addressed by variable names."""

    def __init__(self, path, name, start_values, workdir):
        md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        cs = md.coSimulation
        self.can_interpolate, self.can_save = cs.canInterpolateInputs, cs.canGetAndSetFMUstate
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path), str(workdir / name)),
                             modelIdentifier=cs.modelIdentifier, instanceName=name)
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        for variable, value in start_values.items():
            self.fmu.setReal([self.vr[variable]], [float(value)])
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.state = None
        self.save_time = self.restore_time = self.step_time = 0.0

    def get(self, names):
        return np.array(self.fmu.getReal([self.vr[n] for n in names]))

    def set(self, names, values, slopes=None):
        self.fmu.setReal([self.vr[n] for n in names], list(values))
        if slopes is not None:
            self.fmu.setRealInputDerivatives([self.vr[n] for n in names], [1] * len(names), list(slopes))

    def step(self, t, h):
        start = time.perf_counter()
        self.fmu.doStep(t, h)
        self.step_time += time.perf_counter() - start

    def save(self):
        """Into the same FMUstate each time: the FMU overwrites a state it made."""
        start = time.perf_counter()
        if self.state is None:
            self.state = self.fmu.getFMUstate()
        else:
            self.fmu.fmi2GetFMUstate(self.fmu.component, ctypes.byref(self.state))
        self.save_time += time.perf_counter() - start

    def restore(self):
        start = time.perf_counter()
        self.fmu.setFMUstate(self.state)
        self.restore_time += time.perf_counter() - start

    def free(self):
        if self.state is not None:
            self.fmu.freeFMUstate(self.state)
        self.fmu.terminate()
        self.fmu.freeInstance()


class System:
    """A plant and a controller: plant outputs -> controller inputs, and back."""

    def __init__(self, plant, controller, to_controller, to_plant, observed):
        self.plant, self.controller = plant, controller
        self.to_controller, self.to_plant = to_controller, to_plant  # [(source name, target name)]
        self.observed = observed  # plant outputs whose error is measured

    def measurements(self):
        return self.plant.get([s for s, _ in self.to_controller])

    def commands(self):
        return self.controller.get([s for s, _ in self.to_plant])

    def exchange(self, slopes=None):
        """Gauss-Seidel at a communication point: plant -> controller -> plant.
        slopes: (measurement slopes, command slopes) or None (held)."""
        y = self.measurements()
        self.controller.set([t for _, t in self.to_controller], y, None if slopes is None else slopes[0])
        u = self.commands()
        self.plant.set([t for _, t in self.to_plant], u, None if slopes is None else slopes[1])
        return y, u

    def free(self):
        self.plant.free()
        self.controller.free()


def linear_system(workdir):
    fmu = BUILD / "controllers" / "pid_controller_2.fmu"
    plant = Fmu(fmu, "plant", {"Kp[1]": 0.0, "Ki[1]": 1.0}, workdir)
    controller = Fmu(fmu, "controller", {"Kp[1]": 20.0, "setpoint[1]": 1.0}, workdir)
    return System(plant, controller, [("command[1]", "measurement[1]")], [("command[1]", "setpoint[1]")],
                  ["command[1]"])


def linear_exact(t):
    return (1.0 - np.exp(-20.0 * t))[:, None]


def ssp_system(workdir, plant_substep, ssp=BUILD / "ssp" / "robot_arm_pid.ssp"):
    ssd, unzip = read_ssd(str(ssp)), pathlib.Path(extract(str(ssp), str(workdir / "ssp")))
    parts = {c.name: c for c in ssd.system.elements}
    values = read_ssv(str(ssp), parts["controller"].parameterBindings[0].source).parameters
    plant = Fmu(unzip / parts["plant"].source, "plant", {"solver.h_max": plant_substep}, workdir)
    controller = Fmu(unzip / parts["controller"].source, "controller",
                     {p.name: float(p.value) for p in values}, workdir)
    links = [(c.startElement, c.startConnector, c.endConnector) for c in ssd.system.connections]
    return System(plant, controller, [(s, t) for e, s, t in links if e == "plant"],
                  [(s, t) for e, s, t in links if e == "controller"],
                  [s for e, s, _ in links if e == "plant"])


def run(make_system, master, H, stop, workdir):
    """(times, observed outputs [steps + 1, n], iterations per step, per-step
    costs in s: save + restore, doStep of both FMUs, wall)."""
    system = make_system(workdir)
    n = int(round(stop / H))
    rows, iterations = [], 0
    previous = None  # (y, u) at t_(k-1)
    start = time.perf_counter()
    try:
        for k in range(n + 1):
            t = k * H
            if master == "zoh_jacobi" and k > 0:  # outputs of t_k, commands computed from y(t_(k-1))
                y, u = system.measurements(), system.commands()
                system.controller.set([t_ for _, t_ in system.to_controller], y)
                system.plant.set([t_ for _, t_ in system.to_plant], u)
            elif master == "interpolation" and previous is not None:
                y, u = system.measurements(), None
                slope_y = (y - previous[0]) / H
                system.controller.set([t_ for _, t_ in system.to_controller], y, slope_y)
                u = system.commands()
                system.plant.set([t_ for _, t_ in system.to_plant], u, (u - previous[1]) / H)
            else:
                y, u = system.exchange()
            previous = (y, u)
            rows.append(system.plant.get(system.observed))
            if k == n:
                break
            if master == "rollback":
                iterations += rollback_step(system, t, H, y, u)
            else:
                system.plant.step(t, H)
                system.controller.step(t, H)
                iterations += 1
        wall = time.perf_counter() - start
        fmus = [system.plant, system.controller]
        save_restore = sum(f.save_time + f.restore_time for f in fmus) / n
        stepping = sum(f.step_time for f in fmus) / n
        return np.arange(n + 1) * H, np.array(rows), iterations / n, save_restore, stepping, wall / n
    finally:
        system.free()


def rollback_step(system, t, H, y0, u0, tolerance=1e-10, max_iterations=50):
    """One step iterated with state restore until the end values settle;
    leaves both FMUs at t + H. Returns the number of step attempts."""
    for f in (system.plant, system.controller):
        f.save()
    y1, u1 = y0, u0  # first guess: held
    for iteration in range(1, max_iterations + 1):
        system.controller.set([t_ for _, t_ in system.to_controller], y0, (y1 - y0) / H)
        if system.plant.can_interpolate:
            system.plant.set([t_ for _, t_ in system.to_plant], u0, (u1 - u0) / H)
        else:  # held at the step's mean: the same integral of the input over the step
            system.plant.set([t_ for _, t_ in system.to_plant], (u0 + u1) / 2)
        system.plant.step(t, H)
        system.controller.step(t, H)
        y_new = system.measurements()
        system.controller.set([t_ for _, t_ in system.to_controller], y_new)
        u_new = system.commands()
        change = max(np.max(np.abs(y_new - y1) / (1 + np.abs(y1))), np.max(np.abs(u_new - u1) / (1 + np.abs(u1))))
        if change <= tolerance:
            return iteration
        y1, u1 = y_new, u_new
        for f in (system.plant, system.controller):
            f.restore()
    raise RuntimeError(f"rollback: the inputs did not settle in {max_iterations} iterations at t = {t}")


# --- the study ---------------------------------------------------------------------


SYSTEMS = {
    # name: (system factory, stop time, communication steps, reference(times) or None)
    "linear": (linear_system, 0.5, [2e-3, 5e-3, 1e-2, 2e-2, 5e-2], linear_exact),
    "robot_arm": (functools.partial(ssp_system, plant_substep=PLANT_SUBSTEP), 1.0,
                  [1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3], None),
}


def richardson_reference(make_system, stop, workdir):
    """2 G(h) - G(2h) of Gauss-Seidel runs at h = PLANT_SUBSTEP, on the grid of 2h;
    and |G(h) - G(2h)|, about the error of G(h)."""
    t2, coarse = run(make_system, "zoh_gauss_seidel", 2 * PLANT_SUBSTEP, stop, workdir)[:2]
    _, fine = run(make_system, "zoh_gauss_seidel", PLANT_SUBSTEP, stop, workdir)[:2]
    fine = fine[::2]
    return t2, 2 * fine - coarse, np.max(np.abs(fine - coarse))


def missing_capability(system_factory, master, workdir):
    """Why a master cannot run on a system ('' if it can)."""
    if master in ("zoh_jacobi", "zoh_gauss_seidel"):
        return ""
    system = system_factory(workdir)
    try:
        for role, f in (("plant", system.plant), ("controller", system.controller)):
            if master == "rollback" and not f.can_save:
                return f"the {role} declares canGetAndSetFMUstate=false"
            if not f.can_interpolate and (master == "interpolation" or role == "controller"):
                return f"the {role} declares canInterpolateInputs=false"
        return ""
    finally:
        system.free()


def study(systems, quick, workdir):
    rows = []
    for name in systems:
        factory, stop, steps, exact = SYSTEMS[name]
        if quick:
            stop, steps = stop / 2, steps[1::2]
        if exact is None and not missing_capability(factory, "rollback", workdir):
            ref_t, ref = run(factory, "rollback", PLANT_SUBSTEP, stop, workdir)[:2]
            print(f"{name}: reference ready (rollback at h = {PLANT_SUBSTEP})")
        elif exact is None:
            ref_t, ref, ref_error = richardson_reference(factory, stop, workdir)
            print(f"{name}: reference ready (Gauss-Seidel at h = {PLANT_SUBSTEP} differs from 2h by {ref_error:.2g})")
        for master in MASTERS:
            why = missing_capability(factory, master, workdir)
            for H in steps:
                row = dict(system=name, master=master, H=H, error=math.nan, iterations_per_step=math.nan,
                           save_restore_us_per_step=math.nan, dostep_us_per_step=math.nan,
                           wall_us_per_step=math.nan, note=why)
                if not why:
                    try:
                        t, y, iterations, save_restore, stepping, wall = run(factory, master, H, stop, workdir)
                        reference = exact(t) if exact else np.array([np.interp(t, ref_t, ref[:, j])
                                                                     for j in range(ref.shape[1])]).T
                        row.update(error=float(np.max(np.abs(y - reference))), iterations_per_step=iterations,
                                   save_restore_us_per_step=1e6 * save_restore if master == "rollback" else math.nan,
                                   dostep_us_per_step=1e6 * stepping, wall_us_per_step=1e6 * wall)
                    except Exception as e:  # an unstable loop ends in a discard: recorded, not fatal
                        row["note"] = f"failed: {str(e)[:120]}"
                rows.append(row)
                print(f"{name:9s} {master:16s} H = {H:<7g} error {row['error']:.3g}  "
                      f"iterations {row['iterations_per_step']:.3g}  {row['note']}")
    add_orders(rows)
    return rows


def add_orders(rows):
    """Slope of log(error) over log(H) for each system and master (least squares
    over the three smallest steps: the asymptotic range)."""
    for key in {(r["system"], r["master"]) for r in rows}:
        group = sorted((r for r in rows if (r["system"], r["master"]) == key and r["error"] > 0),
                       key=lambda r: r["H"])[:3]
        order = math.nan
        if len(group) >= 2:
            order = float(np.polyfit(np.log([r["H"] for r in group]), np.log([r["error"] for r in group]), 1)[0])
        for r in rows:
            if (r["system"], r["master"]) == key:
                r["order"] = order


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    systems = sorted({r["system"] for r in rows})
    fig, axes = plt.subplots(1, len(systems), figsize=(5.5 * len(systems), 4.2), squeeze=False, layout="constrained")
    for ax, name in zip(axes[0], systems):
        for master in MASTERS:
            group = [r for r in rows if r["system"] == name and r["master"] == master and r["error"] > 0]
            if group:
                ax.loglog([r["H"] for r in group], [r["error"] for r in group], "o-",
                          label=f"{master} (order {group[0]['order']:.2f})")
            else:
                notes = [r["note"] for r in rows if r["system"] == name and r["master"] == master]
                if notes:
                    ax.plot([], [], " ", label=f"{master}: not run ({notes[0]})")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel("communication step H [s]")
        ax.set_ylabel("largest error over the run" + (" [rad]" if name == "robot_arm" else ""))
        ax.set_title(name, fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("Closed-loop coupling error against the communication step", fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=pathlib.Path, default=ROOT / "benchmarks" / "results")
    parser.add_argument("--systems", nargs="+", default=list(SYSTEMS), choices=list(SYSTEMS))
    parser.add_argument("--quick", action="store_true", help="half the run, every other step (a smoke run)")
    parser.add_argument("--replot", action="store_true", help="redraw the PNG from the CSV in --out")
    args = parser.parse_args()
    if args.replot:
        with open(args.out / "cosim_coupling.csv") as f:
            rows = [{k: (float(v) if k in ("H", "error", "order") else v) for k, v in r.items()}
                    for r in csv.DictReader(f)]
        plot(rows, args.out / "cosim_coupling.png")
        return 0
    workdir = pathlib.Path(tempfile.mkdtemp(prefix="cosim_coupling_"))
    try:
        rows = study(args.systems, args.quick, workdir)
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    args.out.mkdir(parents=True, exist_ok=True)
    with open(args.out / "cosim_coupling.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, args.out / "cosim_coupling.png")
    print(f"cosim_coupling: wrote {args.out / 'cosim_coupling.csv'} and {args.out / 'cosim_coupling.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
