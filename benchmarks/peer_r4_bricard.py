#!/usr/bin/env python3
"""R4 Bricard mechanism (IFToMM A04), our FMU against Exudyn: five uniform
rods (1 kg, 1 m, 0.1 m square) and six revolute joints, from rest under
gravity -y, 10 s. Grubler count 0, true mobility 1: one of the joint
constraints is redundant. The metrics:
  * error: the total energy drift, max over the samples of |E(t) - E(0)|
    in units of m g L (9.81 J);
  * constraint_drift: the largest violation of the six revolute joints,
    point mismatch (m) or axis misalignment (rad), from the bodies' poses.
over substeps h = 1e-2 ... 5e-4, and the wall time of the 10 s run;
energy and poses every 0.01 s in both codes.

Both codes: generalized-alpha, rho_inf = 1 (the scene's default: no
numerical dissipation in the energy).

Ours: build/fmus/bricard.fmu (a tree of five revolute joints in joint
coordinates, the sixth joint a cut joint with five constraint rows of which
one is redundant, found at the start and left out of the solve).
Newton: largest position increment 1e-12.

Exudyn: five rigid bodies (NodeRigidBodyEP: Euler parameters, 7
coordinates each with the Euler-parameter constraint) and six
JointRevoluteZ (five constraint rows each: 35 coordinates, 5 + 30 rows), the
redundant row kept as in ours. Exudyn cannot factorise the singular
Jacobian by default, so it runs as its own Bricard example does: dense LU
(EigenDense) with linearSolver.ignoreSingularJacobian = True (a zero pivot
is taken as a redundant equation); its EXUdense solver with the same flag
stops with "matrix is not factorized". Newton: increment 1e-14
(residualMode 1): at 1e-12 its modified Newton stops before it has
converged (energy drift 1.1e-5 m g L at h = 1e-3 against 6.5e-7 at 1e-14);
its residual test (relative 1e-8) fails at h = 1e-2, relative 1e-10
gives 2.9e-5 at h = 1e-3.
Writes r4_bricard_precision.csv and .png.
"""

import numpy as np
from scipy.spatial.transform import Rotation

from peer_common import EXUDYN, FMUS, OURS, FmuRun, Panel, PeerStudy, exudyn_settings, exudyn_solve

G, MASS, L, A, STOP, OUTPUT = 9.81, 1.0, 1.0, 0.1, 10.0, 0.01
POINTS = np.array([(0, 0, 0), (1, 0, 0), (1, -1, 0), (1, -1, 1), (0, -1, 1), (0, 0, 1)], dtype=float)
AXES = np.array([(0, 1, 0), (0, 0, 1), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 0)], dtype=float)
# Joint k connects body PARENT[k] to body CHILD[k] (rod indices 0..4, -1 = ground).
PARENT, CHILD = [-1, 0, 1, 2, 3, -1], [0, 1, 2, 3, 4, 4]
J_LOCAL = np.diag([MASS * 2 * A * A / 12, MASS * (L * L + A * A) / 12, MASS * (L * L + A * A) / 12])  # x along the rod
STEPS = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4]
RHO_INF = 1.0
EXUDYN_TOLERANCE = 1e-14
MGL = MASS * G * L


def design_frames():
    """Centre and rotation matrix (columns: body axes in world) of each rod,
    as examples/bricard/make_scene.py places them: x along the rod."""
    centres, rotations = [], []
    for i in range(5):
        x = POINTS[i + 1] - POINTS[i]
        other = np.array([0.0, 0, 1]) if abs(x[2]) < 0.5 else np.array([1.0, 0, 0])
        z = other - x * (other @ x)
        centres.append(0.5 * (POINTS[i] + POINTS[i + 1]))
        rotations.append(np.column_stack([x, np.cross(z, x), z]))
    return np.array(centres), np.array(rotations)


CENTRES0, ROTATIONS0 = design_frames()
E0 = MASS * G * np.sum(CENTRES0[:, 1])  # at rest


def energy(p, v, R, w):
    """p, v, w: (samples, rod, 3) world centre position, velocity, angular
    velocity; R: (samples, rod, 3, 3) body -> world."""
    inertia = np.einsum("nbij,jk,nblk->nbil", R, J_LOCAL, R)
    kinetic = 0.5 * MASS * np.sum(v**2, axis=(1, 2)) + 0.5 * np.einsum("nbi,nbij,nbj->n", w, inertia, w)
    return kinetic + MASS * G * np.sum(p[:, :, 1], axis=1)


def constraint_drift(p, R):
    """Largest joint violation over samples and joints: the joint point seen
    from both bodies (m) and the joint axis seen from both (rad)."""
    worst = 0.0
    for k in range(6):
        ends = []
        for b in (PARENT[k], CHILD[k]):
            if b < 0:
                ends.append((POINTS[k][None, :], AXES[k][None, :]))
            else:
                point_local = ROTATIONS0[b].T @ (POINTS[k] - CENTRES0[b])
                axis_local = ROTATIONS0[b].T @ AXES[k]
                ends.append((p[:, b] + R[:, b] @ point_local, R[:, b] @ axis_local))
        worst = max(worst, np.max(np.linalg.norm(ends[0][0] - ends[1][0], axis=1)),
                    np.max(np.linalg.norm(ends[0][1] - ends[1][1], axis=1)))
    return float(worst)


def metrics(p, v, R, w):
    return dict(error=float(np.max(np.abs(energy(p, v, R, w) - E0))) / MGL, constraint_drift=constraint_drift(p, R),
                rho_inf=RHO_INF, rod1_x_travel_m=float(np.ptp(p[:, 0, 0])))


def ours(fmu, h):
    run = FmuRun(fmu, {"solver.h_max": h, "solver.rho_inf": RHO_INF, "solver.tolerance": EXUDYN_TOLERANCE})
    rods = [f"rod{i}" for i in range(1, 6)]
    names = [f"{b}.{q}.{c}" for b in rods for q in ("position", "velocity", "angular_velocity") for c in "xyz"]
    names += [f"{b}.orientation.{c}" for b in rods for c in "xyzw"]
    s, wall, statistics = run.sample(names, STOP, OUTPUT)
    kinematics = s[:, :45].reshape(len(s), 5, 3, 3)  # sample, rod, quantity, xyz
    R = Rotation.from_quat(s[:, 45:].reshape(-1, 4)).as_matrix().reshape(len(s), 5, 3, 3)
    return dict(wall_time_s=wall, **metrics(kinematics[:, :, 0], kinematics[:, :, 1], R, kinematics[:, :, 2]),
                **statistics)


def exudyn_rigid_bodies(h):
    import exudyn as exu
    from exudyn.itemInterface import ObjectGround, SensorBody
    from exudyn.rigidBodyUtilities import RigidBodyInertia

    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.AddObject(ObjectGround())
    inertia = RigidBodyInertia(mass=MASS, inertiaTensor=J_LOCAL)
    rods = [mbs.CreateRigidBody(inertia=inertia, referencePosition=list(CENTRES0[i]),
                                referenceRotationMatrix=ROTATIONS0[i], gravity=[0.0, -G, 0.0], show=False)
            for i in range(5)]
    for k in range(6):
        parent = ground if PARENT[k] < 0 else rods[PARENT[k]]
        mbs.CreateRevoluteJoint(itemNumbers=[parent, rods[CHILD[k]]], position=list(POINTS[k]), axis=list(AXES[k]),
                                show=False)
    kinds = (exu.OutputVariableType.Position, exu.OutputVariableType.Velocity,
             exu.OutputVariableType.AngularVelocity, exu.OutputVariableType.RotationMatrix)
    sensors = [[mbs.AddSensor(SensorBody(bodyNumber=b, outputVariableType=k, storeInternal=True, writeToFile=False))
                for k in kinds] for b in rods]
    mbs.Assemble()
    settings = exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF, tolerance=EXUDYN_TOLERANCE,
                               sensor_period=OUTPUT)
    settings.linearSolver.solverType = exu.LinearSolverType.EigenDense
    settings.linearSolver.ignoreSingularJacobian = True
    wall, statistics = exudyn_solve(mbs, settings)
    data = [[mbs.GetSensorStoredData(s)[:, 1:] for s in per_rod] for per_rod in sensors]
    p, v, w = (np.stack([d[k] for d in data], axis=1) for k in range(3))
    R = np.stack([d[3].reshape(-1, 3, 3) for d in data], axis=1)
    return dict(wall_time_s=wall, **metrics(p, v, R, w), **statistics)


class Study(PeerStudy):
    label, name, repeats, fmu = "R4", "r4_bricard", 2, FMUS / "bricard.fmu"
    settings, xlabel = STEPS, "wall time for 10 s simulated [s]"

    def codes(self):
        return [(OURS, "5 revolute tree joints + 1 cut joint (redundant row)", lambda h: ours(self.args.fmu, h)),
                (EXUDYN, "RigidBody EP + 6 JointRevoluteZ, ignoreSingularJacobian", exudyn_rigid_bodies)]

    def panels(self, tables):
        return [Panel("energy drift max |E(t) - E(0)| / (m g L)",
                      f"R4 Bricard: energy drift against run time (rho_inf = {RHO_INF}; labels: h)"),
                Panel("constraint drift: largest joint violation [m or rad]", "R4: constraint drift",
                      "constraint_drift", 1e-17)]


if __name__ == "__main__":
    Study().main(__doc__)
