#!/usr/bin/env python3
"""F5 parameter study on Dask: the rod's Young's modulus E and stiffness-
proportional damping against the peak mid-span deflection, a grid of
E x damping runs (default 20 x 10 = 200), one FMU instance per task.

    python examples/flexible_slider_crank/sweep.py build/fmus/flexible_slider_crank.fmu --out out/f5_sweep
    ... --e-values 4 --damping-values 2     (8 runs)
    ... --serial    also time the same runs one after another in this process
"""
import argparse
import pathlib
import sys
import time

import numpy as np
from fmpy import read_model_description

here = pathlib.Path(__file__).resolve().parent
sys.path[:0] = [str(here), str(here.parents[1] / "python")]
from mfbd import sweep  # noqa: E402
from plot import exposed_nodes, midspan_deflection  # noqa: E402


def peak_deflection_mm(nodes):
    return lambda result: 1e3 * np.max(np.abs(midspan_deflection(result.column, nodes)))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out/f5_sweep"))
    parser.add_argument("--e-values", type=int, default=20, help="E from 0.5e11 to 2.5e11 Pa")
    parser.add_argument("--damping-values", type=int, default=10, help="rod.damping from 0 to 2e-4 s")
    parser.add_argument("--workers", type=int, help="LocalCluster processes (default: the cores)")
    parser.add_argument("--scheduler", help="a Dask scheduler address")
    parser.add_argument("--serial", action="store_true", help="also time the runs in one process")
    args = parser.parse_args()
    nodes = exposed_nodes(read_model_description(str(args.fmu)))
    points = sweep.samples([("E", np.linspace(0.5e11, 2.5e11, args.e_values)),
                            ("rod.damping", np.linspace(0.0, 2e-4, args.damping_values))])
    outputs = [f"rod.node{i}.position.*" for i in nodes]
    metrics = {"peak_midspan_deflection_mm": peak_deflection_mm(nodes)}
    start = time.perf_counter()
    rows = sweep.run_sweep(args.fmu, points, outputs, metrics=metrics, scheduler=args.scheduler, workers=args.workers)
    parallel = time.perf_counter() - start
    args.out.mkdir(parents=True, exist_ok=True)
    sweep.write_table(rows, args.out / "f5_sweep.csv")
    sweep.plot_sweep(rows, "E", "peak_midspan_deflection_mm", args.out / "f5_sweep.png", "rod.damping",
                     {"E": "Pa", "rod.damping": "s", "peak_midspan_deflection_mm": "mm"})
    per_run = np.mean([r["wall_time_s"] for r in rows])
    print(f"sweep: {len(rows)} runs on Dask in {parallel:.1f} s ({per_run:.3f} s per run in a worker); "
          f"wrote {(args.out / 'f5_sweep.csv').resolve()}")
    if args.serial:
        start = time.perf_counter()
        serial_rows = [sweep.one_run(args.fmu.read_bytes(), "serial", p, outputs, None, None, metrics) for p in points]
        serial = time.perf_counter() - start
        print(f"sweep: the same runs in one process {serial:.1f} s "
              f"({np.mean([r['wall_time_s'] for r in serial_rows]):.3f} s per run): speed-up {serial / parallel:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
