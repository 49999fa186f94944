"""One FMU run as a co-simulation master: parameters set by name, outputs
picked by name or glob pattern, progress while it runs, and a run that ends
in fmi2Discard marked as truncated."""
import ctypes
import dataclasses
import fnmatch
import pathlib
import shutil
import sys

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2LastSuccessfulTime)

# Categories of the FMU's log that --verbose switches on (logStep: substeps
# and Newton iterations per communication step).
VERBOSE_CATEGORIES = ["logEvents", "logStep", "logStatistics", "logNonlinearSystems", "logSingularLinearSystems",
                      "logStatusWarning", "logStatusDiscard", "logStatusError"]
STATUS = {0: "ok", 1: "warning", 2: "discard", 3: "error", 4: "fatal", 5: "pending"}


@dataclasses.dataclass
class Result:
    """Outputs over time; truncated (with a message) when a step was discarded."""
    model: str
    description: str
    time: np.ndarray
    values: dict          # output name -> array over time
    units: dict           # output name -> unit ('' when dimensionless)
    parameters: dict      # parameters set for this run
    truncated: bool = False
    message: str = ""
    log: list = dataclasses.field(default_factory=list)

    def column(self, name):
        return self.time if name == "time" else self.values[name]


def select(names, patterns):
    """Names matching any of the patterns (exact names or globs), in the
    order of names; a pattern that matches nothing is an error."""
    if not patterns:
        return list(names)
    chosen = set()
    for p in patterns:
        hits = [n for n in names if fnmatch.fnmatchcase(n, p)]
        if not hits:
            raise ValueError(f"output '{p}' matches no output of the FMU (e.g. {', '.join(list(names)[:4])})")
        chosen.update(hits)
    return [n for n in names if n in chosen]


def parse_assignments(items):
    """['name=value', ...] -> {name: float}, naming the bad item."""
    values = {}
    for item in items or []:
        name, sep, text = item.partition("=")
        try:
            if not sep:
                raise ValueError
            values[name.strip()] = float(text)
        except ValueError:
            raise ValueError(f"--param '{item}': expected name=value with a number value") from None
    return values


def variable_units(md):
    units = {}
    for v in md.modelVariables:
        units[v.name] = (getattr(v, "unit", None) or getattr(getattr(v, "declaredType", None), "unit", None) or "")
    return units


class Master:
    """One FMU instance: instantiate, set parameters, initialize; then
    step() and get(); close() frees it and its unpacked folder."""

    def __init__(self, fmu, parameters=None, verbose=False, log=None, start_time=0.0, stop_time=None,
                 relative_tolerance=None):
        self.md = read_model_description(str(fmu))
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.log = log if log is not None else []
        self.verbose = verbose
        self.unzip = extract(str(fmu))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzip,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="mfbd")
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = fmi2CallbackLoggerTYPE(self._logger)
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(lambda n, s: None)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(lambda p: None)
        self._callbacks.componentEnvironment = None
        uri = (pathlib.Path(self.unzip) / "resources").as_uri()
        self.fmu.component = self.fmu.fmi2Instantiate(b"mfbd", 1, self.md.guid.encode(), uri.encode(),
                                                      ctypes.byref(self._callbacks), 0, 1 if verbose else 0)
        if not self.fmu.component:
            self.close()
            raise RuntimeError("fmi2Instantiate failed: " + "; ".join(m for _, _, m in self.log))
        if verbose:
            self.fmu.setDebugLogging(True, VERBOSE_CATEGORIES)
        self.fmu.setupExperiment(tolerance=relative_tolerance, startTime=start_time, stopTime=stop_time)
        for name, value in (parameters or {}).items():
            self.set(name, value)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def _logger(self, env, name, status, category, message):
        entry = (STATUS.get(status, str(status)), category.decode(errors="replace"), message.decode(errors="replace"))
        self.log.append(entry)
        if self.verbose or status >= 1:
            from tqdm import tqdm
            tqdm.write(f"[{entry[0]}] {entry[1]}: {entry[2]}", file=sys.stderr)

    def set(self, name, value):
        v = self.variables.get(name)
        if v is None or v.causality not in ("parameter", "input"):
            known = [n for n, x in self.variables.items() if x.causality == "parameter"]
            raise ValueError(f"--param {name}: no such parameter of {self.md.modelName} "
                             f"(parameters: {', '.join(known)})")
        try:
            self.fmu.setReal([v.valueReference], [float(value)])
        except FMICallException:
            raise ValueError(f"--param {name}={value} refused by the FMU: "
                             + "; ".join(m for _, _, m in self.log[-2:])) from None

    def get(self, names):
        return self.fmu.getReal([self.variables[n].valueReference for n in names])

    def step(self, t, h):
        """True after a completed step; False after fmi2Discard (the FMU kept
        the state of the step start)."""
        try:
            self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            return True
        except FMICallException as e:
            if e.status != 2:
                raise
            return False

    def last_successful_time(self):
        return self.fmu.getRealStatus(fmi2LastSuccessfulTime)

    def close(self):
        try:
            if getattr(self.fmu, "component", None):
                self.fmu.fmi2FreeInstance(self.fmu.component)
                self.fmu.component = None
            self.fmu.freeLibrary()
        finally:
            shutil.rmtree(self.unzip, ignore_errors=True)


def simulate(fmu, parameters=None, outputs=None, stop_time=None, step=None, tolerance=None,
             progress=True, verbose=False, relative_tolerance=None):
    """Runs the FMU from its default experiment (overridden by the
    arguments) and returns a Result of the selected outputs. tolerance: the
    Newton tolerance (solver.tolerance); relative_tolerance: the error
    tolerance given to fmi2SetupExperiment (None: the default experiment's,
    0: none, substeps of solver.h_max)."""
    md = read_model_description(str(fmu))
    names = [v.name for v in md.modelVariables if v.causality == "output"]
    chosen = select(names, outputs)
    experiment = md.defaultExperiment
    t0 = float(experiment.startTime or 0.0) if experiment else 0.0
    t_end = float(stop_time if stop_time is not None else (experiment.stopTime if experiment else 1.0))
    h = float(step if step is not None else (experiment.stepSize if experiment and experiment.stepSize else
                                             (t_end - t0) / 500))
    if relative_tolerance is None:
        relative_tolerance = float(experiment.tolerance) if experiment and experiment.tolerance else 0.0
    params = dict(parameters or {})
    if tolerance is not None:
        params["solver.tolerance"] = tolerance
    log = []
    master = Master(fmu, params, verbose=verbose, log=log, start_time=t0, stop_time=t_end,
                    relative_tolerance=relative_tolerance or None)
    n = max(1, int(np.ceil((t_end - t0) / h * (1 - 1e-12))))  # the last step ends at t_end
    times, rows = [t0], [master.get(chosen)]
    truncated, message = False, ""
    bar = _progress(t_end - t0, enabled=progress)
    try:
        for k in range(n):
            t = t0 + k * h
            if not master.step(t, min(t0 + (k + 1) * h, t_end) - t):
                truncated = True
                last = master.last_successful_time()
                reasons = [m for s, _, m in log if s in ("discard", "error")]
                message = (f"fmi2Discard at t = {t:g} s (last successful time {last:g} s): "
                           + (reasons[-1] if reasons else "no message from the FMU"))
                break
            times.append(min(t0 + (k + 1) * h, t_end))
            rows.append(master.get(chosen))
            if bar:
                _advance(bar, times[-1] - t0)
    finally:
        if bar:
            bar.close()
        master.close()
    values = np.array(rows).reshape(len(rows), len(chosen))
    units = variable_units(md)
    return Result(md.modelName, md.description or "", np.array(times),
                  {n: values[:, i] for i, n in enumerate(chosen)}, {n: units.get(n, "") for n in chosen},
                  params, truncated, message, log)


def _progress(total, enabled):
    """A bar over simulated time with the real-time factor (simulated
    seconds per wall-clock second) and the ETA."""
    if not enabled:
        return None
    from tqdm import tqdm
    bar = tqdm(total=total, file=sys.stderr, unit="s", dynamic_ncols=True, mininterval=0.5,
               bar_format="t = {n:.4g}/{total:.4g} s |{bar}| {postfix}, elapsed {elapsed}, ETA {remaining}")
    bar.set_postfix_str("real-time factor ?", refresh=False)
    return bar


def _advance(bar, simulated):
    bar.update(simulated - bar.n)
    elapsed = bar.format_dict["elapsed"]
    if elapsed > 0:
        bar.set_postfix_str(f"real-time factor {simulated / elapsed:.3g}", refresh=False)
