#!/usr/bin/env python3
"""R1 pendulum, our FMU against Exudyn: error of the bob position at t = 10 s
against the published value (shared/benchmarks R1) over substeps
h = 1e-2 ... 5e-5, and the wall time of the 10 s run.

Both codes use Lie-group / Arnold-Bruls generalized-alpha with rho_inf = 0.8
(the pendulum scene's default). Newton stops on the increment (ours: largest
position increment 1e-12; Exudyn KinematicTree: increment norm 1e-12) or, for
the Exudyn mass point, on the residual (see peer_common.exudyn_settings).

Ours: build/fmus/pendulum.fmu (a point mass on a revolute joint, one joint
coordinate), communication step 0.1 s.

Exudyn, two models of the same physics:
  * KinematicTree: one RevoluteZ link of mass 1 kg with its centre of mass
    1 m from the axis and zero inertia about it -- minimal (joint)
    coordinates, the same formulation as ours;
  * MassPoint2D + ConnectorDistance: a 1 kg point in the plane held at 1 m
    from the ground point by an index-3 distance constraint (redundant
    coordinates and a Lagrange multiplier).
Writes r1_pendulum_precision.csv and .png.
"""
import numpy as np

from peer_common import (EXUDYN, FMUS, OURS, FmuRun, Panel, PeerStudy, exudyn_explicit_settings, exudyn_settings,
                         exudyn_solve)

G, L, MASS, STOP = 9.81, 1.0, 1.0, 10.0
R1_AT_10S = (0.275087462576, -0.961419205099)
STEPS = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5]
RHO_INF = 0.8
# The error-controlled runs (ours and Exudyn's adaptive explicit solvers)
# over tolerances, Exudyn's RK44 over fixed steps.
TOLERANCES = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
RK44_STEPS = [0.1, 5e-2, 2e-2, 1e-2, 5e-3, 2e-3]


def position_error(x, y):
    return float(np.hypot(x - R1_AT_10S[0], y - R1_AT_10S[1]))


def ours(fmu, h, communication=0.1):
    run = FmuRun(fmu, {"solver.h_max": h, "solver.rho_inf": RHO_INF})
    (x, y), wall, statistics = run.at_end(["bob.position.x", "bob.position.y"], STOP, communication)
    return dict(wall_time_s=wall, error=position_error(x, y), rho_inf=RHO_INF, **statistics)


def ours_by_tolerance(fmu, tolerance, communication=0.1):
    """Driven by an error tolerance (fmi2SetupExperiment): the integrator
    the FMU chooses (a rigid, non-stiff scene: Dormand-Prince 5(4)), h_max
    the communication step."""
    run = FmuRun(fmu, {"solver.h_max": communication}, tolerance=tolerance)
    (x, y), wall, statistics = run.at_end(["bob.position.x", "bob.position.y"], STOP, communication)
    return dict(wall_time_s=wall, error=position_error(x, y), tolerance=tolerance, **statistics)


def exudyn_kinematic_tree(h, solver=None, tolerance=None):
    import exudyn as exu
    from exudyn.itemInterface import NodeGenericODE2, ObjectKinematicTree

    mbs = exu.SystemContainer().AddSystem()
    node = mbs.AddNode(NodeGenericODE2(numberOfODE2Coordinates=1, referenceCoordinates=[0.0],
                                       initialCoordinates=[0.0], initialCoordinates_t=[0.0]))
    mbs.AddObject(ObjectKinematicTree(
        nodeNumber=node, jointTypes=[exu.JointType.RevoluteZ], linkParents=[-1],
        jointTransformations=exu.Matrix3DList([np.eye(3)]), jointOffsets=exu.Vector3DList([[0.0, 0.0, 0.0]]),
        linkInertiasCOM=exu.Matrix3DList([np.zeros((3, 3))]), linkCOMs=exu.Vector3DList([[L, 0.0, 0.0]]),
        linkMasses=[MASS], gravity=[0.0, -G, 0.0]))
    mbs.Assemble()
    settings = (exudyn_explicit_settings(solver, STOP, h, tolerance) if solver
                else exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF))
    wall, statistics = exudyn_solve(mbs, settings)
    angle = mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates)
    angle = float(np.ravel(angle)[0])
    return dict(wall_time_s=wall, error=position_error(L * np.cos(angle), L * np.sin(angle)),
                **(dict(solver=solver, tolerance=tolerance or "") if solver else dict(rho_inf=RHO_INF)), **statistics)


def exudyn_mass_point(h):
    import exudyn as exu
    from exudyn.itemInterface import (LoadForceVector, MarkerBodyPosition, MarkerNodePosition, NodePoint2D,
                                      ObjectConnectorDistance, ObjectGround, ObjectMassPoint2D)

    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.AddObject(ObjectGround())
    node = mbs.AddNode(NodePoint2D(referenceCoordinates=[L, 0.0]))
    mbs.AddObject(ObjectMassPoint2D(mass=MASS, nodeNumber=node))
    pivot = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    bob = mbs.AddMarker(MarkerNodePosition(nodeNumber=node))
    mbs.AddObject(ObjectConnectorDistance(markerNumbers=[pivot, bob], distance=L))
    mbs.AddLoad(LoadForceVector(markerNumber=bob, loadVector=[0.0, -MASS * G, 0.0]))
    mbs.Assemble()
    settings = exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF, residual_criterion=True)
    wall, statistics = exudyn_solve(mbs, settings)
    p = mbs.GetNodeOutput(node, exu.OutputVariableType.Position)
    return dict(wall_time_s=wall, error=position_error(p[0], p[1]), rho_inf=RHO_INF, **statistics)


class Study(PeerStudy):
    label, name, repeats, fmu = "R1", "r1_pendulum", 3, FMUS / "pendulum.fmu"
    settings, xlabel = STEPS, "wall time for 10 s simulated [s]"

    def codes(self):
        return [(OURS, "revolute joint, joint coordinate", lambda h: ours(self.args.fmu, h)),
                (OURS, "by tolerance (Dormand-Prince 5(4))", lambda tol: ours_by_tolerance(self.args.fmu, tol),
                 TOLERANCES),
                (EXUDYN, "KinematicTree RevoluteZ (joint coordinate)", exudyn_kinematic_tree),
                (EXUDYN, "MassPoint2D + ConnectorDistance (index 3)", exudyn_mass_point),
                (EXUDYN, "KinematicTree, RK44", lambda h: exudyn_kinematic_tree(h, "RK44"), RK44_STEPS),
                (EXUDYN, "KinematicTree, DOPRI5 by tolerance",
                 lambda tol: exudyn_kinematic_tree(None, "DOPRI5", tol), TOLERANCES),
                (EXUDYN, "KinematicTree, ODE23 by tolerance",
                 lambda tol: exudyn_kinematic_tree(None, "ODE23", tol), TOLERANCES)]

    def panels(self, tables):
        return [Panel("bob position error at t = 10 s [m]",
                      f"R1 pendulum: error against run time (generalized-alpha, rho_inf = {RHO_INF}; labels: h)")]


if __name__ == "__main__":
    Study().main(__doc__)
