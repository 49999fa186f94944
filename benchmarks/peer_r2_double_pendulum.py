#!/usr/bin/env python3
"""R2 double pendulum, our FMU against Exudyn: two uniform bars (1 kg, 1 m)
on revolute joints, released at rest from horizontal, 10 s. The motion is
chaotic, so trajectories are not compared; the metrics are
  * error: the total energy drift, max over the samples of |E(t) - E(0)|
    in units of m g L (E(0) = 0: both bars start at y = 0 at rest);
  * constraint_drift: the largest distance between a joint's point seen
    from its two bodies (or from ground), m; identically round-off for
    joint-coordinate models, the index-3 drift of Exudyn's redundant one.
over substeps h = 1e-2 ... 1e-4, and the wall time of the 10 s run.
Energy and joint points are sampled every 0.01 s in both codes (our
communication step; Exudyn's sensor period).

Both codes use generalized-alpha with rho_inf = 1 (no numerical
dissipation: it would show up as energy drift), except Exudyn's redundant
model: at rho_inf = 1 its Newton stalls from t = 3.4 s on (h = 1e-2: the
increment stops shrinking at 1e-11 ... 1e-14 relative, the step is cut
to 1e-6 and the run crawls), so it runs at 0.95. Newton stops on
the increment: ours 1e-12 (largest position increment, with the
contraction estimate), Exudyn 1e-14: at 1e-12 its modified Newton stops
before it has converged at h <= 2e-4 (energy drift 1.0e-5 m g L at
h = 1e-4 against 2.6e-6 with full Newton); at 1e-14 it matches full Newton.

Ours: build/fmus/double_pendulum.fmu (two revolute joints, joint coordinates).
Exudyn, two models of the same physics:
  * KinematicTree: two RevoluteZ links, minimal (joint) coordinates, the
    same formulation as ours;
  * RigidBody2D + RevoluteJoint2D: redundant coordinates (x, y, angle per
    bar) and index-3 joint constraints with Lagrange multipliers.
Writes r2_double_pendulum_precision.csv and .png.
"""

import numpy as np

from peer_common import (EXUDYN, FMUS, OURS, FmuRun, Panel, PeerStudy, exudyn_explicit_settings, exudyn_settings,
                         exudyn_solve)

G, L, MASS, STOP, OUTPUT = 9.81, 1.0, 1.0, 10.0, 0.01
J = MASS * L * L / 12  # about the centre of mass, perpendicular to the bar
STEPS = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4]
RHO_INF = 1.0
RHO_INF_EXUDYN_REDUNDANT = 0.95
EXUDYN_TOLERANCE = 1e-14
MGL = MASS * G * L
# Error-controlled runs (ours, Exudyn's adaptive explicit solvers) over
# tolerances; Exudyn's RK44 over fixed steps.
TOLERANCES = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
RK44_STEPS = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4]


def energy(p, v, w):
    """p, v: (samples, bar, xy) centre-of-mass positions and velocities, w:
    (samples, bar) angular velocities -> total energy (samples,)."""
    return np.sum(0.5 * MASS * np.sum(v**2, axis=2) + 0.5 * J * w**2 + MASS * G * p[:, :, 1], axis=1)


def joint_points_drift(p, angle):
    """Largest mismatch of the shoulder (bar 1 end vs origin) and the elbow
    (bar 1 end vs bar 2 start), from centre-of-mass positions and bar angles."""
    d = 0.5 * L * np.stack([np.cos(angle), np.sin(angle)], axis=2)  # (samples, bar, xy)
    shoulder = np.linalg.norm(p[:, 0] - d[:, 0], axis=1)
    elbow = np.linalg.norm(p[:, 0] + d[:, 0] - (p[:, 1] - d[:, 1]), axis=1)
    return float(max(shoulder.max(), elbow.max()))


def metrics(p, v, w, angle):
    return dict(error=float(np.max(np.abs(energy(p, v, w)))) / MGL, constraint_drift=joint_points_drift(p, angle))


def ours(fmu, h, tolerance=None):
    """Substeps of h, or driven by an error tolerance (the integrator the
    FMU chooses, the Newton tolerance its own; h_max the largest step
    Exudyn's explicit solvers take, STOP / 100: sampled every OUTPUT, the
    substeps may step past the communication points while no input
    changes)."""
    parameters = ({"solver.h_max": STOP / 100} if tolerance else
                  {"solver.h_max": h, "solver.rho_inf": RHO_INF, "solver.tolerance": EXUDYN_TOLERANCE})
    run = FmuRun(fmu, parameters, tolerance=tolerance)
    names = [f"bar{i}.{q}.{c}" for i in (1, 2) for q in ("position", "velocity") for c in "xy"]
    names += ["bar1.angular_velocity.z", "bar2.angular_velocity.z", "shoulder.angle", "elbow.angle"]
    s, wall, statistics = run.sample(names, STOP, OUTPUT)
    p = s[:, [0, 1, 4, 5]].reshape(-1, 2, 2)
    v = s[:, [2, 3, 6, 7]].reshape(-1, 2, 2)
    angle = np.column_stack([s[:, 10], s[:, 10] + s[:, 11]])
    return dict(wall_time_s=wall, **metrics(p, v, s[:, 8:10], angle), **statistics,
                **({"tolerance": tolerance} if tolerance else {"rho_inf": RHO_INF}))


def exudyn_kinematic_tree(h, solver=None, tolerance=None):
    import exudyn as exu
    from exudyn.itemInterface import NodeGenericODE2, ObjectKinematicTree, SensorNode

    mbs = exu.SystemContainer().AddSystem()
    node = mbs.AddNode(NodeGenericODE2(numberOfODE2Coordinates=2, referenceCoordinates=[0.0, 0.0],
                                       initialCoordinates=[0.0, 0.0], initialCoordinates_t=[0.0, 0.0]))
    inertia = np.diag([0.0, J, J])
    mbs.AddObject(ObjectKinematicTree(
        nodeNumber=node, jointTypes=[exu.JointType.RevoluteZ] * 2, linkParents=[-1, 0],
        jointTransformations=exu.Matrix3DList([np.eye(3)] * 2),
        jointOffsets=exu.Vector3DList([[0.0, 0.0, 0.0], [L, 0.0, 0.0]]),
        linkInertiasCOM=exu.Matrix3DList([inertia] * 2), linkCOMs=exu.Vector3DList([[L / 2, 0.0, 0.0]] * 2),
        linkMasses=[MASS] * 2, gravity=[0.0, -G, 0.0]))
    sensors = [mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=kind, storeInternal=True,
                                        writeToFile=False))
               for kind in (exu.OutputVariableType.Coordinates, exu.OutputVariableType.Coordinates_t)]
    mbs.Assemble()
    settings = (exudyn_explicit_settings(solver, STOP, h, tolerance, sensor_period=OUTPUT) if solver else
                exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF, tolerance=EXUDYN_TOLERANCE,
                                sensor_period=OUTPUT))
    wall, statistics = exudyn_solve(mbs, settings)
    q, qd = (mbs.GetSensorStoredData(s)[:, 1:3] for s in sensors)
    # Centre-of-mass kinematics of the two links from the joint coordinates.
    angle = np.cumsum(q, axis=1)
    rate = np.cumsum(qd, axis=1)
    e = np.stack([np.cos(angle), np.sin(angle)], axis=2)
    n = np.stack([-np.sin(angle), np.cos(angle)], axis=2)
    p = np.stack([0.5 * L * e[:, 0], L * e[:, 0] + 0.5 * L * e[:, 1]], axis=1)
    v = np.stack([0.5 * L * rate[:, [0]] * n[:, 0], L * rate[:, [0]] * n[:, 0] + 0.5 * L * rate[:, [1]] * n[:, 1]],
                 axis=1)
    return dict(wall_time_s=wall, **metrics(p, v, rate, angle), **statistics,
                **(dict(solver=solver, tolerance=tolerance or "") if solver else {"rho_inf": RHO_INF}))


def exudyn_rigid_bodies(h):
    import exudyn as exu
    from exudyn.itemInterface import LoadMassProportional, MarkerBodyMass, MarkerBodyPosition, NodeRigidBody2D, \
        ObjectGround, ObjectJointRevolute2D, ObjectRigidBody2D, SensorBody

    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.AddObject(ObjectGround())
    bodies = []
    for i in range(2):
        node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[(i + 0.5) * L, 0.0, 0.0]))
        bodies.append(mbs.AddObject(ObjectRigidBody2D(mass=MASS, inertia=J, nodeNumber=node)))
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=bodies[-1])),
                                         loadVector=[0.0, -G, 0.0]))
    pairs = [(ground, [0.0, 0.0, 0.0], bodies[0], [-L / 2, 0.0, 0.0]),
             (bodies[0], [L / 2, 0.0, 0.0], bodies[1], [-L / 2, 0.0, 0.0])]
    for a, pa, b, pb in pairs:
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
            mbs.AddMarker(MarkerBodyPosition(bodyNumber=a, localPosition=pa)),
            mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=pb))]))
    kinds = (exu.OutputVariableType.Position, exu.OutputVariableType.Velocity,
             exu.OutputVariableType.AngularVelocity, exu.OutputVariableType.Rotation)
    sensors = [[mbs.AddSensor(SensorBody(bodyNumber=b, outputVariableType=k, storeInternal=True, writeToFile=False))
                for k in kinds] for b in bodies]
    mbs.Assemble()
    settings = exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF_EXUDYN_REDUNDANT, tolerance=EXUDYN_TOLERANCE,
                               sensor_period=OUTPUT)
    wall, statistics = exudyn_solve(mbs, settings)
    data = [[mbs.GetSensorStoredData(s) for s in per_body] for per_body in sensors]
    p = np.stack([d[0][:, 1:3] for d in data], axis=1)
    v = np.stack([d[1][:, 1:3] for d in data], axis=1)
    w = np.column_stack([d[2][:, 3] for d in data])
    angle = np.column_stack([d[3][:, -1] for d in data])
    return dict(wall_time_s=wall, **metrics(p, v, w, angle), rho_inf=RHO_INF_EXUDYN_REDUNDANT, **statistics)


class Study(PeerStudy):
    label, name, repeats, fmu = "R2", "r2_double_pendulum", 3, FMUS / "double_pendulum.fmu"
    settings, xlabel = STEPS, "wall time for 10 s simulated [s]"

    def codes(self):
        return [(OURS, "two revolute joints, joint coordinates", lambda h: ours(self.args.fmu, h)),
                (OURS, "by tolerance (Dormand-Prince 5(4))", lambda tol: ours(self.args.fmu, None, tol),
                 TOLERANCES),
                (EXUDYN, "KinematicTree 2 x RevoluteZ (joint coordinates)", exudyn_kinematic_tree),
                (EXUDYN, "KinematicTree, RK44", lambda h: exudyn_kinematic_tree(h, "RK44"), RK44_STEPS),
                (EXUDYN, "KinematicTree, DOPRI5 by tolerance",
                 lambda tol: exudyn_kinematic_tree(None, "DOPRI5", tol), TOLERANCES),
                (EXUDYN, "KinematicTree, ODE23 by tolerance",
                 lambda tol: exudyn_kinematic_tree(None, "ODE23", tol), TOLERANCES),
                (EXUDYN, f"RigidBody2D + RevoluteJoint2D (index 3, rho_inf {RHO_INF_EXUDYN_REDUNDANT})",
                 exudyn_rigid_bodies)]

    def panels(self, tables):
        return [Panel("energy drift max |E(t) - E(0)| / (m g L)",
                      f"R2 double pendulum: energy drift against run time (rho_inf = {RHO_INF}; labels: h)"),
                Panel("constraint drift: largest joint-point mismatch [m]",
                      "R2: constraint drift (round-off in joint coordinates)", "constraint_drift", 1e-17)]


if __name__ == "__main__":
    Study().main(__doc__)
