"""Speed of the portable linux64 FMU binary (issue 19, item 5): the binary
as the build makes it now ("after") against one built the pre-portability
way ("before"), from the same source, on rigid and flexible example scenes.

after:  build/fmu_binaries/linux64/mfbd_fmu.so (the default configuration):
        libstdc++ linked in, glibc symbols newer than 2.17 sent to their
        2.17 versions (memcpy, exp, log, pow, hypot, ...), KLU compiled from
        the pinned SuiteSparse 7.1.0 source into the binary,
        -fno-delete-null-pointer-checks.
before: the same source configured with -DMFBD_PORTABLE_LINUX64=OFF (the
        system's shared libstdc++, glibc's current symbol versions),
        -DMFBD_SYSTEM_KLU=ON (Debian's shared libklu.so.1, SuiteSparse 5.12,
        as before commit 98ed8bb) and -DMFBD_NO_DELETE_NULL_POINTER_CHECKS=OFF
        (GCC's default): the configuration of c8ac0b0, the last commit before
        the portability work, apart from the FMI-only export map, which every
        build now has. Built here into build/before (the FMU binary only)
        unless --before names a binary.

Both binaries are driven by the project's C master (build/fmu_master: load,
instantiate on the packed FMU's resources, fixed communication steps of the
default experiment) over the same scene and span. Measures:

1. Primary, independent of the machine's load: instructions executed
   inside fmi2DoStep (everything the steps call: libm, libc, libstdc++ and
   KLU included), counted by valgrind's callgrind over the span, and split
   into the solver, KLU, libstdc++, libm and libc (GROUPS); and the
   instructions of a whole run of one step
   (loading, relocation, instantiation, initialization). One run each: the
   counts do not depend on the load.
2. Secondary: CPU time (user + system) of the whole master process, runs
   of the two binaries interleaved (after, before, before, after, ...) so
   that a change of the machine's load hits both alike; medians, and the
   median (min-max) of the after/before ratios of consecutive pairs.

The outputs of the two binaries are compared as well (largest difference
relative to the output's largest magnitude): the same numbers mean the
same work, so the counts compare the builds, not different paths.

Writes results/platform_speed.csv and .png. Not a test: nothing asserts a
time.

    .venv/bin/python benchmarks/platform_speed.py --out benchmarks/results
"""
import argparse
import csv
import os
import pathlib
import re
import shutil
import statistics
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "python"))
from conftest import BUILD, FMUS  # noqa: E402

from fmpy import extract, read_model_description  # noqa: E402

AFTER = BUILD / "fmu_binaries" / "linux64" / "mfbd_fmu.so"
BEFORE_BUILD = BUILD / "before"
BEFORE_OPTIONS = ["-DMFBD_PORTABLE_LINUX64=OFF", "-DMFBD_SYSTEM_KLU=ON", "-DMFBD_NO_DELETE_NULL_POINTER_CHECKS=OFF"]
MASTER = BUILD / "fmu_master"
# Scene -> (kind, simulated span in s): spans long enough that loading is
# a small part of a run, short enough for runs under callgrind.
SCENES = {
    "pendulum": ("rigid", 300.0),
    "double_pendulum": ("rigid", 100.0),
    "four_bar": ("rigid", 100.0),
    "n_four_bar": ("rigid", 3.0),
    "cantilever_vibration": ("flexible", 20.0),
    "flexible_four_bar": ("flexible", 4.0),
}


def build_before(folder, jobs):
    """Configures and builds the pre-portability FMU binary (and its master)
    in `folder`; returns the binary's path."""
    subprocess.run(["cmake", "-S", str(ROOT), "-B", str(folder), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                    "-DMFBD_FMU_ONLY=ON", f"-DPython3_EXECUTABLE={sys.executable}", *BEFORE_OPTIONS],
                   check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", str(folder), "--target", "mfbd_fmu", "-j", str(jobs)], check=True)
    return folder / "fmu_binaries" / "linux64" / "mfbd_fmu.so"


class Scene:
    """An example's packed FMU, extracted: the master's command line for a
    binary over the scene's first `span` seconds."""

    def __init__(self, name, span, folder):
        fmu = FMUS / f"{name}.fmu"
        self.name = name
        self.md = read_model_description(str(fmu))
        self.resources = pathlib.Path(extract(str(fmu), str(folder / name))) / "resources"
        experiment = self.md.defaultExperiment
        self.step = float(experiment.stepSize) if experiment and experiment.stepSize else 0.01
        self.span = span
        self.outputs = [v.valueReference for v in self.md.modelVariables
                        if v.causality == "output" and v.type == "Real"]

    def command(self, binary, span=None):
        return [str(MASTER), str(binary), str(self.resources), self.md.guid, "0", repr(span or self.span),
                repr(self.step), *map(str, self.outputs)]


def rows(text):
    return [[float(x) for x in line.split()] for line in text.splitlines()]


# Where fmi2DoStep's instructions go: KLU wherever it is (Debian's shared
# libraries before, compiled into the binary after), the system's
# libstdc++ (before only: after, it is inside the binary and counts as
# "binary"), libm, libc, and the rest of the FMU binary (the solver).
GROUPS = ("binary", "klu", "libstdcxx", "libm", "libc", "other")
KLU_LIBRARIES = ("libklu", "libamd", "libbtf", "libcolamd", "libsuitesparseconfig")


class KluNames:
    """Whether a function of the FMU binary is KLU's: a C identifier
    (LTO's suffixes such as .constprop.0 dropped) with a SuiteSparse prefix
    (the sources name their exported functions through macros, KLU_factor
    for klu_factor) or that KLU's pinned sources define or call (their
    static functions); the solver's functions are C++ (qualified names)."""

    def __init__(self, build):
        source = None
        for line in (build / "CMakeCache.txt").read_text().splitlines():
            if line.startswith("MFBD_KLU_SOURCE_DIR:"):
                source = pathlib.Path(line.split("=", 1)[1]) / "suitesparse"
        self.text = "\n".join(p.read_text(errors="replace") for part in
                              ("KLU", "AMD", "BTF", "COLAMD", "SuiteSparse_config")
                              for p in sorted((source / part).rglob("*.[ch]"))) if source else ""
        self.known = {}

    def __call__(self, function):
        name = function.split(".")[0]
        if name not in self.known:
            self.known[name] = bool(re.fullmatch(r"[A-Za-z_]\w*", name)) and (
                name.startswith(("klu_", "amd_", "btf_", "colamd", "symamd", "SuiteSparse_"))
                or re.search(rf"\b{re.escape(name)}\s*\(", self.text) is not None)
        return self.known[name]


def group(obj, function, klu_names):
    name = pathlib.Path(obj or "").name
    if name.startswith(KLU_LIBRARIES):
        return "klu"
    if name.startswith("mfbd_fmu"):
        return "klu" if klu_names(function or "") else "binary"
    for g, prefix in (("libstdcxx", "libstdc++"), ("libm", "libm.so"), ("libc", "libc.so")):
        if name.startswith(prefix):
            return g
    return "other"


def self_cost_by_group(path, klu_names):
    """Instructions (self cost) per GROUPS entry from a callgrind output file.
    Name compression: "ob=(3) /lib/x.so" defines id 3, "ob=(3)" refers to
    it (cob= shares the table, cfn= fn='s); the cost line after a "calls="
    line is the call's inclusive cost (counted in the callee's own lines),
    so it is skipped."""
    tables = {"ob": {}, "fn": {}}
    current = {"ob": None, "fn": None}
    after_call = False
    costs = dict.fromkeys(GROUPS, 0)
    with open(path) as f:
        for line in f:
            key = line.split("=", 1)[0]
            if key in ("ob", "cob", "fn", "cfn"):
                table = tables[key[-2:]]
                rest = line.rstrip("\n").split("=", 1)[1]
                m = re.match(r"\((\d+)\)(?: (.*))?$", rest)
                if m and m.group(2) is not None:
                    table[m.group(1)] = m.group(2)
                if key in current:
                    current[key] = table[m.group(1)] if m else rest
            elif line.startswith("calls="):
                after_call = True
            elif line[:1].isdigit() or line[:1] in "+-*":
                fields = line.split()
                if not after_call and len(fields) > 1:
                    costs[group(current["ob"], current["fn"], klu_names)] += int(fields[1])
                after_call = False
    return costs


def totals(path):
    for line in path.read_text().splitlines():
        if line.startswith(("totals:", "summary:")):
            return int(line.split()[1])
    raise RuntimeError(f"no total in {path}")


def callgrind(command, folder, tag, toggle=None):
    """(instructions counted, callgrind's output file, the master's output
    rows) of one run under callgrind; with `toggle`, only inside that
    function (inclusive: everything it calls)."""
    out = folder / f"callgrind.{tag}"
    run = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                          *([f"--toggle-collect={toggle}"] if toggle else []), *command],
                         capture_output=True, text=True, check=True)
    return totals(out), out, rows(run.stdout)


def cpu_seconds(command):
    """User + system CPU time of one run of `command` (a child process)."""
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(process.pid, 0)
    process.returncode = os.waitstatus_to_exitcode(status)
    if process.returncode != 0:
        raise RuntimeError(f"{command[1]} failed: {process.stderr.read().decode()[-1000:]}")
    process.stderr.close()
    return usage.ru_utime + usage.ru_stime


def interleaved(commands, repeats):
    """CPU seconds of each command over `repeats` rounds; the order within a
    round alternates, so neither command always runs first."""
    times = {k: [] for k in commands}
    keys = list(commands)
    for r in range(repeats):
        for k in (keys if r % 2 == 0 else keys[::-1]):
            times[k].append(cpu_seconds(commands[k]))
    return times


def largest_difference(a, b):
    """Largest |a - b| of an output relative to that output's largest
    magnitude (at least 1e-3), over the rows of both runs."""
    assert len(a) == len(b) and [r[0] for r in a] == [r[0] for r in b]
    worst = 0.0
    for k in range(1, len(a[0])):
        scale = max([1e-3] + [abs(r[k]) for r in a])
        worst = max(worst, max(abs(x[k] - y[k]) for x, y in zip(a, b)) / scale)
    return worst


def measure(scene, binaries, repeats, folder):
    steps = {k: callgrind(scene.command(b), folder, f"{scene.name}.{k}", toggle="fmi2DoStep")
             for k, b in binaries.items()}
    # Loading, instantiation, initialization and one step: what a run costs
    # besides its steps.
    fixed = {k: callgrind(scene.command(b, span=scene.step), folder, f"{scene.name}.{k}.fixed")[0]
             for k, b in binaries.items()}
    times = interleaved({k: scene.command(b) for k, b in binaries.items()}, repeats)
    ratios = sorted(a / b for a, b in zip(times["after"], times["before"]))
    result = {
        "scene": scene.name, "kind": SCENES[scene.name][0], "span_s": scene.span,
        "communication_steps": round(scene.span / scene.step),
        "dostep_instructions_before": steps["before"][0], "dostep_instructions_after": steps["after"][0],
        "dostep_instructions_ratio": steps["after"][0] / steps["before"][0],
        "one_step_run_instructions_before": fixed["before"], "one_step_run_instructions_after": fixed["after"],
        "cpu_s_before_median": statistics.median(times["before"]),
        "cpu_s_after_median": statistics.median(times["after"]),
        "cpu_ratio_median": statistics.median(ratios), "cpu_ratio_min": ratios[0], "cpu_ratio_max": ratios[-1],
        "repeats": repeats,
        "outputs_largest_relative_difference": largest_difference(steps["before"][2], steps["after"][2]),
    }
    klu_names = KluNames(BUILD)
    split = {k: self_cost_by_group(steps[k][1], klu_names) for k in binaries}
    for g in split["before"]:
        for k in ("before", "after"):
            result[f"dostep_{g}_{k}"] = split[k][g]
    return result


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    x = np.arange(len(results))
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.bar(x - 0.2, [r["dostep_instructions_ratio"] for r in results], 0.4,
           label="instructions in fmi2DoStep (callgrind)")
    median = np.array([r["cpu_ratio_median"] for r in results])
    spread = np.array([[m - r["cpu_ratio_min"], r["cpu_ratio_max"] - m] for m, r in zip(median, results)]).T
    ax.bar(x + 0.2, median, 0.4, yerr=spread, capsize=3,
           label="CPU time of the process, median of pairs (min-max)")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks(x, [r["scene"] for r in results], rotation=20)
    ax.set_ylabel("after / before")
    ax.set_ylim(0.5, max(1.5, max(r["cpu_ratio_max"] for r in results) + 0.05))
    ax.set_title("linux64 FMU binary: portable build (after) against the pre-portability build (before)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.3), ncol=1, frameon=False)
    fig.tight_layout()
    fig.subplots_adjust(bottom=0.38)
    fig.savefig(path, dpi=120)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=pathlib.Path, default=ROOT / "benchmarks" / "results")
    parser.add_argument("--before", type=pathlib.Path,
                        help="the pre-portability binary (default: built into build/before)")
    parser.add_argument("--after", type=pathlib.Path, default=AFTER)
    parser.add_argument("--repeats", type=int, default=21, help="interleaved CPU-time runs of each binary")
    parser.add_argument("--jobs", type=int, default=2, help="parallel jobs of the 'before' build")
    parser.add_argument("--scenes", nargs="*", default=list(SCENES), choices=list(SCENES))
    parser.add_argument("--replot", action="store_true", help="redraw the PNG from the CSV in --out")
    args = parser.parse_args()
    if args.replot:
        with open(args.out / "platform_speed.csv") as f:
            results = [{k: v if k in ("scene", "kind") else float(v) for k, v in r.items()} for r in csv.DictReader(f)]
        plot(results, args.out / "platform_speed.png")
        return
    if not shutil.which("valgrind"):
        sys.exit("platform_speed.py needs valgrind (scripts/setup.sh installs it)")
    before = args.before or build_before(BEFORE_BUILD, args.jobs)
    binaries = {"after": args.after.resolve(), "before": before.resolve()}
    args.out.mkdir(parents=True, exist_ok=True)
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = pathlib.Path(tmp)
        for name in args.scenes:
            scene = Scene(name, SCENES[name][1], folder)
            results.append(measure(scene, binaries, args.repeats, folder))
            r = results[-1]
            print(f"{name:22s} instructions in fmi2DoStep after/before {r['dostep_instructions_ratio']:.4f}"
                  f"  one-step run {r['one_step_run_instructions_after'] / r['one_step_run_instructions_before']:.3f}"
                  f"  CPU median of pairs {r['cpu_ratio_median']:.3f}"
                  f" ({r['cpu_ratio_min']:.3f}-{r['cpu_ratio_max']:.3f})"
                  f"  outputs differ by {r['outputs_largest_relative_difference']:.1e}", flush=True)
    with open(args.out / "platform_speed.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(results[0]))
        writer.writeheader()
        writer.writerows(results)
    plot(results, args.out / "platform_speed.png")


if __name__ == "__main__":
    main()
