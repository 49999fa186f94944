#!/usr/bin/env python3
"""F6 flexible four-bar with a 5 degree defect at joint C (Bauchau et al.
2016), our FMU against Exudyn: error of the drive torque over one revolution
of bar 1 against run time, over paired refinements (elements per bar n,
substep h) = PAIRS below.

Problem (examples/flexible_four_bar): bars A(0,0,0) -> B(0,0,0.12) ->
C(0.24,0,0.12) -> D(0.24,0,0), sections of shared/benchmarks F6 (bars 1-2:
16 mm square steel, bar 3: 8 mm); revolute joints at A, B, D about global y,
at C about (0, cos 5 deg, sin 5 deg); bar 1 driven at A. The linkage is a
parallelogram: at bar-1 angles pi/2 and 3 pi/2 all bars line up, and the
defect makes the bars snap through there (the drive torque reverses within
a few hundredths of a second). Two changes to the example scene, both
codes alike, so that the curve to converge to is well defined:
  * the drive starts smoothly: the angle theta(t) = (omega/T)(t^2/2 +
    (T/(2 pi))^2 (cos(2 pi t/T) - 1)) up to T = 1 s, then omega T/2 +
    omega (t - T), omega = 0.6 rad/s (the example's omega t jumps to
    0.6 rad/s at t = 0); one revolution ends at 2 pi/omega + T/2 = 10.97 s;
  * light stiffness-proportional (Kelvin-Voigt) damping beta = 3e-5 s in
    every bar (ours: the flexible bodies' "damping"; Exudyn: the section's
    dampingMatrix = beta times its stiffness matrix). Without it the
    vibrations that the snap-through excites (bar modes of some hundred Hz)
    ring on, damped only by the integrator, so the torque sampled after a
    snap depends on h and n by their phase and no run converges to another
    (measured: 2.8 N m apart between n = 8 and 16 without damping).
Generalized-alpha rho_inf = 0.8; Newton stops on the increment, 1e-12.

Metric: the drive torque at A (about the drive axis) sampled at 200 equal
intervals over the revolution, away from the snap-throughs: error = the
largest |torque - reference| over the samples whose bar-1 angle is more
than 0.6 rad from pi/2 and 3 pi/2 (127 of the 200; the quasi-static part of
the revolution). Reference: our FMU at n = 32 (REFERENCE). The substep is
the same for all runs, h = T_rev/(200 * 13) = 4.2e-3 s: this part of the
curve does not depend on h (measured: 1.5e-8 N m between h = 5.3e-4 and
2.6e-4 at n = 16, and the same error at h = 4.2e-3 and 2.1e-3 at n = 4).
Within the snap windows the torque does depend on h (0.46 N m between
h = 5.3e-4 and 2.6e-4 at n = 16: the vibration the snap excites is not
resolved by these steps) and converged references there would cost minutes;
the CSV has the whole-revolution deviation (error_whole_revolution, against
the same reference at the same h) and the peak torque for comparison only.
Exudyn's runs are measured against our reference; the two codes' agreement:
Exudyn's n = 8 and 16 runs extrapolated in n (order 2) against our
reference, over the same samples (f6_four_bar_reference.csv). Also in the
CSV: the largest out-of-plane displacement of joint C (bar 3's node 0).

Ours: the example scene with the changes above; 3D corotational beams; the
joints on flexible nodes through virtual bodies and flexible body joints.
Exudyn: ObjectBeamGeometricallyExact (3D, SE(3) interpolation) on
NodeRigidBodyEP nodes (Euler parameters; with Lie-group nodes
NodeRigidBodyRotVecLG, n = 4, h = 2e-3, its implicit solver cut the step
down to 24,260 steps instead of 500 in the first second, as in F4); joints B, C, D ObjectJointRevoluteZ between
MarkerNodeRigid markers whose frames turn z onto the joint axis; A an
ObjectJointGeneric (all six axes locked) whose rotation offset about the
axis is theta(t) (symbolic user function); the torque is its TorqueLocal
about z. Wall time: the whole revolution, outputs every 1/200 of it.
Writes f6_four_bar_precision.csv, f6_four_bar_reference.csv and
f6_four_bar_precision.png.
"""

import numpy as np

from peer_common import EXUDYN, OURS, FmuRun, Panel, PeerStudy, draw_curves, exudyn_settings, exudyn_solve, \
    extrapolated, figure, load_scene, save_figure, spin_up_angle, sweep

OMEGA, T_UP, DEFECT, BETA = 0.6, 1.0, np.radians(5.0), 3e-5
STOP = 2 * np.pi / OMEGA + T_UP / 2  # one revolution of bar 1
SAMPLES = 200
OUTPUT = STOP / SAMPLES
H = OUTPUT / 13  # 13 substeps per output interval
PAIRS = [(2, H), (4, H), (8, H), (16, H)]  # (elements per bar, substep)
REFERENCE = (32, H)
WINDOW = 0.6  # rad about the flat configurations left out of the error
RHO_INF = 0.8
RAMP = "if(T - t, omega/T*(t^2/2 + (T/(2*pi))^2*(cos(2*pi*t/T) - 1)), omega*T/2 + omega*(t - T))"
# start, end, EA, GA, GJ, EI, rho A, rho J (shared/benchmarks F6)
BARS = [([0, 0, 0], [0, 0, 0.12], 5.2992e7, 1.68803e7, 733.488, 1130.50, 1.9968, [8.51968e-5, 4.25984e-5, 4.25984e-5]),
        ([0, 0, 0.12], [0.24, 0, 0.12], 5.2992e7, 1.68803e7, 733.488, 1130.50, 1.9968,
         [8.51968e-5, 4.25984e-5, 4.25984e-5]),
        ([0.24, 0, 0.12], [0.24, 0, 0], 1.3248e7, 4.22008e6, 45.843, 70.656, 0.4992, [5.3248e-6, 2.6624e-6, 2.6624e-6])]


def drive_angle(t):
    return spin_up_angle(np.asarray(t, dtype=float), OMEGA, T_UP)


def quasi_static_samples():
    """Mask of the output samples whose bar-1 angle is more than WINDOW from
    the flat configurations pi/2 and 3 pi/2."""
    angle = drive_angle(OUTPUT * np.arange(1, SAMPLES + 1))
    return (np.abs(angle - np.pi / 2) > WINDOW) & (np.abs(angle - 3 * np.pi / 2) > WINDOW)


def four_bar_scene(n):
    scene = load_scene("flexible_four_bar")
    scene["parameters"]["T"] = {"value": T_UP, "unit": "s", "description": "spin-up time of the drive"}
    scene["solver"]["rho_inf"] = RHO_INF
    for body in scene["flexible_bodies"]:
        body["beam"]["elements"] = n
        body["damping"] = BETA
        body.pop("outputs")
        if body["name"] == "bar3":
            body["outputs"] = {"nodes": [0]}
    for joint in scene["joints"]:
        if joint["name"] == "A":
            joint["drive"] = RAMP
        for end in ("parent", "child"):
            if isinstance(joint[end], dict) and joint[end]["node"] != 0:
                joint[end]["node"] = n  # the bar's last node
    return scene


def ours(fmu, h):
    run = FmuRun(fmu, {"solver.h_max": h * (1 + 1e-9)})
    s, wall, statistics = run.sample(["A.drive_torque", "bar3.node0.position.y", "A.angle"], SAMPLES * OUTPUT, OUTPUT)
    s = s[1:]  # from t = OUTPUT on
    assert abs(s[-1, 2] - 2 * np.pi) < 1e-9, s[-1, 2]
    return dict(wall_time_s=wall, torque=s[:, 0], out_of_plane=float(np.abs(s[:, 1]).max()), **statistics)


def _drive_offset(mbs, t, itemNumber, lOffset):
    import exudyn as exu
    return [0, 0, 0, 0, 0, spin_up_angle(t, OMEGA, T_UP, exu.symbolic.cos, exu.symbolic.IfThenElse)]


def _beam_frame(start, end):
    """Node frame of a bar: x along the bar, y global y (the example's section_y)."""
    x = np.subtract(end, start) / np.linalg.norm(np.subtract(end, start))
    y = np.array([0.0, 1.0, 0.0])
    return np.column_stack([x, y, np.cross(x, y)])


def _axis_frame(axis):
    """A frame whose z is the joint axis."""
    z = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    x = np.array([1.0, 0.0, 0.0]) - z[0] * z
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def exudyn_four_bar(n, h):
    import exudyn as exu
    from exudyn.advancedUtilities import CreateSymbolicUserFunction
    from exudyn.itemInterface import MarkerBodyRigid, MarkerNodeRigid, NodeRigidBodyEP, ObjectBeamGeometricallyExact, \
        ObjectGround, ObjectJointGeneric, ObjectJointRevoluteZ, SensorNode, SensorObject
    from exudyn.rigidBodyUtilities import RotationMatrix2EulerParameters

    def transformation(rotation, translation=(0.0, 0.0, 0.0)):
        h = np.eye(4)
        h[:3, :3], h[:3, 3] = rotation, translation
        return h

    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.AddObject(ObjectGround())
    bars = []
    for start, end, EA, GA, GJ, EI, rho_a, rho_j in BARS:
        frame = _beam_frame(start, end)
        section = exu.BeamSection()
        section.stiffnessMatrix = np.diag([EA, GA, GA, GJ, EI, EI])
        section.dampingMatrix = BETA * section.stiffnessMatrix
        section.inertia = np.diag(rho_j)
        section.massPerLength = rho_a
        parameters = list(RotationMatrix2EulerParameters(frame))
        nodes = [mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=list(np.add(start, np.subtract(end, start) * i / n))
                                             + parameters)) for i in range(n + 1)]
        length = np.linalg.norm(np.subtract(end, start)) / n
        for i in range(n):
            mbs.AddObject(ObjectBeamGeometricallyExact(nodeNumbers=[nodes[i], nodes[i + 1]], length=length,
                                                       sectionData=section))
        bars.append((nodes, frame))

    def on_node(node, frame, axis):
        return mbs.AddMarker(MarkerNodeRigid(nodeNumber=node, localHT=transformation(frame.T @ _axis_frame(axis))))

    def on_ground(position, axis):
        return mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localHT=transformation(_axis_frame(axis), position)))

    y, tilted = [0.0, 1.0, 0.0], [0.0, np.cos(DEFECT), np.sin(DEFECT)]
    (n1, f1), (n2, f2), (n3, f3) = bars
    drive = mbs.AddObject(ObjectJointGeneric(markerNumbers=[on_ground([0, 0, 0], y), on_node(n1[0], f1, y)],
                                             constrainedAxes=[1] * 6))
    offset = CreateSymbolicUserFunction(mbs, _drive_offset, "offsetUserFunction", drive)  # alive through the solve
    mbs.SetObjectParameter(drive, "offsetUserFunction", offset)
    mbs.AddObject(ObjectJointRevoluteZ(markerNumbers=[on_node(n1[-1], f1, y), on_node(n2[0], f2, y)]))
    mbs.AddObject(ObjectJointRevoluteZ(markerNumbers=[on_node(n2[-1], f2, tilted), on_node(n3[0], f3, tilted)]))
    mbs.AddObject(ObjectJointRevoluteZ(markerNumbers=[on_ground([0.24, 0, 0], y), on_node(n3[-1], f3, y)]))
    torque = mbs.AddSensor(SensorObject(objectNumber=drive, outputVariableType=exu.OutputVariableType.TorqueLocal,
                                        storeInternal=True, writeToFile=False))
    joint_c = mbs.AddSensor(SensorNode(nodeNumber=n3[0], outputVariableType=exu.OutputVariableType.Position,
                                       storeInternal=True, writeToFile=False))
    mbs.Assemble()
    settings = exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF, sensor_period=OUTPUT, sparse=True)
    settings.timeIntegration.numberOfSteps = SAMPLES * round(OUTPUT / h)
    wall, statistics = exudyn_solve(mbs, settings)
    data, c = mbs.GetSensorStoredData(torque), mbs.GetSensorStoredData(joint_c)
    keep = data[:, 0] > 0.5 * OUTPUT  # the sensors also store t = 0
    assert keep.sum() == SAMPLES and np.allclose(data[keep, 0], OUTPUT * np.arange(1, SAMPLES + 1), atol=1e-8)
    # TorqueLocal: in the frame of marker 0 (ground, z on the axis), on marker 1's side.
    return dict(wall_time_s=wall, torque=data[keep, 3], out_of_plane=float(np.abs(c[keep, 2]).max()), **statistics)


class Study(PeerStudy):
    label, name, repeats = "F6", "f6_four_bar", 1
    settings, xlabel = PAIRS, "wall time for one revolution [s]"
    tables, curves = ("precision", "reference"), True

    def codes(self):
        return [(OURS, "3D corotational beams, joints on virtual bodies", lambda n, h: ours(self.fmus[n], h)),
                (EXUDYN, "BeamGeometricallyExact (EP nodes), RevoluteZ + GenericJoint drive", exudyn_four_bar)]

    def run(self):
        """Our converged curve (REFERENCE), the sweep against it, then
        Exudyn's two finest runs extrapolated against it."""
        self.fmus = {n: self.pack(four_bar_scene(n), f"four_bar{n}") for n, _ in self.settings + [REFERENCE]}
        self.quasi_static = quasi_static_samples()
        self.reference = ours(self.fmus[REFERENCE[0]], REFERENCE[1])
        print(f"F6 reference {OURS} n={REFERENCE[0]} h={REFERENCE[1]:.2e}: largest |torque| "
              f"{np.abs(self.reference['torque']).max():.4f} N m, wall {self.reference['wall_time_s']:.1f} s",
              flush=True)
        self.results = {}
        rows = sweep(self.label, self.codes(), self.settings, self.args.repeats, self.measure, self.results)
        finer, finest = self.settings[-2:]
        exudyn_limit = extrapolated(self.results[(EXUDYN, finer)]["torque"], self.results[(EXUDYN, finest)]["torque"])
        agreement = float(np.abs(exudyn_limit - self.reference["torque"])[self.quasi_static].max())
        reference_rows = [dict(code=OURS, h_or_elements=REFERENCE[0], wall_time_s=self.reference["wall_time_s"],
                               error="", h_s=REFERENCE[1],
                               max_abs_torque_nm=float(np.abs(self.reference["torque"]).max()),
                               out_of_plane_c_m=self.reference["out_of_plane"], kind="reference run"),
                          dict(code=EXUDYN, h_or_elements="extrapolated", wall_time_s="", error=agreement,
                               h_s=finest[1], kind=f"n = {finer[0]} and {finest[0]} extrapolated (order 2) against ours")]
        print(f"F6 Exudyn extrapolated from n = {finer[0]}, {finest[0]} against our reference: "
              f"max |torque difference| {agreement:.3e} N m away from the snaps (largest |torque| there "
              f"{np.abs(self.reference['torque'][self.quasi_static]).max():.3f} N m)", flush=True)
        return dict(precision=rows, reference=reference_rows)

    def measure(self, r, code):
        deviation = np.abs(r["torque"] - self.reference["torque"])
        return dict(error=float(deviation[self.quasi_static].max()), error_whole_revolution=float(deviation.max()),
                    max_abs_torque_nm=float(np.abs(r["torque"]).max()), out_of_plane_c_m=r["out_of_plane"],
                    out_of_plane_error_m=abs(r["out_of_plane"] - self.reference["out_of_plane"]))

    def draw(self, tables, png):
        fig, (a, b) = figure(2, (12, 4.8))
        self.draw_panel(a, tables["precision"], Panel(
            f"max |drive torque - reference| [N m], > {WINDOW} rad from the snaps",
            f"F6 four-bar: drive torque vs ours at n = {REFERENCE[0]}\n"
            f"(labels: elements per bar; h = {self.settings[0][1]:.2g} s in every run)"))
        t = OUTPUT * np.arange(1, SAMPLES + 1)
        for flat in (np.pi / 2, 3 * np.pi / 2):
            inside = t[np.abs(drive_angle(t) - flat) <= WINDOW]
            b.axvspan(inside[0], inside[-1], color="0.9")
        coarsest, finest = self.settings[0], self.settings[-1]
        draw_curves(b, t, [(self.reference["torque"], "C0-", 1.5, f"{OURS}, n = {REFERENCE[0]} (reference)"),
                           (self.results[(EXUDYN, finest)]["torque"], "C3--", 1.2, f"{EXUDYN}, n = {finest[0]}"),
                           (self.results[(OURS, coarsest)]["torque"], "C9:", 1, f"{OURS}, n = {coarsest[0]}"),
                           (self.results[(EXUDYN, coarsest)]["torque"], "C1:", 1, f"{EXUDYN}, n = {coarsest[0]}")],
                    "drive torque at A [N m]",
                    "drive torque over one revolution (smooth start, beta = 3e-5 s; grey: snap windows)")
        save_figure(fig, png)


if __name__ == "__main__":
    Study().main(__doc__)
