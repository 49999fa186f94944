#!/usr/bin/env python3
"""F1 pure end moment (static), our FMU against Exudyn: tip position error at
load factor 0.25 (M = pi/2 EI/L, phi = pi/2) against the exact circle
x/L = sin(phi)/phi, y/L = (1 - cos(phi))/phi, over 2 ... 128 elements, and
the wall time of the load-stepped static solve.

Same data for every code: L = 1, EI = 1, EA = 1e7 EI/L^2, clamped root, a
moment about z at the tip, 5 equal load steps to load factor 0.25 (our scene
steps the load factor = time with h_max 0.05), full Newton, increment
tolerance 1e-10.

Ours: examples/cantilever_moment (3D two-node corotational beam, shear-rigid
because the scene gives no GA), packed per element count.
Exudyn, two elements:
  * ObjectBeamGeometricallyExact2D (2D Simo-Reissner, NodeRigidBody2D,
    3 coordinates per node; GA = EA, which a pure moment does not load);
  * ObjectBeamGeometricallyExact (3D, Euler-parameter nodes, 7 coordinates
    per node plus a normalisation constraint; GA = EA). It interpolates on
    SE(3), so a constant-curvature arc is in its solution space: its error is
    round-off at any element count (drawn at 1e-10 in the plot).
Writes f1_end_moment_precision.csv and .png.
"""
import time

import numpy as np

from peer_common import EXUDYN, OURS, FmuRun, SceneFactory, best_of, exudyn_beam_line_2d, exudyn_clamp_coordinates, \
    exudyn_settings, exudyn_solve, figure, load_scene, plot_precision_work, read_csv, save_figure, study_arguments, \
    write_csv

L, EI = 1.0, 1.0
EA = 1e7 * EI / L**2
LAMBDA = 0.25
LOAD_STEPS = 5
ELEMENTS = [2, 4, 8, 16, 32, 64, 128]
PHI = 2 * np.pi * LAMBDA
EXACT_TIP = (L * np.sin(PHI) / PHI, L * (1 - np.cos(PHI)) / PHI)


def tip_error(x, y):
    return float(np.hypot(x - EXACT_TIP[0], y - EXACT_TIP[1]))


def scene_with_elements(n):
    scene = load_scene("cantilever_moment")
    body = scene["flexible_bodies"][0]
    body["beam"]["elements"] = n
    body["loads"] = [dict(load, node=n) for load in body["loads"]]
    body["outputs"] = {"nodes": [n]}
    scene["solver"]["h_max"] = LAMBDA / LOAD_STEPS
    return scene


def ours(fmu, n):
    run = FmuRun(fmu, {"solver.tolerance": 1e-10})  # the scene's, as Exudyn's static solve
    try:
        start = time.perf_counter()
        run.initialize()
        run.step(LAMBDA)
        wall = time.perf_counter() - start
        x, y = run.get(f"beam.node{n}.position.x", f"beam.node{n}.position.y")
        statistics = run.statistics()
    finally:
        run.free()
    return dict(wall_time_s=wall, error=tip_error(x, y), **statistics)


def exudyn_beam_2d(n, sparse):
    import exudyn as exu
    from exudyn.itemInterface import LoadTorqueVector, MarkerNodeRigid

    mbs = exu.SystemContainer().AddSystem()
    nodes = exudyn_beam_line_2d(mbs, n, L, 1.0, 1e-4, EI, EA, EA)
    exudyn_clamp_coordinates(mbs, nodes[0], 3)
    tip = mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[-1]))
    mbs.AddLoad(LoadTorqueVector(markerNumber=tip, loadVector=[0.0, 0.0, LAMBDA * 2 * np.pi * EI / L]))
    return mbs, nodes[-1]


def exudyn_beam_3d(n, sparse):
    import exudyn as exu
    from exudyn.itemInterface import LoadTorqueVector, MarkerBodyRigid, MarkerNodeRigid, NodeRigidBodyEP, \
        ObjectBeamGeometricallyExact, ObjectGround, ObjectJointGeneric

    mbs = exu.SystemContainer().AddSystem()
    section = exu.BeamSection()
    section.stiffnessMatrix = np.diag([EA, EA, EA, EI, EI, EI])  # EA, GAy, GAz, GJ, EIy, EIz
    section.massPerLength = 1.0
    section.inertia = np.diag([1e-4, 1e-4, 1e-4])
    nodes = [mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[L * i / n, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]))
             for i in range(n + 1)]
    for i in range(n):
        mbs.AddObject(ObjectBeamGeometricallyExact(nodeNumbers=[nodes[i], nodes[i + 1]], length=L / n,
                                                   sectionData=section))
    ground = mbs.AddMarker(MarkerBodyRigid(bodyNumber=mbs.AddObject(ObjectGround())))
    root = mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[0]))
    mbs.AddObject(ObjectJointGeneric(markerNumbers=[ground, root], constrainedAxes=[1] * 6))
    tip = mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[-1]))
    mbs.AddLoad(LoadTorqueVector(markerNumber=tip, loadVector=[0.0, 0.0, LAMBDA * 2 * np.pi * EI / L]))
    return mbs, nodes[-1]


def exudyn_static(build, n):
    import exudyn as exu

    sparse = n >= 32  # Exudyn's faster linear solver at each size (dense LU below)
    mbs, tip = build(n, sparse)
    mbs.Assemble()
    settings = exudyn_settings(static=True, tolerance=1e-10, sparse=sparse)
    settings.staticSolver.numberOfLoadSteps = LOAD_STEPS
    wall, statistics = exudyn_solve(mbs, settings, static=True)
    p = mbs.GetNodeOutput(tip, exu.OutputVariableType.Position)
    return dict(wall_time_s=wall, error=tip_error(p[0], p[1]), **statistics)


def run_study(args):
    """Runs every code of the study; its rows."""
    factory = SceneFactory()
    try:
        fmus = {n: factory.fmu(scene_with_elements(n), f"moment{n}") for n in ELEMENTS}
        codes = [(OURS, "3D corotational beam", 6, lambda n: ours(fmus[n], n)),
                 (EXUDYN, "BeamGeometricallyExact2D", 3, lambda n: exudyn_static(exudyn_beam_2d, n)),
                 (EXUDYN, "BeamGeometricallyExact 3D (EP nodes)", 7, lambda n: exudyn_static(exudyn_beam_3d, n))]
        rows = []
        for code, model, per_node, run in codes:
            for n in ELEMENTS:
                r = best_of(lambda: run(n), args.repeats)
                rows.append(dict(code=code, h_or_elements=n, wall_time_s=r["wall_time_s"], error=r["error"],
                                 model=model, coordinates=per_node * (n + 1), load_steps=r["steps"],
                                 newton_iterations=r["newton_iterations"],
                                 factorizations=r.get("factorizations", ""),
                                 rejected_steps=r.get("rejected_steps", "")))
                print(f"F1 {code:9s} {model:38s} n={n:4d}  wall {r['wall_time_s'] * 1e3:9.2f} ms  "
                      f"tip error {r['error']:9.2e} m  load steps {r['steps']}  Newton iterations "
                      f"{r['newton_iterations']}", flush=True)
    finally:
        factory.close()
    return rows


def main():
    args = study_arguments(__doc__, repeats=3)
    csv_path = args.out / "f1_end_moment_precision.csv"
    if args.replot:
        rows = read_csv(csv_path)
    else:
        rows = run_study(args)
        write_csv(csv_path, rows)

    fig, ax = figure()
    plot_precision_work(ax, rows, floor=1e-10)
    ax.set_xlabel("wall time of the static solve (5 load steps) [s]")
    ax.set_ylabel("tip position error at load factor 0.25 [m]")
    ax.set_title("F1 end moment: error against run time (labels: elements; errors < 1e-10 drawn at 1e-10)", fontsize=9)
    png = args.out / "f1_end_moment_precision.png"
    save_figure(fig, png)


if __name__ == "__main__":
    main()
