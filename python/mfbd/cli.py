"""`simulate`: run a packed scene with progress, then write what was asked:
CSV (and Parquet), a plot of the selected outputs, ParaView files, a
rendered frame, an animation."""
import argparse
import fnmatch
import pathlib
import sys

from . import run as runner

EPILOG = """examples:
  simulate.py build/fmus/pendulum.fmu --out out
  simulate.py build/fmus/pendulum.fmu --param angle0=0.5 --stop-time 5 --output 'hinge.*' 'bob.position.?'
  simulate.py build/fmus/flexible_slider_crank.fmu --vtk out/vtk --gif out/f5.gif
exit status: 0 done; 1 bad arguments or a failed run; 3 the run ended in fmi2Discard (results truncated)."""


def parser():
    p = argparse.ArgumentParser(prog="simulate", description=__doc__, epilog=EPILOG,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("fmu", type=pathlib.Path)
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out"), help="folder for CSV and PNG (default out)")
    p.add_argument("--param", "-p", action="append", default=[], metavar="NAME=VALUE",
                   help="set a parameter (repeatable), e.g. --param solver.h_max=1e-4")
    p.add_argument("--output", "-o", nargs="+", default=[], metavar="NAME",
                   help="outputs to record and plot: names or glob patterns (default: all)")
    p.add_argument("--stop-time", type=float, help="s (default: the scene's experiment)")
    p.add_argument("--step", "--output-interval", dest="step", type=float,
                   help="communication step, s (default: the scene's output_interval)")
    p.add_argument("--relative-tolerance", type=float, metavar="TOL",
                   help="error tolerance (fmi2SetupExperiment; default: the scene's experiment.tolerance; "
                        "0: none, substeps of solver.h_max)")
    p.add_argument("--tolerance", type=float, help="Newton tolerance (solver.tolerance)")
    p.add_argument("--parquet", action="store_true", help="also write NAME.parquet")
    p.add_argument("--no-plot", action="store_true")
    p.add_argument("--vtk", type=pathlib.Path, metavar="DIR", help="write a ParaView time series (.pvd + .vtu)")
    p.add_argument("--every", type=int, default=1, help="--vtk: every k-th output time")
    p.add_argument("--render", type=pathlib.Path, metavar="PNG", help="render the last frame offscreen")
    p.add_argument("--gif", "--animation", dest="animation", type=pathlib.Path, metavar="FILE",
                   help="animation, .gif or .mp4")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    p.add_argument("--verbose", "-v", action="store_true",
                   help="the FMU's debug log (logStep: substeps and Newton iterations per step) on stderr")
    return p


def main(argv=None):
    args = parser().parse_args(argv)
    try:
        return simulate_command(args)
    except (ValueError, RuntimeError, FileNotFoundError) as e:
        print(f"simulate: error: {e}", file=sys.stderr)
        return 1


def simulate_command(args):
    from .drawing import check_visuals, required_outputs
    from .scene import read_scene
    drawing_wanted = args.vtk or args.render or args.animation
    outputs = list(args.output)
    parameters = runner.parse_assignments(args.param)
    extra = []
    if drawing_wanted:
        check_visuals(args.fmu, parameters)
        extra = required_outputs(read_scene(args.fmu)[0]) if outputs else []
    result = runner.simulate(args.fmu, parameters, _with_drawing_outputs(args.fmu, outputs, extra),
                             args.stop_time, args.step, args.tolerance, progress=not args.quiet,
                             verbose=args.verbose, relative_tolerance=args.relative_tolerance)
    selected = runner.select(list(result.values), outputs) if outputs else list(result.values)
    _write_tables(args, result, selected)
    if drawing_wanted:
        _write_drawing(args, result)
    t = result.time
    print(f"simulate: {len(t)} output points, t = {t[0]:g} .. {t[-1]:g} s")
    if result.truncated:
        print(f"simulate: RUN TRUNCATED: {result.message}", file=sys.stderr)
        return 3
    return 0


def _with_drawing_outputs(fmu, user, extra):
    """The user's patterns plus those the drawing reads that the FMU has
    (a scene exposes only some bodies and nodes)."""
    if not user:
        return []  # all outputs
    from fmpy import read_model_description
    names = [v.name for v in read_model_description(str(fmu)).modelVariables if v.causality == "output"]
    return user + [p for p in extra if any(fnmatch.fnmatchcase(n, p) for n in names)]


def _write_tables(args, result, selected):
    from .plot import plot
    from .table import write_csv, write_parquet
    name = args.fmu.stem
    args.out.mkdir(parents=True, exist_ok=True)
    chosen = runner.Result(**{**result.__dict__, "values": {n: result.values[n] for n in selected}})
    write_csv(chosen, args.out / f"{name}.csv")
    print(f"simulate: wrote {(args.out / f'{name}.csv').resolve()}")
    if args.parquet:
        write_parquet(chosen, args.out / f"{name}.parquet")
        print(f"simulate: wrote {(args.out / f'{name}.parquet').resolve()}")
    if not args.no_plot:
        from .plot import default_selection
        plot(chosen, args.out / f"{name}.png", None if args.output else default_selection(chosen, selected))
        print(f"simulate: wrote {(args.out / f'{name}.png').resolve()}")


def _write_drawing(args, result):
    from .animate import render_animation, render_png
    from .drawing import Drawing
    from .paraview import write_series
    drawing = Drawing(args.fmu, result)
    if drawing.missing:
        print("simulate: not drawn (no position/orientation outputs; list them in the scene's "
              f"\"outputs\", nodes: \"all\" for a flexible body): {', '.join(drawing.missing)}", file=sys.stderr)
    if args.vtk:
        pvd = write_series(drawing, args.vtk, every=max(1, args.every), name=args.fmu.stem)
        print(f"simulate: wrote {pvd.resolve()} (open in ParaView)")
    if args.render:
        render_png(drawing, args.render)
        print(f"simulate: wrote {args.render.resolve()}")
    if args.animation:
        render_animation(drawing, args.animation)
        print(f"simulate: wrote {args.animation.resolve()}")
