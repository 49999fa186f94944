"""Shared pieces of the Exudyn peer studies (peer_*.py): driving our FMU,
Exudyn solver settings, best-of-N timing, and the CSV / log-log plot every
study writes.

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
from conftest import FMUS, Slave, load_scene, packed  # noqa: E402,F401

OURS = "MFBD-FMU"
EXUDYN = "Exudyn"
# Both codes stop Newton at the same increment tolerance unless a study says
# otherwise (ours: the error estimated after the last correction).
NEWTON_TOLERANCE = 1e-12


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

    sample() runs the timed loop of fmi2DoStep and fmi2GetReal in C
    (fmu_loop.c) over the FMU's own entry points, as a C importer does;
    step() and get() call them through bare ctypes prototypes (fmpy's
    checked wrappers would add about 2 us of Python per call, 5 ms of
    10 ms in F3 at n = 2: 1,000 doSteps and reads). Solver statistics
    come from the `logStatistics` line that fmi2Terminate writes (no log
    callback into Python at every step). The Newton tolerance is
    NEWTON_TOLERANCE (Exudyn's) unless `parameters` sets solver.tolerance."""

    def __init__(self, fmu, parameters=None):
        parameters = {"solver.tolerance": NEWTON_TOLERANCE, **(parameters or {})}
        self.slave = Slave(fmu)
        assert self.slave.instantiate(logging_on=True), self.slave.messages()
        self.slave.call("setDebugLogging", True, ["logStatistics"])
        assert self.slave.call("setupExperiment", None, 0.0, None) == 0
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

    def step(self, h):
        status = self._do_step(self._component, self.t, h, 1)
        assert status == 0, f"fmi2DoStep status {status} at t = {self.t}:\n{self.slave.messages()}"
        self.t += h

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
        statistics). The timed loop of doSteps and reads runs in C
        (benchmarks/fmu_loop.c), as a co-simulation master's does, each read
        straight into its row of the array: the time is the FMU's, not a
        Python loop's (about 1.5 us per communication step, a third of a
        small model's)."""
        steps = int(round(stop / output))
        count = len(names)
        samples = np.zeros((steps + 1, count))
        references = (ctypes.c_uint * count)(*(self.slave.vr[n] for n in names))
        reached = ctypes.c_double(0.0)
        loop = fmu_loop()
        try:
            start = time.perf_counter()
            self.initialize()
            failed = loop(self._do_step_address, self._get_real_address, self._component, output, steps, references,
                          count, samples.ctypes.data, ctypes.byref(reached))
            wall = time.perf_counter() - start
            assert failed == 0, f"fmi2DoStep or fmi2GetReal failed at t = {reached.value}:\n{self.slave.messages()}"
            self.t = reached.value
            statistics = self.statistics()
        finally:
            self.free()
        return samples, wall, statistics


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
    ok = mbs.SolveStatic(settings) if static else mbs.SolveDynamic(settings)
    wall = time.perf_counter() - start
    assert ok, "Exudyn solver failed"
    it = mbs.sys["staticSolver" if static else "dynamicSolver"].it
    return wall, dict(steps=int(it.currentStepIndex), newton_iterations=int(it.newtonStepsCount),
                      factorizations=int(it.newtonJacobiCount))


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
    palette = {OURS: [("C0", "o"), ("C9", "v")], EXUDYN: [("C3", "s"), ("C2", "^"), ("C1", "D")]}
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


def grid_study(label, runs, grid, repeats, measure):
    """Every (code, model, run) of `runs` at every (n, h) of `grid`, the best
    of `repeats`: one row per run with the columns every study has and
    measure(result)'s own (a dict with the error, and a text for the log
    line)."""
    rows = []
    for code, model, run in runs:
        for n, h in grid:
            r = best_of(lambda: run(n, h), repeats)
            columns, text = measure(r)
            rows.append(dict(code=code, h_or_elements=n, wall_time_s=r["wall_time_s"], model=model, h_s=h, **columns,
                             steps=r["steps"], newton_iterations=r["newton_iterations"],
                             factorizations=r.get("factorizations", ""), rejected_steps=r.get("rejected_steps", "")))
            print(f"{label} {code:9s} n={n:4d} h={h:8.2e}  wall {r['wall_time_s']:7.3f} s  {text}  Newton it/step "
                  f"{r['newton_iterations'] / r['steps']:.2f}", flush=True)
    return rows


def mesh_and_step(row):
    """Annotation of a run over elements and substep: "n / h"."""
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


def extrapolated_reference(path, column="tip_deflection_7s_m"):
    """Our Richardson-extrapolated value from a study's reference CSV (to
    redraw its figure)."""
    row = next(r for r in read_csv(path) if r["code"] == OURS and r["h_or_elements"] == "extrapolated")
    return float(row[column])


def cheapest_at(rows, level, error_key="error"):
    """The cheapest run (least wall time) of rows whose error is <= level, or None."""
    ok = [r for r in rows if r.get(error_key) not in (None, "") and float(r[error_key]) <= level]
    return min(ok, key=lambda r: float(r["wall_time_s"])) if ok else None
