#!/usr/bin/env python3
"""Per-step cost of an n-body pendulum chain through the FMU, beside Exudyn's
KinematicTree (issue 3: "per-step cost of an n-body chain grows linearly in
n, n = 2..200, plotted").

The chain: n uniform bars of 1 m and 1 kg each (R2 is n = 2) on revolute
joints about z, released at rest from horizontal under gravity -y; 0.2 s
with substeps h = 1e-3 and communication steps of 0.01 s (200 substeps),
rho_inf = 0.8. Unit bars, not chain_cost.py's 1/n m ones: a chain of n
bars 1/n m long stiffens as n grows, and at h = 1e-3 both codes then
struggle (n = 200: Exudyn cuts its step to 2,745 steps instead of 200 and
takes 160 s a run, we reject 117 of 317 substeps at 11.5 Newton iterations
each), which measures step control, not the cost of a step.

  * Ours, through the FMU (fmpy; fmi2EnterInitializationMode .. the last
    fmi2DoStep timed), the scene packed by build/mfbd-pack with no outputs
    but the last bar: wall time per substep, Newton iterations and
    factorizations per substep. Where that time goes: chain_cost.py takes
    one Newton iteration apart at each n (the cost of a residual, tangent,
    factorization or solve does not depend on the bars' length).
  * Exudyn KinematicTree (n RevoluteZ links, minimal coordinates, the same
    formulation), same h and span, modified Newton on the increment 1e-12;
    its dense (EXUdense) and sparse (EigenSparse) solvers are both run and
    the faster is kept at each n.

The fitted exponent p of cost ~ n^p over n >= 20 is printed and written. A
study, not a test: nothing here asserts a time.
Writes peer_chain_cost.csv and peer_chain_cost.png.
"""
import csv

import numpy as np

from peer_common import EXUDYN, OURS, FmuRun, SceneFactory, best_of, exudyn_settings, exudyn_solve, figure, \
    legend_below, read_csv, save_figure, study_arguments

G, MASS, L = 9.81, 1.0, 1.0  # each bar
H, STOP, COMMUNICATION, RHO_INF = 1e-3, 0.2, 0.01, 0.8
SIZES = [2, 5, 10, 20, 50, 100, 150, 200]


def chain_scene(n):
    inertia = MASS * L * L / 12
    bodies = [{"name": f"bar{i}", "mass": MASS, "inertia": [0, inertia, inertia], "position": [(i + 0.5) * L, 0, 0]}
              for i in range(n)]
    joints = [{"name": f"hinge{i}", "type": "revolute", "parent": "ground" if i == 0 else f"bar{i - 1}",
               "child": f"bar{i}", "position": [i * L, 0, 0]} for i in range(n)]
    return {"format": "mfbd-scene/1", "name": f"chain{n}", "gravity": [0, -G, 0],
            "solver": {"h_max": H, "rho_inf": RHO_INF}, "bodies": bodies, "joints": joints,
            "outputs": {"bodies": [f"bar{n - 1}"], "joints": []}}


def ours(fmu):
    _, wall, statistics = FmuRun(fmu).at_end((), STOP, COMMUNICATION)
    return dict(wall_time_s=wall, **statistics)


def exudyn_chain(n, sparse):
    import exudyn as exu
    length, mass = L, MASS
    inertia = mass * length * length / 12
    from exudyn.itemInterface import NodeGenericODE2, ObjectKinematicTree

    mbs = exu.SystemContainer().AddSystem()
    node = mbs.AddNode(NodeGenericODE2(numberOfODE2Coordinates=n, referenceCoordinates=[0.0] * n,
                                       initialCoordinates=[0.0] * n, initialCoordinates_t=[0.0] * n))
    mbs.AddObject(ObjectKinematicTree(
        nodeNumber=node, jointTypes=[exu.JointType.RevoluteZ] * n, linkParents=list(range(-1, n - 1)),
        jointTransformations=exu.Matrix3DList([np.eye(3)] * n),
        jointOffsets=exu.Vector3DList([[0.0, 0.0, 0.0]] + [[length, 0.0, 0.0]] * (n - 1)),
        linkInertiasCOM=exu.Matrix3DList([np.diag([0.0, inertia, inertia])] * n),
        linkCOMs=exu.Vector3DList([[length / 2, 0.0, 0.0]] * n), linkMasses=[mass] * n, gravity=[0.0, -G, 0.0]))
    mbs.Assemble()
    settings = exudyn_settings(end_time=STOP, h=H, rho_inf=RHO_INF, sensor_period=None, sparse=sparse)
    wall, statistics = exudyn_solve(mbs, settings)
    return dict(wall_time_s=wall, **statistics)


def exponent(n, cost, lower=20):
    """Least-squares slope of log(cost) against log(n) over n >= lower."""
    n, cost = np.asarray(n, float), np.asarray(cost, float)
    sel = n >= lower
    return float(np.polyfit(np.log(n[sel]), np.log(cost[sel]), 1)[0])


def write_rows(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(dict.fromkeys(k for r in rows for k in r)))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    print(f"wrote {path.resolve()}")


def plot(rows, path, slopes):
    fig, ax = figure(figsize=(7.5, 5.2))
    for label, style in ((OURS, dict(color="C0", marker="o")), (EXUDYN, dict(color="C3", marker="s"))):
        sel = [r for r in rows if r["code"] == label]
        ax.loglog([r["n"] for r in sel], [r["us_per_step"] for r in sel], "-",
                  label=f"{label} ({sel[0]['model']}): ~n^{slopes[label]:.2f} for n >= 20", **style)
    n = np.array(SIZES, float)
    ours_cost = np.array([r["us_per_step"] for r in rows if r["code"] == OURS])
    for p, ls in ((1, "--"), (2, ":")):
        ax.loglog(n, ours_cost[-1] * (n / n[-1])**p, "k" + ls, lw=0.8, label=f"~n^{p}")
    ax.set_xlabel("bodies n")
    ax.set_ylabel("wall time per substep [µs]")
    ax.set_title(f"n-body pendulum chain, h = {H:g}, communication step {COMMUNICATION:g} s", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    legend_below(ax)
    save_figure(fig, path)


def main():
    args = study_arguments(__doc__, repeats=3, extra=[("--sizes", dict(type=int, nargs="+", default=SIZES))])
    if args.replot:
        rows = [{**r, "n": float(r["n"]), "us_per_step": float(r["us_per_step"])}
                for r in read_csv(args.out / "peer_chain_cost.csv")]
        slopes = {r["code"]: float(r["fitted_exponent_n_ge_20"]) for r in rows}
        return plot(rows, args.out / "peer_chain_cost.png", slopes)

    factory = SceneFactory()
    rows = []
    try:
        for n in args.sizes:
            fmu = factory.fmu(chain_scene(n), f"chain{n}")
            r = best_of(lambda: ours(fmu), args.repeats)
            steps = r["steps"]
            rows.append(dict(code=OURS, model="FMU, joint coordinates, automatic Newton matrix (recursive from n = 80)", n=n, us_per_step=1e6 * r["wall_time_s"] / steps,
                             wall_time_s=r["wall_time_s"], steps=steps,
                             newton_per_step=r["newton_iterations"] / steps, factorizations=r["factorizations"],
                             rejected_steps=r.get("rejected_steps", 0)))
            print(f"chain {OURS:9s} n={n:4d}  {rows[-1]['us_per_step']:10.1f} us/step  Newton it/step "
                  f"{rows[-1]['newton_per_step']:.2f}  factorizations {r['factorizations']}  "
                  f"rejected {r.get('rejected_steps', 0)}", flush=True)
        for n in args.sizes:
            best = None
            for sparse in (False, True):
                r = best_of(lambda: exudyn_chain(n, sparse), args.repeats)
                if best is None or r["wall_time_s"] < best[0]["wall_time_s"]:
                    best = (r, sparse)
            r, sparse = best
            steps = r["steps"]
            rows.append(dict(code=EXUDYN, model="KinematicTree", n=n, us_per_step=1e6 * r["wall_time_s"] / steps,
                             wall_time_s=r["wall_time_s"], steps=steps,
                             newton_per_step=r["newton_iterations"] / steps, factorizations=r["factorizations"],
                             linear_solver="EigenSparse" if sparse else "EXUdense"))
            print(f"chain {EXUDYN:9s} n={n:4d}  {rows[-1]['us_per_step']:10.1f} us/step  Newton it/step "
                  f"{rows[-1]['newton_per_step']:.2f}  factorizations {r['factorizations']}  "
                  f"({rows[-1]['linear_solver']})", flush=True)
    finally:
        factory.close()
    slopes = {code: exponent([r["n"] for r in rows if r["code"] == code],
                             [r["us_per_step"] for r in rows if r["code"] == code]) for code in (OURS, EXUDYN)}
    for r in rows:
        r["fitted_exponent_n_ge_20"] = slopes[r["code"]]
    write_rows(args.out / "peer_chain_cost.csv", rows)
    print(f"fitted exponent of the cost per substep (n >= 20): ours {slopes[OURS]:.2f}, Exudyn {slopes[EXUDYN]:.2f}")
    plot(rows, args.out / "peer_chain_cost.png", slopes)


if __name__ == "__main__":
    main()
