"""The harness of the Exudyn peer studies (peer_*.py): a study is its
physics (the problem's data, our run, the peer's runs, the error) in a
PeerStudy, which runs every code at every setting (best of N), writes the
CSVs and draws the error against wall time; and the pieces studies share:
driving our FMU, Exudyn's solver settings and common elements, the smooth
spin-up drive, Richardson extrapolation.

Timing rule, both codes: time.perf_counter around the simulation only.
Ours: fmi2EnterInitializationMode .. the last fmi2DoStep (instantiation,
unzipping and packing are outside). Exudyn: mbs.SolveDynamic / SolveStatic
(model building and mbs.Assemble are outside). The fastest of a few repeats
counts, which filters out noise from other processes on the machine.
"""
import argparse
import copy
import csv
import ctypes
import dataclasses
import functools
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "python"))
from conftest import FMUS, Slave, load_scene, packed  # noqa: E402

OURS = "MFBD-FMU"
EXUDYN = "Exudyn"
# Both codes stop Newton at the same increment tolerance unless a study says
# otherwise (ours: the error estimated after the last correction).
NEWTON_TOLERANCE = 1e-12
# Relative tolerances of the series driven by fmi2SetupExperiment (issue 18's range).
TOLERANCES = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
# The flexible studies' series (tolerance_series) span 1e-2 .. 1e-6. They
# start at 1e-2 because their loose levels are a hundredth of f1 (F3, the
# tip mass) or 1e-2 m (F4's tip, L = 10 m): what a user after that error
# asks for. They stop at 1e-6: below it the error of the modes under
# h_max, held per unit step, costs minutes per run on the fine meshes (F3
# n = 2 at 1e-8: 38 s for its 10 s), and the mesh's error is far above
# the time error there. Half decades between: Exudyn's front halves its
# step, a factor of about 4 in error per level at second order, and ours
# is sampled as finely (a factor of 10 overshot the error levels by up to
# 10: F4's elongation at 1e-7 reached 8.6e-9 at tolerance 1e-4, 2.2e-7 at
# 1e-3).
FLEXIBLE_TOLERANCES = [1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6]


def best_of(run, repeats, min_total=0.5, max_repeats=25):
    """Calls run() at least `repeats` times, and again while the runs so far
    took less than min_total seconds in all (so millisecond runs are repeated
    often enough for their minimum to mean something); the result (a dict)
    with the least wall time."""
    results = []
    while len(results) < repeats or (sum(r["wall_time_s"] for r in results) < min_total
                                     and len(results) < max_repeats):
        results.append(run())
    return min(results, key=lambda r: r["wall_time_s"])


class FmuRun:
    """One FMU instance, for timing a run and reading its Newton statistics.

    sample() and at_end() run the timed loop of fmi2DoStep and fmi2GetReal
    in C (fmu_loop.c) over the FMU's own entry points, as a C importer
    does; get() reads through a bare ctypes prototype (fmpy's
    checked wrappers would add about 2 us of Python per call, 5 ms of
    10 ms in F3 at n = 2: 1,000 doSteps and reads). Solver statistics
    come from the `logStatistics` line that fmi2Terminate writes (no log
    callback into Python at every step). The Newton tolerance is
    NEWTON_TOLERANCE (Exudyn's) unless `parameters` sets solver.tolerance."""

    def __init__(self, fmu, parameters=None, tolerance=None, stop_time=None):
        # Driven by an error tolerance (fmi2SetupExperiment), the Newton
        # tolerance follows it (README, Error control) unless set here.
        parameters = {**({} if tolerance else {"solver.tolerance": NEWTON_TOLERANCE}), **(parameters or {})}
        self.slave = Slave(fmu)
        assert self.slave.instantiate(logging_on=True), self.slave.messages()
        self.slave.call("setDebugLogging", True, ["logStatistics"])
        # stop_time: the duration the error tolerance holds over (README,
        # Error control; none: the scene's experiment).
        assert self.slave.call("setupExperiment", tolerance, 0.0, stop_time) == 0
        for name, value in parameters.items():
            assert self.slave.set(name, value) == 0, self.slave.messages()
        self.t = 0.0
        library = self.slave.fmu.dll
        self._component = ctypes.cast(self.slave.fmu.component, ctypes.c_void_p).value
        self._do_step = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                                         ctypes.c_int)(("fmi2DoStep", library))
        self._get_real = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t,
                                          ctypes.c_void_p)(("fmi2GetReal", library))
        self._reads = {}  # names -> (value references, values)
        # The entry points' addresses, for the C loop of sample().
        self._do_step_address = ctypes.cast(self._do_step, ctypes.c_void_p).value
        self._get_real_address = ctypes.cast(self._get_real, ctypes.c_void_p).value

    def initialize(self):
        assert self.slave.call("enterInitializationMode") == 0, self.slave.messages()
        assert self.slave.call("exitInitializationMode") == 0, self.slave.messages()

    def at_end(self, names, stop, communication):
        """Initializes, steps to `stop` by `communication` and reads `names`
        there only (none: nothing), then frees the instance: (the values, the
        wall time of initialization and steps, statistics)."""
        try:
            wall = self._timed_loop(communication, int(round(stop / communication)), None, 0, None)
            values = self.get(*names) if names else None
            statistics = self.statistics()
        finally:
            self.free()
        return values, wall, statistics

    def _timed_loop(self, output, steps, references, count, rows):
        """Initialization and fmu_loop.c's steps (reading `count` references
        into `rows` at every point), timed: the wall time. A Python loop
        would add about 1.5 us per communication step, a third of a small
        model's."""
        reached = ctypes.c_double(0.0)
        loop = fmu_loop()
        start = time.perf_counter()
        self.initialize()
        failed = loop(self._do_step_address, self._get_real_address, self._component, output, steps, references,
                      count, rows, ctypes.byref(reached))
        wall = time.perf_counter() - start
        assert failed == 0, f"fmi2DoStep or fmi2GetReal failed at t = {reached.value}:\n{self.slave.messages()}"
        self.t = reached.value
        return wall

    def get(self, *names):
        if names not in self._reads:
            references = (ctypes.c_uint * len(names))(*(self.slave.vr[n] for n in names))
            values = (ctypes.c_double * len(names))()
            self._reads[names] = references, values  # kept alive: the FMU is given their addresses
        references, values = self._reads[names]
        status = self._get_real(self._component, ctypes.addressof(references), len(names), ctypes.addressof(values))
        assert status == 0, self.slave.messages()
        return values[0] if len(names) == 1 else list(values)

    def statistics(self):
        """Substeps, Newton iterations, matrix factorizations and rejected
        (halved) substeps of the run so far, as a dict (terminates the run)."""
        assert self.slave.call("terminate") == 0, self.slave.messages()
        last = [m for _, c, m in self.slave.log if c == "logStatistics"][-1]
        found = dict(steps=r"substeps (\d+)", newton_iterations=r"Newton iterations (\d+)",
                     factorizations=r"factorizations (\d+)", rejected_steps=r"rejected (\d+)")
        return {k: int(m.group(1)) for k, pattern in found.items() if (m := re.search(pattern, last))}

    def free(self):
        unzip = self.slave.unzip_dir
        self.slave.free()
        shutil.rmtree(unzip, ignore_errors=True)

    def sample(self, names, stop, output):
        """Initializes, steps to `stop` by `output`, reading `names` at every
        communication point (t = 0 included), and frees the instance.
        Returns (samples, one row per point, the wall time of the run,
        statistics). Each read goes straight into its row of the array
        (_timed_loop)."""
        steps = int(round(stop / output))
        count = len(names)
        samples = np.zeros((steps + 1, count))
        references = (ctypes.c_uint * count)(*(self.slave.vr[n] for n in names))
        try:
            wall = self._timed_loop(output, steps, references, count, samples.ctypes.data)
            statistics = self.statistics()
        finally:
            self.free()
        return samples, wall, statistics


def our_run(fmu, h, output, stop, tolerance=None, parameters=None):
    """Our FMU at substeps of h, or (tolerance) driven by fmi2SetupExperiment's
    error tolerance over the run (stopTime `stop`) with h_max the output
    interval: the FMU then chooses the integrator (generalized-alpha, the
    error split at h_max, for flexible bodies) and the substeps."""
    if tolerance:
        return FmuRun(fmu, {"solver.h_max": output, **(parameters or {})}, tolerance=tolerance, stop_time=stop)
    return FmuRun(fmu, {"solver.h_max": h, **(parameters or {})})


def tolerance_series(pairs, run, tolerances=FLEXIBLE_TOLERANCES):
    """Ours driven by fmi2SetupExperiment's tolerance on every mesh of the
    (n, h) pairs, as one series (codes() entries of one model, each mesh's
    with the tolerances as its own settings; run(n, tolerance), each result
    naming its mesh in `elements`). The user of a flexible model picks the
    mesh for the spatial error and the tolerance for the time error, so
    this front spans both, as Exudyn's generalized-alpha front spans mesh
    and step."""
    def on_mesh(n, tolerance):
        return dict(run(n, tolerance), elements=n)

    return [(OURS, "by tolerance (generalized-alpha)", functools.partial(on_mesh, n), tolerances)
            for n in dict.fromkeys(n for n, _ in pairs)]


def fmu_loop():
    """benchmarks/fmu_loop.c's sample(), built (cc -O2) into the build folder
    when missing or older than its source."""
    source = ROOT / "benchmarks" / "fmu_loop.c"
    library = FMUS.parent / "fmu_loop.so"
    if not library.exists() or library.stat().st_mtime < source.stat().st_mtime:
        subprocess.run(["cc", "-O2", "-shared", "-fPIC", str(source), "-o", str(library)], check=True)
    function = ctypes.CDLL(str(library)).sample
    function.restype = ctypes.c_int
    function.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_int,
                         ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_void_p]
    return function


class SceneFactory:
    """Packs scene variants into FMUs (build/mfbd-pack) in one temporary folder."""

    def __init__(self):
        self.folder = pathlib.Path(tempfile.mkdtemp(prefix="mfbd-peer-"))

    def fmu(self, scene, name):
        return packed(copy.deepcopy(scene), self.folder, name)

    def close(self):
        shutil.rmtree(self.folder, ignore_errors=True)


def exudyn_settings(static=False, end_time=1.0, h=1e-3, rho_inf=0.8, tolerance=NEWTON_TOLERANCE,
                    sensor_period=None, sparse=False, residual_criterion=False):
    """Exudyn SimulationSettings for a timed run: no solution file, no console
    output, one thread, generalized-alpha with spectral radius rho_inf.

    Newton stops on the size of the increment (residualMode 1, tolerance
    `tolerance`), as ours does (largest position increment). Exudyn's default
    residual-based criterion (relative 1e-8) cannot be met on the stiff beams
    (axial stiffness 1e7 N): Newton fails, the step is cut many times, and
    the run is neither at the requested h nor fast. With residual_criterion
    the residual-based stop is kept (relative 1e-10, absolute 1e-12): the
    index-3 mass point pendulum needs it, because its multiplier increments
    grow like 1/h^2 and an increment-based stop then ends Newton too early
    or too late (the error at t = 10 s grows as h shrinks)."""
    import exudyn as exu

    s = exu.SimulationSettings()
    s.solution.file.write = False
    s.solution.sensors.active = sensor_period is not None
    if sensor_period is not None:
        s.solution.sensors.writePeriod = sensor_period
    s.parallel.numberOfThreads = 1
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse if sparse else exu.LinearSolverType.EXUdense
    solver = s.staticSolver if static else s.timeIntegration
    solver.verboseMode = 0
    if residual_criterion:
        solver.newton.residualMode = 0
        solver.newton.relativeTolerance = 1e-10
        solver.newton.absoluteTolerance = 1e-12
    else:
        solver.newton.residualMode = 1
        solver.newton.relativeTolerance = tolerance
        solver.newton.absoluteTolerance = tolerance
    if not static:
        s.timeIntegration.numberOfSteps = int(round(end_time / h))
        s.timeIntegration.endTime = end_time
        s.timeIntegration.generalizedAlpha.spectralRadius = rho_inf
    return s


def exudyn_solve(mbs, settings, static=False):
    """Runs the solver, timed: (wall time, dict(steps=, newton_iterations=,
    factorizations=)), factorizations being Exudyn's Jacobian computations
    (each one factorised)."""
    start = time.perf_counter()
    ok = (mbs.SolveStatic(settings) if static
          else mbs.SolveDynamic(settings, solverType=settings.timeIntegration.solverType))
    wall = time.perf_counter() - start
    assert ok, "Exudyn solver failed"
    it = mbs.sys["staticSolver" if static else "dynamicSolver"].it
    return wall, dict(steps=int(it.currentStepIndex), newton_iterations=int(it.newtonStepsCount),
                      factorizations=int(it.newtonJacobiCount))


EXPLICIT_SOLVERS = ("RK44", "DOPRI5", "ODE23")


def exudyn_explicit_settings(solver, end_time, h=None, tolerance=None, sensor_period=None):
    """Exudyn SimulationSettings for one of its explicit solvers: fixed steps
    h (RK44), or step-size control to a relative and absolute tolerance
    (DOPRI5, ODE23: automaticStepSize, the initial step Exudyn's own)."""
    import exudyn as exu

    s = exudyn_settings(end_time=end_time, h=h or end_time / 100, sensor_period=sensor_period)
    t = s.timeIntegration
    t.solverType = getattr(exu.DynamicSolverType, solver)
    t.automaticStepSize = tolerance is not None
    if tolerance is not None:
        t.relativeTolerance = tolerance
        t.absoluteTolerance = tolerance
    return s


def exudyn_beam_line_2d(mbs, n, length, mass_per_length, rotary_inertia, EI, EA, GA, start=0.0):
    """n Exudyn ObjectBeamGeometricallyExact2D elements on n + 1 NodeRigidBody2D
    nodes along x from `start`; returns the nodes."""
    from exudyn.itemInterface import NodeRigidBody2D, ObjectBeamGeometricallyExact2D

    nodes = [mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[start + length * i / n, 0.0, 0.0]))
             for i in range(n + 1)]
    for i in range(n):
        mbs.AddObject(ObjectBeamGeometricallyExact2D(
            nodeNumbers=[nodes[i], nodes[i + 1]], length=length / n, massPerLength=mass_per_length,
            crossSectionInertia=rotary_inertia, bendingStiffness=EI, axialStiffness=EA, shearStiffness=GA))
    return nodes


def exudyn_clamp_coordinates(mbs, node, count):
    """Exudyn coordinate constraints holding the first `count` coordinates of
    a node at their reference (or at an offset set on them later); returns
    the connector objects."""
    from exudyn.itemInterface import MarkerNodeCoordinate, NodePointGround, ObjectConnectorCoordinate

    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    fixed = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    return [mbs.AddObject(ObjectConnectorCoordinate(
        markerNumbers=[fixed, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=c))]))
        for c in range(count)]


def cantilever_scene(example, n):
    """An example cantilever (examples/<example>) with n elements, its loads
    moved to the tip node and that node as the output."""
    scene = load_scene(example)
    body = scene["flexible_bodies"][0]
    body["beam"]["elements"] = n
    body["loads"] = [dict(load, node=n) for load in body["loads"]]
    body["outputs"] = {"nodes": [n]}
    return scene


def spin_up_angle(t, omega, ramp, cos=np.cos, where=np.where):
    """The smooth spin-up of Simo and Vu-Quoc (F4, F5, F6): theta(t) =
    (omega/T)(t^2/2 + (T/(2 pi))^2 (cos(2 pi t/T) - 1)) up to T = ramp, then
    omega T/2 + omega (t - T). As numbers, or as an Exudyn symbolic
    expression given its cos and IfThenElse."""
    up = omega / ramp * (t * t / 2 + (ramp / (2 * np.pi))**2 * (cos(2 * np.pi / ramp * t) - 1))
    return where(t <= ramp, up, omega * ramp / 2 + omega * (t - ramp))


def exudyn_spin_up_drive(mbs, connector, omega, ramp):
    """Drives the offset of an Exudyn coordinate constraint along the spin-up
    angle, and its rate, by symbolic user functions (an expression tree
    evaluated in C++: no Python call per Newton iteration). Returns them:
    they must stay alive through the solve."""
    import exudyn as exu
    from exudyn.advancedUtilities import CreateSymbolicUserFunction

    sym = exu.symbolic

    def angle(mbs, t, itemNumber, lOffset):
        return spin_up_angle(t, omega, ramp, sym.cos, sym.IfThenElse)

    def rate(mbs, t, itemNumber, lOffset):
        up = omega / ramp * (t - ramp / (2 * np.pi) * sym.sin(2 * np.pi / ramp * t))
        return sym.IfThenElse(t <= ramp, up, sym.Real(omega))

    functions = []
    for function, name in ((angle, "offsetUserFunction"), (rate, "offsetUserFunction_t")):
        functions.append(CreateSymbolicUserFunction(mbs, function, name, connector))
        mbs.SetObjectParameter(connector, name, functions[-1])
    return functions


def study_arguments(doc, repeats, fmu=None, extra=()):
    """The command line of a peer study: --out (made if missing), --repeats,
    --fmu when the study runs one packed FMU, and `extra` as (flag, kwargs)."""
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("benchmarks/results"))
    if fmu is not None:
        parser.add_argument("--fmu", type=pathlib.Path, default=fmu)
    parser.add_argument("--repeats", type=int, default=repeats)
    parser.add_argument("--replot", action="store_true",
                        help="redraw the figure from the study's CSV in --out (no runs)")
    for flag, kwargs in extra:
        parser.add_argument(flag, **kwargs)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    return args


def figure(ncols=1, figsize=(7.5, 5)):
    """A figure with ncols axes, drawn without a display."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt.subplots(1, ncols, figsize=figsize)


def write_csv(path, rows):
    """rows: list of dicts; columns code, h_or_elements, wall_time_s, error
    first, then every other key in order of first appearance."""
    columns = ["code", "h_or_elements", "wall_time_s", "error"]
    for r in rows:
        columns += [k for k in r if k not in columns]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
    print(f"wrote {pathlib.Path(path).resolve()}")


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def series_label(row):
    return f"{row['code']}: {row['model']}" if row.get("model") else row["code"]


def pareto_front(points):
    """Indices of the (time, error) points no cheaper point beats in error,
    cheapest first: a code at its best settings."""
    front, best = [], np.inf
    for i in sorted(range(len(points)), key=lambda k: points[k][0]):
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def plot_precision_work(ax, rows, error_key="error", annotate="h_or_elements", floor=1e-16):
    """Log-log error against wall time, one series per code and model: every
    run a marker, a line through the series' Pareto front labelled with
    `annotate` (a column, or a function of the row; open unlabelled markers:
    runs a cheaper run of the same series beats, their settings in the
    CSV), the legend below the axes where it hides no point."""
    palette = {OURS: [("C0", "o"), ("C9", "v"), ("C4", "P")],
               EXUDYN: [("C3", "s"), ("C2", "^"), ("C1", "D"), ("C5", "X"), ("C6", "<"), ("C8", ">")]}
    labels = list(dict.fromkeys(series_label(r) for r in rows))
    for label in labels:
        sel = [r for r in rows if series_label(r) == label and r.get(error_key) not in (None, "")]
        if not sel:
            continue
        x = np.array([float(r["wall_time_s"]) for r in sel])
        y = np.maximum(np.array([float(r[error_key]) for r in sel]), floor)
        code = sel[0]["code"]
        same_code = [lab for lab in labels if lab.startswith(code)]
        color, marker = palette[code][same_code.index(label) % len(palette[code])]
        front = pareto_front(list(zip(x, y)))
        ax.loglog(x[front], y[front], "-", marker=marker, color=color, label=label)
        beaten = [i for i in range(len(sel)) if i not in front]
        ax.loglog(x[beaten], y[beaten], linestyle="none", marker=marker, color=color, mfc="none", alpha=0.6)
        for i in front:
            text = annotate(sel[i]) if callable(annotate) else _short(sel[i][annotate])
            ax.annotate(text, (x[i], y[i]), textcoords="offset points", xytext=(4, 3), fontsize=6, color=color)
    ax.grid(True, which="both", alpha=0.3)
    legend_below(ax)


def draw_curves(ax, t, curves, ylabel, title):
    """Curves over time, each (values, matplotlib format, line width, label)."""
    for values, style, width, label in curves:
        ax.plot(t, values, style, lw=width, label=label)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)


def legend_below(ax):
    """The legend under the axes (outside the data), one entry a line."""
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), borderaxespad=0.0)


def refinement_grid(pairs, meshes=2):
    """The paired refinements (n, h) plus the finer steps on the `meshes`
    coarsest meshes: where the spatial error is small, a code's best
    setting is a coarse mesh with a fine step; both codes run the same grid
    and the Pareto front of each shows it at its best."""
    grid = list(pairs)
    for i, (n, _) in enumerate(pairs[:meshes]):
        grid += [(n, h) for _, h in pairs[i + 1:] if h < pairs[i][1] and (n, h) not in grid]
    return grid


STATISTICS = ("steps", "newton_iterations", "factorizations", "rejected_steps")


def sweep(label, codes, settings, repeats, measure, keep=None):
    """Every (code, model, run) of `codes` at every setting, the best of
    `repeats`: one row per run. A code given as (code, model, run,
    own_settings) runs at its own settings instead (tolerances of a
    solver with step-size control beside the fixed steps of the others). A setting is a substep h or an element count
    n (run(setting)), or a pair (n, h) (run(n, h)); the row has the code,
    the setting (h_or_elements, and h_s for a pair), the wall time, the
    model, measure(result, code)'s columns (the error among them) and the
    solver's statistics. keep: a dict that gets each best result by (code,
    setting), for a study that draws its runs' curves."""
    rows = []
    for code, model, run, *own in codes:
        for setting in (own[0] if own else settings):
            pair = isinstance(setting, tuple)
            r = best_of(lambda: run(*setting) if pair else run(setting), repeats)
            if keep is not None:
                keep[(code, setting)] = r
            rows.append(result_row(label, code, model, setting, r, measure(r, code)))
    return rows


def result_row(label, code, model, setting, r, columns):
    """The CSV row of one run (see sweep), and its log line."""
    pair = isinstance(setting, tuple)
    row = dict(code=code, h_or_elements=setting[0] if pair else setting, wall_time_s=r["wall_time_s"], model=model)
    if pair:
        row["h_s"] = setting[1]
    where = f"n={setting[0]:<4d} h={setting[1]:8.2e}" if pair else f"{setting:g}"
    text = "  ".join(f"{k} {v:.3e}" if isinstance(v, float) else f"{k} {v}" for k, v in columns.items())
    print(f"{label} {code:9s} {model}  {where}  wall {r['wall_time_s'] * 1e3:9.2f} ms  {text}  "
          f"Newton it/step {r['newton_iterations'] / r['steps']:.2f}", flush=True)
    return dict(row, **columns, **{k: r.get(k, "") for k in STATISTICS})


def measured(r, code=None):
    """A result's own columns: the numbers and texts it carries beyond the
    wall time and the statistics (curves stay out of the CSV)."""
    return {k: v for k, v in r.items()
            if k != "wall_time_s" and k not in STATISTICS and isinstance(v, (int, float, str))}


@dataclasses.dataclass
class Panel:
    """One axes of error against wall time: the rows' column `error_key`."""
    ylabel: str
    title: str
    error_key: str = "error"
    floor: float = 1e-16
    fontsize: int = 9


FIGURE_SIZES = {1: (7.5, 5), 2: (12, 5), 3: (16, 5)}


class PeerStudy:
    """A peer study: a subclass gives its label and file name, the settings,
    the codes (code, model, run) and the figure's panels; results of a run
    are dicts with wall_time_s, the solver statistics and the measured
    columns (measure() turns a run's raw quantities into errors where a
    study needs a reference). main() parses the command line, runs every
    code at every setting (or, with --replot, reads the CSVs back), writes
    results/<name>_<table>.csv for each of `tables` and draws
    results/<name>_precision.png. A study that computes references first,
    or writes more tables, extends run(); one whose figure draws curves of
    its runs (no --replot: the CSVs do not keep them) sets curves = True and
    extends draw()."""

    label = ""           # prefix of the log lines ("R1")
    name = ""            # results/<name>_precision.csv, .png
    repeats = 2          # best of, by default
    fmu = None           # a packed example (--fmu), or None: the study packs its scenes (self.pack)
    xlabel = ""          # the wall time's axis
    annotate = "h_or_elements"  # the label of a point on the Pareto front (a column or a function of the row)
    tables = ("precision",)
    curves = False

    settings = ()        # substeps h, element counts n, or pairs (n, h)

    def codes(self):
        """[(code, model, run)]: run(setting) -> result."""
        raise NotImplementedError

    def measure(self, r, code):
        return measured(r)

    def panels(self, tables):
        raise NotImplementedError

    def run(self):
        """The tables of a run: {table: rows}."""
        return {"precision": sweep(self.label, self.codes(), self.settings, self.args.repeats, self.measure)}

    def draw(self, tables, png):
        panels = self.panels(tables)
        fig, axes = figure(len(panels), FIGURE_SIZES[len(panels)])
        for ax, panel in zip(np.atleast_1d(axes), panels):
            self.draw_panel(ax, tables["precision"], panel)
        save_figure(fig, png)

    def draw_panel(self, ax, rows, panel):
        plot_precision_work(ax, rows, panel.error_key, self.annotate, panel.floor)
        ax.set_xlabel(self.xlabel)
        ax.set_ylabel(panel.ylabel)
        ax.set_title(panel.title, fontsize=panel.fontsize)

    def pack(self, scene, name):
        """Our FMU of a scene variant (packed once per run of the study)."""
        return self._factory.fmu(scene, name)

    def main(self, doc):
        self.args = study_arguments(doc, self.repeats, self.fmu)
        paths = {t: self.args.out / f"{self.name}_{t}.csv" for t in self.tables}
        if self.args.replot:
            if self.curves:
                sys.exit(f"--replot: the figure of {self.name} draws the runs' curves, which its CSVs do not keep")
            tables = {t: read_csv(path) for t, path in paths.items()}
        else:
            self._factory = SceneFactory()
            try:
                tables = self.run()
            finally:
                self._factory.close()
            for t, path in paths.items():
                write_csv(path, tables[t])
        self.draw(tables, self.args.out / f"{self.name}_precision.png")


def extrapolated(coarse, fine):
    """Richardson extrapolation for order 2 in the element size (n doubled)."""
    return fine + (fine - coarse) / 3.0


def extrapolated_references(label, runs, meshes, key, column):
    """Each code's runs at `meshes` ((n, h), n doubling) and the extrapolation
    of result[key] from the last two: (rows for a reference CSV, with the
    value in `column`; {code: extrapolated value})."""
    rows, values = [], {}
    for code, run in runs:
        found = []
        for n, h in meshes:
            r = run(n, h)
            found.append(r[key])
            rows.append(dict(code=code, h_or_elements=n, wall_time_s=r["wall_time_s"], error="", h_s=h,
                             **{column: r[key]}, kind="run"))
            print(f"{label} reference {code:9s} n={n:4d} h={h:7.1e}  {key} {r[key]:.9f}  "
                  f"wall {r['wall_time_s']:.2f} s", flush=True)
        values[code] = extrapolated(*found[-2:])
        rows.append(dict(code=code, h_or_elements="extrapolated", wall_time_s="", error="", h_s=meshes[-1][1],
                         **{column: values[code]}, kind="Richardson in n, order 2"))
    return rows, values


def mesh_and_step(row):
    """Annotation of a run over elements and substep: "n / h"; of a run
    driven by a tolerance: "n / tol" and its value (n where the row has
    it); of a run at a substep h only: h."""
    if row.get("tolerance") not in (None, ""):
        mesh = f"{row['elements']}/" if row.get("elements") not in (None, "") else ""
        return f"{mesh}tol {float(row['tolerance']):.0e}"
    if row.get("h_s") in (None, ""):
        return _short(row["h_or_elements"])
    return f"{_short(row['h_or_elements'])}/{float(row['h_s']):.0e}"


def _short(value):
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    return f"{int(v)}" if v >= 1 and v == int(v) else f"{v:.0e}"


def save_figure(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")  # legends sit outside the axes
    print(f"wrote {pathlib.Path(path).resolve()}")


def extrapolated_value(rows, column):
    """Our extrapolated value in a study's reference rows (as written or read back)."""
    return float(next(r[column] for r in rows if r["code"] == OURS and r["h_or_elements"] == "extrapolated"))


def cheapest_at(rows, level, error_key="error"):
    """The cheapest run (least wall time) of rows whose error is <= level, or None."""
    ok = [r for r in rows if r.get(error_key) not in (None, "") and float(r[error_key]) <= level]
    return min(ok, key=lambda r: float(r["wall_time_s"])) if ok else None
