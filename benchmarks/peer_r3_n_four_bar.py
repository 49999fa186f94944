#!/usr/bin/env python3
"""R3 N-four-bar (IFToMM A02), N = 40, our FMU against Exudyn: 2N + 1 = 81
uniform links (1 m, 1 kg), N + 1 cranks on ground pivots at x = 0 ... N,
N couplers; gravity -y; cranks vertical, couplers horizontal, the top of
crank 0 starting at 1 m/s. The cranks swing over the top about once every
2 s: the mechanism passes the singular configuration (all bars on the
ground line, the loop constraints lose 40 ranks) 20 times in the 20 s
of A02, the first at t = 0.7216 s.

Span: Exudyn's Newton fails at the first singular configuration
(t = 0.720 s; it cuts the step to 1e-5 and below and crawls), so both codes
are compared over 0 <= t <= STOP = 0.6 s (cranks 61 degrees from the
vertical). Our FMU runs the full 20 s: one run at h = 1e-3 is reported
alone (r3_n_four_bar_full.csv).

Metrics, sampled every 0.01 s in both codes:
  * error: crank 0's angle against the exact motion, max over the samples:
    the mechanism moves as one parallelogram (cranks rotate alike, couplers
    translate), so the energy integral gives it, with inertia
    ((N+1)/3 + N) m L^2 and potential ((N+1)/2 + N) m g L cos(theta)
    (integrated here by scipy to 1e-12);
  * energy_drift: the total energy drift, max |E(t) - E(0)| in m g L;
  * constraint_drift: the largest distance of a crank's foot from its
    ground pivot and of a coupler's ends from the cranks' tops (each
    coupler's end on the next crank is a cut joint in ours; every joint is
    a constraint in Exudyn), m.
over substeps h = 1e-2 ... 5e-4. Generalized-alpha rho_inf = 0.8 (the
scene's default; both codes), Newton on the increment 1e-12 (Exudyn's
modified Newton fails at 1e-14 here).

Ours: examples/n_four_bar/make_scene.py (a tree of two levels, every crank
on its ground pivot and every coupler on its crank's top, 81 joint
coordinates; each coupler's joint to the next crank is cut, 80 planar +
120 out-of-plane constraint rows, the out-of-plane ones redundant in a
planar motion), all bodies as outputs.
Exudyn: 81 RigidBody2D (243 coordinates), 121 RevoluteJoint2D (242 rows,
index 3), sparse LU (EigenSparse).
Writes r3_n_four_bar_precision.csv and .png.
"""
import importlib.util

import numpy as np
from scipy.integrate import solve_ivp

from peer_common import EXUDYN, OURS, ROOT, FmuRun, Panel, PeerStudy, exudyn_settings, exudyn_solve, result_row

N, G, MASS, L = 40, 9.81, 1.0, 1.0
J = MASS * L * L / 12
STOP, OUTPUT, FULL, FULL_H = 0.6, 0.01, 20.0, 1e-3
STEPS = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4]
RHO_INF = 0.8
MGL = MASS * G * L


def scene():
    """The R3 scene of examples/n_four_bar/make_scene.py, with every body as an output."""
    path = ROOT / "examples" / "n_four_bar" / "make_scene.py"
    spec = importlib.util.spec_from_file_location("n_four_bar_scene", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    s = module.n_four_bar(N)
    s["outputs"] = {"bodies": "all", "joints": ["pivot0"]}
    return s


def crank_angle_exact(times):
    """Angle of every crank from the vertical (positive towards +x) at
    `times` while the mechanism moves as a parallelogram: cranks rotate
    about their pivots, couplers translate; energy integral with inertia
    ((N+1)/3 + N) m L^2 and potential ((N+1)/2 + N) m g L cos(theta)."""
    inertia = (N + 1) * MASS * L * L / 3 + N * MASS * L * L
    weight = ((N + 1) / 2 + N) * MASS * G * L

    def rhs(_, y):
        return [y[1], weight * np.sin(y[0]) / inertia]
    sol = solve_ivp(rhs, (0, times[-1]), [0.0, 1.0 / L], t_eval=times, rtol=1e-12, atol=1e-12)
    return sol.y[0]


def bars(p, angle):
    """p: (samples, 81, 2) centres (crank0, coupler0, crank1, ...), angle
    (samples, 81) of each bar's axis from +x -> (start, end) points."""
    d = 0.5 * L * np.stack([np.cos(angle), np.sin(angle)], axis=2)
    return p - d, p + d


def metrics(p, v, w, angle):
    """p, v: (samples, bar, xy) centres and their velocities, w angular
    velocities, angle of each bar's axis from +x; samples every OUTPUT from 0."""
    e = np.sum(0.5 * MASS * np.sum(v**2, axis=2) + 0.5 * J * w**2 + MASS * G * p[:, :, 1], axis=1)
    start, end = bars(p, angle)
    cranks = np.arange(0, 2 * N + 1, 2)
    pivots = np.stack([cranks // 2, np.zeros(N + 1)], axis=1)
    foot = np.max(np.linalg.norm(start[:, cranks] - pivots[None], axis=2))
    tops = np.max(np.linalg.norm(start[:, 1::2] - end[:, cranks[:-1]], axis=2))  # coupler start on crank i's top
    ends = np.max(np.linalg.norm(end[:, 1::2] - end[:, cranks[1:]], axis=2))  # coupler end on crank i+1's top
    theta = np.pi / 2 - np.unwrap(angle[:, 0])  # crank 0 from the vertical, towards +x
    exact = crank_angle_exact(OUTPUT * np.arange(len(theta)))
    return dict(error=float(np.max(np.abs(theta - exact))), energy_drift=float(np.max(np.abs(e - e[0]))) / MGL,
                constraint_drift=float(max(foot, tops, ends)), crank0_angle=float(theta[-1]))


def body_names():
    return [n for i in range(N + 1) for n in ([f"crank{i}"] + ([f"coupler{i}"] if i < N else []))]


def ours(fmu, h, stop=STOP):
    run = FmuRun(fmu, {"solver.h_max": h, "solver.rho_inf": RHO_INF})
    names = [f"{b}.{q}" for b in body_names()
             for q in ("position.x", "position.y", "velocity.x", "velocity.y", "angular_velocity.z",
                       "orientation.w", "orientation.z")]
    s, wall, statistics = run.sample(names, stop, OUTPUT)
    s = s.reshape(len(s), 2 * N + 1, 7)
    angle = 2 * np.arctan2(s[:, :, 6], s[:, :, 5])  # planar rotation about z from the quaternion
    return dict(wall_time_s=wall, **metrics(s[:, :, 0:2], s[:, :, 2:4], s[:, :, 4], angle), **statistics)


def exudyn_rigid_bodies(h):
    import exudyn as exu
    from exudyn.itemInterface import LoadMassProportional, MarkerBodyMass, MarkerBodyPosition, NodeRigidBody2D, \
        ObjectGround, ObjectJointRevolute2D, ObjectRigidBody2D, SensorBody

    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.AddObject(ObjectGround())
    bodies, reference_angles = [], []
    for k in range(2 * N + 1):
        i = k // 2
        if k % 2 == 0:  # crank i: vertical, centre (i, 0.5), axis +y; rate -1 rad/s
            reference, velocity = [i, 0.5 * L, np.pi / 2], [0.5, 0.0, -1.0]
        else:  # coupler i: horizontal, centre (i + 0.5, 1); translates at 1 m/s
            reference, velocity = [i + 0.5, L, 0.0], [1.0, 0.0, 0.0]
        reference_angles.append(reference[2])
        node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=reference, initialVelocities=velocity))
        bodies.append(mbs.AddObject(ObjectRigidBody2D(mass=MASS, inertia=J, nodeNumber=node)))
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=bodies[-1])),
                                         loadVector=[0.0, -G, 0.0]))

    def pin(a, pa, b, pb):
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
            mbs.AddMarker(MarkerBodyPosition(bodyNumber=a, localPosition=[pa, 0.0, 0.0])),
            mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=[pb, 0.0, 0.0]))]))

    half = 0.5 * L
    for i in range(N + 1):
        crank = bodies[2 * i]
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
            mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[float(i), 0.0, 0.0])),
            mbs.AddMarker(MarkerBodyPosition(bodyNumber=crank, localPosition=[-half, 0.0, 0.0]))]))
        if i < N:
            pin(crank, half, bodies[2 * i + 1], -half)
            pin(bodies[2 * i + 1], half, bodies[2 * i + 2], half)
    kinds = (exu.OutputVariableType.Position, exu.OutputVariableType.Velocity,
             exu.OutputVariableType.AngularVelocity, exu.OutputVariableType.Rotation)
    sensors = [[mbs.AddSensor(SensorBody(bodyNumber=b, outputVariableType=k, storeInternal=True, writeToFile=False))
                for k in kinds] for b in bodies]
    mbs.Assemble()
    settings = exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF, sensor_period=OUTPUT, sparse=True)
    wall, statistics = exudyn_solve(mbs, settings)
    data = [[mbs.GetSensorStoredData(s) for s in per_body] for per_body in sensors]
    samples = min(len(d[0]) for d in data)
    p = np.stack([d[0][:samples, 1:3] for d in data], axis=1)
    v = np.stack([d[1][:samples, 1:3] for d in data], axis=1)
    w = np.column_stack([d[2][:samples, 3] for d in data])
    angle = np.column_stack([d[3][:samples, -1] for d in data]) + np.array(reference_angles)  # Rotation: from reference
    return dict(wall_time_s=wall, **metrics(p, v, w, angle), **statistics)


class Study(PeerStudy):
    label, name, repeats = "R3", "r3_n_four_bar", 2
    settings, xlabel = STEPS, f"wall time for {STOP:g} s simulated [s]"
    tables = ("precision", "full")
    model = "81 revolute tree joints + 40 cut joints"

    def codes(self):
        self.scene_fmu = self.pack(scene(), "n_four_bar")
        return [(OURS, self.model, lambda h: ours(self.scene_fmu, h)),
                (EXUDYN, "RigidBody2D + RevoluteJoint2D (index 3), sparse", exudyn_rigid_bodies)]

    def measure(self, r, code):
        return dict(error=r["error"], energy_drift=r["energy_drift"], constraint_drift=r["constraint_drift"],
                    simulated_s=STOP, rho_inf=RHO_INF)

    def run(self):
        tables = super().run()
        # Ours over the whole 20 s of A02, through its 20 singular configurations (Exudyn stops at the first).
        r = ours(self.scene_fmu, FULL_H, FULL)
        tables["full"] = [result_row("R3 whole run", OURS, self.model, FULL_H, r,
                                     dict(self.measure(r, OURS), simulated_s=FULL))]
        return tables

    def panels(self, tables):
        full = tables["full"][0]
        return [Panel(f"crank 0 angle error, max over 0-{STOP:g} s [rad]",
                      f"R3 N-four-bar, N = {N}, 0-{STOP:g} s: Exudyn stops at the first singular configuration\n"
                      f"(0.72 s); ours over {FULL:g} s at h = {FULL_H:g}: angle error {float(full['error']):.1e} rad, "
                      f"{float(full['wall_time_s']):.1f} s (rho_inf = {RHO_INF}; labels: h)", fontsize=8),
                Panel("energy drift max |E(t) - E(0)| / (m g L)", "R3: energy drift", "energy_drift"),
                Panel("constraint drift: largest joint-point mismatch [m]", "R3: constraint drift", "constraint_drift",
                      1e-17)]


if __name__ == "__main__":
    Study().main(__doc__)
