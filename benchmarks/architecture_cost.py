#!/usr/bin/env python3
"""Cost of our FMU on each problem of scripts/benchmark.sh, built from two
commits: "before" (a build folder of the older code) against "after" (this
checkout's build/). Issue 16 item 9: the restructuring must leave no
problem more than 5 % slower.

Each problem runs at settings its peer study uses (the scene, parameters,
outputs, stop time and communication step are taken from the study's own
`ours` function, so they cannot drift from the study), with
generalized-alpha at fixed substeps h_max and no FMI tolerance in both
builds (the newer code's scene gets solver.method = generalized_alpha, so
its automatic choice cannot pick another integrator). The master is
tests/fmu_master/fmu_master.c (build/fmu_master), which drives the FMU
binary as a C importer does and prints every output at every
communication point.

Two measures:
  * instructions: valgrind --tool=callgrind, counted inside
    fmi2EnterInitializationMode, fmi2ExitInitializationMode, fmi2DoStep
    and fmi2GetReal (the region the studies time; loading, parsing and
    instantiation are outside). Independent of the machine's load, and
    the primary measure;
  * CPU: the whole master process's user + system time (os.wait4), median
    of --runs runs, before and after interleaved (A B A B ...), so a
    drift in the machine's speed hits both alike. Includes process start
    and instantiation (about 1-3 ms).
Both builds' outputs are compared row by row: the largest difference of a
column relative to that column's largest magnitude.

Writes results/architecture_cost.csv and .png. Usage:
  python benchmarks/architecture_cost.py --before BUILD_DIR [--after BUILD_DIR]
        [--runs N] [--only R1,F6] [--no-callgrind] [--out benchmarks/results]
"""
import argparse
import copy
import csv
import importlib
import json
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
import zipfile

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
import peer_common  # noqa: E402
from peer_common import load_scene  # noqa: E402

COUNTED = ("fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2DoStep", "fmi2GetReal")


class Recorded(Exception):
    """Raised by Recorder at the run: the study's settings are known then."""


class Recorder:
    """Stands in for peer_common.FmuRun inside a study's `ours`: keeps the
    parameters (with FmuRun's default Newton tolerance), the outputs, the
    stop time and the communication step, and runs nothing."""

    last = None

    def __init__(self, fmu, parameters=None, tolerance=None):
        assert tolerance is None, "the comparison runs at fixed substeps, without an FMI tolerance"
        self.parameters = {"solver.tolerance": peer_common.NEWTON_TOLERANCE, **(parameters or {})}

    def _record(self, names, stop, communication):
        Recorder.last = dict(parameters=self.parameters, names=list(names), stop=stop, communication=communication)
        raise Recorded

    def at_end(self, names, stop, communication):
        self._record(names, stop, communication)

    def sample(self, names, stop, output):
        self._record(names, stop, output)


def study(name):
    return importlib.import_module(name)


# (problem, setting label, study module, scene builder, the study's run of ours with a placeholder FMU).
# Per problem the coarsest setting of the study and a finer one (a run long enough for process CPU time).
CASES = [
    ("R1", "h 1e-2", "peer_r1_pendulum", lambda m: load_scene("pendulum"), lambda m: m.ours(None, 1e-2)),
    ("R1", "h 1e-4", "peer_r1_pendulum", lambda m: load_scene("pendulum"), lambda m: m.ours(None, 1e-4)),
    ("R2", "h 1e-2", "peer_r2_double_pendulum", lambda m: load_scene("double_pendulum"),
     lambda m: m.ours(None, 1e-2)),
    ("R2", "h 5e-4", "peer_r2_double_pendulum", lambda m: load_scene("double_pendulum"),
     lambda m: m.ours(None, 5e-4)),
    ("R3", "h 1e-2", "peer_r3_n_four_bar", lambda m: m.scene(), lambda m: m.ours(None, 1e-2)),
    ("R3", "h 5e-4", "peer_r3_n_four_bar", lambda m: m.scene(), lambda m: m.ours(None, 5e-4)),
    ("R4", "h 1e-2", "peer_r4_bricard", lambda m: load_scene("bricard"), lambda m: m.ours(None, 1e-2)),
    ("R4", "h 1e-3", "peer_r4_bricard", lambda m: load_scene("bricard"), lambda m: m.ours(None, 1e-3)),
    ("R5", "h 1e-2", "peer_r5_slider_crank", lambda m: load_scene("slider_crank"), lambda m: m.ours(None, 1e-2)),
    ("R5", "h 2e-4", "peer_r5_slider_crank", lambda m: load_scene("slider_crank"), lambda m: m.ours(None, 2e-4)),
    ("R6", "h 1e-2", "peer_r6_flyball_governor", lambda m: load_scene("flyball_governor"),
     lambda m: m.ours(None, 1e-2)),
    ("R6", "h 5e-4", "peer_r6_flyball_governor", lambda m: load_scene("flyball_governor"),
     lambda m: m.ours(None, 5e-4)),
    ("F1", "n 2", "peer_f1_end_moment", lambda m: m.scene_with_elements(2), lambda m: m.ours(None, 2)),
    ("F1", "n 128", "peer_f1_end_moment", lambda m: m.scene_with_elements(128), lambda m: m.ours(None, 128)),
    ("F3", "n 2, h 1e-2", "peer_f3_vibration", lambda m: m.vibration_scene(2),
     lambda m: m.ours(None, "beam.node2.position.y", 1e-2)),
    ("F3", "n 16, h 2.5e-3", "peer_f3_vibration", lambda m: m.vibration_scene(16),
     lambda m: m.ours(None, "beam.node16.position.y", 2.5e-3)),
    ("F4 spin-up", "n 2, h 8e-3", "peer_f4_spin_up", lambda m: m.spin_up_scene(2),
     lambda m: m.ours(None, 2, 8e-3, m.STOP)),
    ("F4 spin-up", "n 8, h 2e-3", "peer_f4_spin_up", lambda m: m.spin_up_scene(8),
     lambda m: m.ours(None, 8, 2e-3, m.STOP)),
    ("F4 motor", "n 2, h 8e-3", "peer_f4_motor", lambda m: m.motor_scene(2), lambda m: m.ours(None, 2, 8e-3)),
    ("F4 motor", "n 8, h 2e-3", "peer_f4_motor", lambda m: m.motor_scene(8), lambda m: m.ours(None, 8, 2e-3)),
    ("F5", "n 2, h 5e-4", "peer_f5_slider_crank", lambda m: m.slider_crank_scene(2),
     lambda m: m.ours(None, 2, 5e-4)),
    ("F5", "n 8, h 1.25e-4", "peer_f5_slider_crank", lambda m: m.slider_crank_scene(8),
     lambda m: m.ours(None, 8, 1.25e-4)),
    ("F6", "n 2", "peer_f6_four_bar", lambda m: m.four_bar_scene(2), lambda m: m.ours(None, m.H)),
    ("F6", "n 8", "peer_f6_four_bar", lambda m: m.four_bar_scene(8), lambda m: m.ours(None, m.H)),
    ("tip mass", "n 2, h 1e-2", "peer_tip_mass", lambda m: m.tip_mass_scene(2),
     lambda m: m.ours(None, "tip.position.y", 1e-2, m.EXACT)),
    ("tip mass", "n 16, h 2.5e-3", "peer_tip_mass", lambda m: m.tip_mass_scene(16),
     lambda m: m.ours(None, "tip.position.y", 2.5e-3, m.EXACT)),
    ("chain", "n 20", "peer_chain_cost", lambda m: m.chain_scene(20), lambda m: m.ours(None)),
    ("chain", "n 200", "peer_chain_cost", lambda m: m.chain_scene(200), lambda m: m.ours(None)),
]


def case_settings(module_name, scene_of, run_of):
    """The scene and the recorded run settings of one case."""
    m = study(module_name)
    # The study may make its run itself or through peer_common.our_run.
    m.FmuRun = Recorder
    shared, peer_common.FmuRun = peer_common.FmuRun, Recorder
    scene = scene_of(m)
    try:
        run_of(m)
    except Recorded:
        pass
    else:
        raise RuntimeError(f"{module_name}.ours ran no FmuRun")
    finally:
        peer_common.FmuRun = shared
    return scene, Recorder.last


class Packed:
    """A scene packed by one build's mfbd-pack and unzipped: the binary,
    resources, GUID and value references."""

    def __init__(self, build, scene, folder):
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "scene.json").write_text(json.dumps(scene, indent=1))
        fmu = folder / "scene.fmu"
        result = subprocess.run([str(build / "mfbd-pack"), str(folder / "scene.json"), "-o", str(fmu)],
                                capture_output=True, text=True)
        assert result.returncode == 0, f"{build / 'mfbd-pack'}: {result.stderr}"
        unzipped = folder / "fmu"
        with zipfile.ZipFile(fmu) as z:
            z.extractall(unzipped)
        root = ET.parse(unzipped / "modelDescription.xml").getroot()
        self.guid = root.get("guid")
        identifier = root.find("CoSimulation").get("modelIdentifier")
        self.binary = unzipped / "binaries" / "linux64" / f"{identifier}.so"
        self.resources = unzipped / "resources"
        self.vr = {v.get("name"): v.get("valueReference") for v in root.iter("ScalarVariable")}

    def command(self, master, run):
        outputs = [self.vr[n] for n in run["names"]]
        starts = [f"{self.vr[n]}={v!r}" for n, v in run["parameters"].items()]
        return [str(master), str(self.binary), str(self.resources), self.guid, "0", repr(run["stop"]),
                repr(run["communication"]), *outputs, *starts]


def callgrind(command, folder):
    """Instructions executed inside the counted FMI functions, the rows the
    master printed, and the solver statistics of the run."""
    out = folder / "callgrind.out"
    toggles = [f"--toggle-collect={f}" for f in COUNTED]
    env = {**os.environ, "MFBD_MASTER_LOG": "logStatistics"}
    result = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *toggles, *command],
                            capture_output=True, text=True, env=env)
    assert result.returncode == 0, result.stderr[-3000:]
    totals = re.search(r"^(?:summary|totals): (\d+)", out.read_text(), re.M)
    return int(totals.group(1)), result.stdout, solver_statistics(result.stderr)


def solver_statistics(log):
    found = dict(substeps=r"substeps (\d+)", newton=r"Newton iterations (\d+)", factorizations=r"factorizations (\d+)")
    lines = [line for line in log.splitlines() if "logStatistics" in line]
    if not lines:
        return {}
    return {k: int(m.group(1)) for k, p in found.items() if (m := re.search(p, lines[-1]))}


def cpu_seconds(command):
    """User + system CPU time of one run of the master (output discarded)."""
    with open(os.devnull, "wb") as null:
        process = subprocess.Popen(command, stdout=null, stderr=null)
        _, status, usage = os.wait4(process.pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0, command
    return usage.ru_utime + usage.ru_stime


def rows_of(text):
    return np.array([[float(x) for x in line.split()] for line in text.splitlines() if line.strip()])


def quantity(name):
    """The kind of an output, for its scale: "rod5.position.x" -> "position",
    "hinge1.angle" -> "angle"."""
    parts = name.split(".")
    return parts[-2] if len(parts) > 2 and parts[-1] in ("x", "y", "z", "w") else parts[-1]


def agreement(before, after, names):
    """Largest difference of an output over both runs, relative to the
    scale of its quantity (the largest magnitude of any output of the same
    kind: positions, velocities, angles...), and the output's name. A
    component that stays near zero is so measured against its vector's
    size, not against its own round-off."""
    a, b = rows_of(before), rows_of(after)
    if a.shape != b.shape:
        return float("inf"), f"rows {a.shape} vs {b.shape}"
    if a.shape[1] == 1:
        return 0.0, "time only"
    scales = {}
    for j, name in enumerate(names, start=1):
        q = quantity(name)
        scales[q] = max(scales.get(q, 0.0), np.abs(a[:, j]).max(), np.abs(b[:, j]).max())
    worst, where = 0.0, ""
    for j, name in enumerate(names, start=1):
        d = float(np.abs(a[:, j] - b[:, j]).max() / max(scales[quantity(name)], 1e-300))
        if d >= worst:
            worst, where = d, name
    return worst, where


def without_visuals(scene):
    """The scene without `visual` entries, which the older parser does not
    know (the physics never reads them)."""
    scene = copy.deepcopy(scene)
    for item in scene.get("bodies", []) + scene.get("flexible_bodies", []):
        item.pop("visual", None)
    return scene


def source_commit(build):
    """The commit of the sources a build folder was configured from (its
    CMakeCache's CMAKE_HOME_DIRECTORY), for the CSV and the figure."""
    cache = (build / "CMakeCache.txt").read_text()
    home = re.search(r"^CMAKE_HOME_DIRECTORY:INTERNAL=(.*)$", cache, re.M).group(1)
    result = subprocess.run(["git", "-C", home, "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    return result.stdout.strip() or home


def measure_case(args, label, setting, module_name, scene_of, run_of, work):
    scene, run = case_settings(module_name, scene_of, run_of)
    after_scene = copy.deepcopy(scene)
    after_scene.setdefault("solver", {})["method"] = "generalized_alpha"
    folder = work / re.sub(r"[^A-Za-z0-9]+", "_", f"{label}_{setting}")
    packs = {"before": Packed(args.before, without_visuals(scene), folder / "before"),
             "after": Packed(args.after, after_scene, folder / "after")}
    commands = {side: p.command(args.master, run) for side, p in packs.items()}
    row = dict(problem=label, setting=setting, before=args.before_commit, after=args.after_commit, stop_s=run["stop"], communication_s=run["communication"],
               h_max_s=run["parameters"].get("solver.h_max", ""))
    printed = {}
    if not args.no_callgrind:
        for side in ("before", "after"):
            instructions, printed[side], stats = callgrind(commands[side], folder / side)
            row[f"instructions_{side}"] = instructions
            for k, v in stats.items():
                row[f"{k}_{side}"] = v
        row["instructions_ratio"] = row["instructions_after"] / row["instructions_before"]
        if row.get("newton_before") and row.get("newton_after"):
            # Cost per Newton iteration: a change in how many iterations the
            # stopping test asks for is kept apart from the cost of each.
            row["per_newton_ratio"] = row["instructions_ratio"] * row["newton_before"] / row["newton_after"]
    else:
        for side in ("before", "after"):
            printed[side] = subprocess.run(commands[side], capture_output=True, text=True, check=True).stdout
    cpu = {"before": [], "after": []}
    for side in ("before", "after"):
        cpu_seconds(commands[side])  # warm-up: page cache, dynamic loader
    for _ in range(args.runs):
        for side in ("before", "after"):
            cpu[side].append(cpu_seconds(commands[side]))
    for side in ("before", "after"):
        row[f"cpu_ms_{side}"] = 1e3 * statistics.median(cpu[side])
    row["cpu_ratio"] = row["cpu_ms_after"] / row["cpu_ms_before"]
    row["max_relative_difference"], row["worst_output"] = agreement(printed["before"], printed["after"],
                                                                     run["names"])
    return row


def write_csv(path, rows):
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)


def draw(rows, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [f"{r['problem']}\n{r['setting']}" for r in rows]
    x = np.arange(len(rows))
    fig, ax = plt.subplots(figsize=(max(8, 0.55 * len(rows)), 4.8))
    if "instructions_ratio" in rows[0]:
        ax.bar(x - 0.2, [r["instructions_ratio"] for r in rows], 0.4, label="instructions (callgrind)")
    ax.bar(x + 0.2, [r["cpu_ratio"] for r in rows], 0.4, label="process CPU time, median of interleaved runs")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.axhline(1.05, color="r", lw=0.8, ls="--", label="+5 %")
    ax.set_xticks(x)
    ax.set_xticklabels(labels, rotation=90, fontsize=7)
    ax.set_ylabel("after / before")
    ax.set_title(f"Cost of our FMU built at {rows[0]['after']} over {rows[0]['before']}, "
                 "generalized-alpha at fixed substeps")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.45), ncol=3)
    fig.tight_layout()
    fig.savefig(png, dpi=110, bbox_inches="tight")
    print(f"wrote {png}")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--before", type=pathlib.Path, help="build folder of the older code")
    p.add_argument("--after", type=pathlib.Path, default=ROOT / "build", help="build folder of this code")
    p.add_argument("--master", type=pathlib.Path, default=ROOT / "build" / "fmu_master")
    p.add_argument("--runs", type=int, default=5, help="interleaved CPU-time runs of each build")
    p.add_argument("--only", default="", help="comma-separated problems (R1,F6,chain,...)")
    p.add_argument("--no-callgrind", action="store_true", help="CPU time only")
    p.add_argument("--out", type=pathlib.Path, default=HERE / "results")
    p.add_argument("--name", default="architecture_cost", help="results/NAME.csv and NAME.png")
    p.add_argument("--replot", action="store_true", help="redraw results/NAME.png from results/NAME.csv")
    p.add_argument("--keep", type=pathlib.Path, help="keep the packed FMUs and callgrind files in this folder")
    args = p.parse_args()
    if args.replot:
        with open(args.out / f"{args.name}.csv") as f:
            rows = [{k: (float(v) if re.fullmatch(r"[-+.\deE]+|inf|nan", v) else v) for k, v in r.items()}
                    for r in csv.DictReader(f)]
        draw(rows, args.out / f"{args.name}.png")
        return
    if args.before is None:
        p.error("--before BUILD_DIR is needed (or --replot)")
    args.before_commit, args.after_commit = source_commit(args.before), source_commit(args.after)
    only = {s.strip() for s in args.only.split(",") if s.strip()}
    rows = []
    with tempfile.TemporaryDirectory(prefix="mfbd-arch-") as tmp:
        if args.keep:
            tmp = args.keep
        for label, setting, module_name, scene_of, run_of in CASES:
            if only and label not in only:
                continue
            start = time.perf_counter()
            r = measure_case(args, label, setting, module_name, scene_of, run_of, pathlib.Path(tmp))
            rows.append(r)
            print(f"{label:10s} {setting:15s} instructions {r.get('instructions_ratio', float('nan')):.4f}  "
                  f"cpu {r['cpu_ms_before']:8.2f} -> {r['cpu_ms_after']:8.2f} ms ({r['cpu_ratio']:.3f})  "
                  f"outputs {r['max_relative_difference']:.1e} ({r['worst_output']})  "
                  f"[{time.perf_counter() - start:.0f} s]", flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    name = args.name if not only else args.name + "_" + "_".join(sorted(only)).replace(" ", "")
    write_csv(args.out / f"{name}.csv", rows)
    draw(rows, args.out / f"{name}.png")


if __name__ == "__main__":
    main()
