"""`sweep`: a parameter study over any packed FMU on Dask, one FMU instance
per task: a grid or random samples, local by default (a LocalCluster on
this machine's cores) or a scheduler address; one table (CSV, Parquet)
and a plot.

Each run gives, for every selected output, its peak |value| (column
"peak:<output>"), its final value ("final:<output>"), and whether it
ended in fmi2Discard; a Python caller may give its own metrics."""
import argparse
import hashlib
import itertools
import os
import pathlib
import sys
import tempfile
import time

import numpy as np

from . import run as runner

EPILOG = """examples:
  sweep.py build/fmus/flexible_slider_crank.fmu --grid rod.damping=0:2e-4:5 --grid E=1e11:3e11:4 \\
      --output rod.node4.position.y --out out/sweep
  sweep.py FMU --random angle0=-1:1 --samples 50 --seed 1 --scheduler tcp://host:8786"""


def grid_values(spec):
    """'name=a:b:n' (n values from a to b) or 'name=v1,v2,...'."""
    name, _, text = spec.partition("=")
    try:
        if ":" in text:
            a, b, n = text.split(":")
            return name, list(np.linspace(float(a), float(b), int(n)))
        return name, [float(x) for x in text.split(",")]
    except ValueError:
        raise ValueError(f"--grid '{spec}': expected name=a:b:n or name=v1,v2,...") from None


def random_range(spec):
    name, _, text = spec.partition("=")
    try:
        a, b = (float(x) for x in text.split(":"))
    except ValueError:
        raise ValueError(f"--random '{spec}': expected name=a:b") from None
    return name, (a, b)


def samples(grid=(), random=(), count=0, seed=0):
    """[{name: value}]: the full grid, or count uniform random samples."""
    if grid and random:
        raise ValueError("give --grid or --random, not both")
    if grid:
        names = [g[0] for g in grid]
        return [dict(zip(names, combo)) for combo in itertools.product(*[g[1] for g in grid])]
    rng = np.random.default_rng(seed)
    return [{name: float(rng.uniform(a, b)) for name, (a, b) in random} for _ in range(count)]


def local_fmu(data, digest):
    """The FMU's bytes as a file on this worker (written once per worker)."""
    path = pathlib.Path(tempfile.gettempdir()) / f"mfbd-sweep-{digest}.fmu"
    if not path.exists():
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_bytes(data)
        tmp.replace(path)
    return path


def one_run(data, digest, parameters, outputs, stop_time, step, metrics):
    """One task: one FMU instance, one run; a row of the table."""
    fmu = local_fmu(data, digest)
    row = dict(parameters)
    start = time.perf_counter()
    try:
        result = runner.simulate(fmu, parameters, outputs, stop_time, step, progress=False)
    except (ValueError, RuntimeError) as e:
        return {**row, "truncated": True, "error": str(e)}
    wall = time.perf_counter() - start
    for name, y in result.values.items():
        row[f"peak:{name}"] = float(np.max(np.abs(y)))
        row[f"final:{name}"] = float(y[-1])
    for label, metric in (metrics or {}).items():
        row[label] = float(metric(result))
    row["truncated"] = result.truncated
    row["error"] = result.message
    row["wall_time_s"] = wall
    return row


def run_sweep(fmu, points, outputs=None, stop_time=None, step=None, metrics=None, scheduler=None,
              workers=None, progress=True):
    """Rows in the order of points. scheduler: an address, or None for a
    LocalCluster of one single-threaded worker process per core (an FMU
    instance per task, tasks in parallel processes)."""
    from dask.distributed import Client, LocalCluster, as_completed
    data = pathlib.Path(fmu).read_bytes()
    digest = hashlib.sha256(data).hexdigest()[:16]
    cluster = None
    if scheduler is None:
        cluster = LocalCluster(n_workers=workers or os.cpu_count(), threads_per_worker=1, processes=True,
                               dashboard_address=":0")  # any free port
    client = Client(scheduler or cluster)
    try:
        shared = client.scatter(data, broadcast=True)
        futures = [client.submit(one_run, shared, digest, p, outputs, stop_time, step, metrics, pure=False)
                   for p in points]
        index = {f.key: i for i, f in enumerate(futures)}
        rows = [None] * len(points)
        bar = None
        if progress:
            from tqdm import tqdm
            bar = tqdm(total=len(points), file=sys.stderr, unit="run", desc="sweep")
        for future in as_completed(futures):
            rows[index[future.key]] = future.result()
            if bar:
                bar.update(1)
        if bar:
            bar.close()
        return rows
    finally:
        client.close()
        if cluster:
            cluster.close()


def write_table(rows, path):
    """CSV (or Parquet by suffix) with one row per run."""
    columns = list(dict.fromkeys(k for r in rows for k in r))
    path = pathlib.Path(path)
    if path.suffix == ".parquet":
        import pyarrow as pa
        import pyarrow.parquet as pq
        pq.write_table(pa.table({c: [r.get(c) for r in rows] for c in columns}), path)
        return
    import csv
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, columns)
        w.writeheader()
        w.writerows(rows)


def plot_sweep(rows, x, y, path, colour=None, units=None):
    """y against x, coloured by another parameter if there are two."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    units = units or {}
    ok = [r for r in rows if not r.get("truncated")]
    fig, ax = plt.subplots(figsize=(7.5, 4.6), layout="constrained")
    xs, ys = np.array([r[x] for r in ok]), np.array([r[y] for r in ok])
    if colour:
        cs = np.array([r[colour] for r in ok])
        points = ax.scatter(xs, ys, c=cs, s=18, cmap="viridis")
        fig.colorbar(points, ax=ax, label=f"{colour} [{units.get(colour) or '1'}]")
    else:
        ax.plot(xs[np.argsort(xs)], ys[np.argsort(xs)], "o-", ms=4)
    failed = len(rows) - len(ok)
    ax.set(xlabel=f"{x} [{units.get(x) or '1'}]", ylabel=f"{y} [{units.get(y) or '1'}]")
    ax.set_title(f"{len(ok)} runs" + (f", {failed} discarded (not shown)" if failed else ""), fontsize=9)
    ax.grid(True, alpha=0.3)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def parser():
    p = argparse.ArgumentParser(prog="sweep", description=__doc__, epilog=EPILOG,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("fmu", type=pathlib.Path)
    p.add_argument("--grid", action="append", default=[], metavar="NAME=A:B:N", help="grid axis (repeatable)")
    p.add_argument("--random", action="append", default=[], metavar="NAME=A:B", help="uniform range (repeatable)")
    p.add_argument("--samples", type=int, default=0, help="--random: number of runs")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--output", "-o", nargs="+", required=True, metavar="NAME",
                   help="outputs whose peak |value| and final value each run reports (names or globs)")
    p.add_argument("--stop-time", type=float)
    p.add_argument("--step", type=float, help="communication step, s")
    p.add_argument("--scheduler", help="a Dask scheduler address (default: a LocalCluster on this machine)")
    p.add_argument("--workers", type=int, help="LocalCluster worker processes (default: the cores)")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out/sweep"))
    p.add_argument("--parquet", action="store_true", help="also write sweep.parquet")
    p.add_argument("--quiet", "-q", action="store_true")
    return p


def main(argv=None):
    args = parser().parse_args(argv)
    try:
        grid = [grid_values(g) for g in args.grid]
        random = [random_range(r) for r in args.random]
        points = samples(grid, random, args.samples, args.seed)
        if not points:
            raise ValueError("nothing to run: give --grid, or --random with --samples N")
        from fmpy import read_model_description
        md = read_model_description(str(args.fmu))
        units = runner.variable_units(md)
        names = [v.name for v in md.modelVariables if v.causality == "output"]
        outputs = runner.select(names, args.output)
        known = {v.name for v in md.modelVariables if v.causality == "parameter"}
        for name in points[0]:
            if name not in known:
                raise ValueError(f"{name}: no such parameter of {md.modelName}")
    except ValueError as e:
        print(f"sweep: error: {e}", file=sys.stderr)
        return 1
    rows = run_sweep(args.fmu, points, outputs, args.stop_time, args.step, scheduler=args.scheduler,
                     workers=args.workers, progress=not args.quiet)
    args.out.mkdir(parents=True, exist_ok=True)
    write_table(rows, args.out / "sweep.csv")
    if args.parquet:
        write_table(rows, args.out / "sweep.parquet")
    params = list(points[0])
    units.update({f"peak:{n}": units.get(n, "") for n in outputs})
    plot_sweep(rows, params[0], f"peak:{outputs[0]}", args.out / "sweep.png", params[1] if len(params) > 1 else None,
               units)
    failed = sum(bool(r.get("truncated")) for r in rows)
    print(f"sweep: {len(rows)} runs, {failed} discarded; wrote {(args.out / 'sweep.csv').resolve()} and sweep.png")
    return 3 if failed else 0
