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
import numpy as np

from peer_common import EXUDYN, OURS, FmuRun, Panel, PeerStudy, cantilever_scene, exudyn_beam_line_2d, \
    exudyn_clamp_coordinates, exudyn_settings, exudyn_solve

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
    scene = cantilever_scene("cantilever_moment", n)
    scene["solver"]["h_max"] = LAMBDA / LOAD_STEPS
    return scene


def ours(fmu, n):
    run = FmuRun(fmu, {"solver.tolerance": 1e-10})  # the scene's, as Exudyn's static solve
    (x, y), wall, statistics = run.at_end([f"beam.node{n}.position.x", f"beam.node{n}.position.y"], LAMBDA, LAMBDA)
    return dict(wall_time_s=wall, error=tip_error(x, y), coordinates=6 * (n + 1), **statistics)


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


def exudyn_static(build, n, per_node):
    import exudyn as exu

    sparse = n >= 32  # Exudyn's faster linear solver at each size (dense LU below)
    mbs, tip = build(n, sparse)
    mbs.Assemble()
    settings = exudyn_settings(static=True, tolerance=1e-10, sparse=sparse)
    settings.staticSolver.numberOfLoadSteps = LOAD_STEPS
    wall, statistics = exudyn_solve(mbs, settings, static=True)
    p = mbs.GetNodeOutput(tip, exu.OutputVariableType.Position)
    return dict(wall_time_s=wall, error=tip_error(p[0], p[1]), coordinates=per_node * (n + 1), **statistics)


class Study(PeerStudy):
    label, name, repeats = "F1", "f1_end_moment", 3
    settings, xlabel = ELEMENTS, "wall time of the static solve (5 load steps) [s]"

    def codes(self):
        fmus = {n: self.pack(scene_with_elements(n), f"moment{n}") for n in self.settings}
        return [(OURS, "3D corotational beam", lambda n: ours(fmus[n], n)),
                (EXUDYN, "BeamGeometricallyExact2D", lambda n: exudyn_static(exudyn_beam_2d, n, 3)),
                (EXUDYN, "BeamGeometricallyExact 3D (EP nodes)", lambda n: exudyn_static(exudyn_beam_3d, n, 7))]

    def panels(self, tables):
        return [Panel("tip position error at load factor 0.25 [m]",
                      "F1 end moment: error against run time (labels: elements; errors < 1e-10 drawn at 1e-10)",
                      floor=1e-10)]


if __name__ == "__main__":
    Study().main(__doc__)
