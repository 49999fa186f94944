#!/usr/bin/env python3
"""R6 stiff flyball governor (IFToMM A05), our FMU against Exudyn: shaft
driven at Omega = 2 pi rad/s about z (gravity -z), two rods (0.3 kg, 1 m)
with 5 kg balls on hinges at the shaft top, a 3 kg slider on the shaft, and
coupler spring-dampers (k = 8e5 N/m, c = 4e4 N s/m, free length 0.5 m) from
each rod's midpoint to the slider: a slow governor swing against spring
time scales of m/c ~ 1e-4 s and sqrt(m/k) ~ 2.5e-3 s; 10 s from the
benchmark start (rods 30 degrees below horizontal, springs at free length).

No closed form: the reference is a converged run, ours at h = 1e-4 (Exudyn
converges to it: its error against it falls at second order with h down
to its finest step; an Exudyn run at 1e-4 would take 30 s). Metrics over 0 <= t <= 10 s, sampled every 0.01 s
in both codes, over substeps h = 1e-2 ... 5e-4:
  * error: the slider position (guide coordinate), max |z(t) - z_ref(t)|, m;
  * hinge_error: the rod 1 hinge angle, max |phi(t) - phi_ref(t)|, rad.
Both codes: generalized-alpha rho_inf = 0.8 (the scene's default), Newton
on the increment, 1e-12.

Ours: build/fmus/flyball_governor.fmu (examples/flyball_governor: shaft on
a driven revolute joint, slider on a prismatic joint, rods on revolute
joints, balls on fixed joints; joint coordinates; the couplers are
spring_damper force elements).
Exudyn: one KinematicTree (the same formulation): shaft RevoluteZ, slider
PrismaticZ on the shaft, rods RevoluteY on the shaft with the balls merged
into them (mass, centre of mass and inertia of rod + ball), so 4
coordinates; couplers ConnectorSpringDamper between MarkerKinematicTreeRigid
points; the shaft angle driven by a CoordinateConstraint whose offset is
Omega t (Exudyn symbolic user functions, evaluated in C++).
Writes r6_flyball_governor_precision.csv and .png.
"""
import math

import numpy as np

from peer_common import EXUDYN, FMUS, OURS, FmuRun, Panel, PeerStudy, exudyn_settings, exudyn_solve

G, OMEGA = 9.81, 2 * math.pi
DENSITY, SECTION, LENGTH = 3000.0, 0.01, 1.0
ROD = DENSITY * SECTION**2 * LENGTH  # 0.3 kg
SLIDER, CUBE, BALL = 3.0, 0.1, 5.0
OFFSET, SLIDER_HEIGHT, ALPHA = 0.05, 0.5, math.radians(30.0)
K, C, FREE = 8e5, 4e4, 0.5
J_ALONG, J_ACROSS = ROD * 2 * SECTION**2 / 12, ROD * (LENGTH**2 + SECTION**2) / 12
STOP, OUTPUT = 10.0, 0.01
STEPS = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4]
REFERENCE_H = 1e-4
RHO_INF = 0.8


def ours(fmu, h):
    run = FmuRun(fmu, {"solver.h_max": h, "solver.rho_inf": RHO_INF})
    names = ["guide.position", "hinge1.angle"]
    s, wall, statistics = run.sample(names, STOP, OUTPUT)
    return dict(wall_time_s=wall, slider=s[:, 0], hinge=s[:, 1], **statistics)


def _shaft_angle(mbs, t, itemNumber, lOffset):
    return OMEGA * t


def _shaft_rate(mbs, t, itemNumber, lOffset):
    import exudyn as exu
    return exu.symbolic.Real(OMEGA)


def rod_with_ball():
    """Mass, centre of mass (along the rod's x) and inertia about it of a rod
    with its ball at the tip."""
    mass = ROD + BALL
    com = (ROD * LENGTH / 2 + BALL * LENGTH) / mass
    across = J_ACROSS + ROD * (LENGTH / 2 - com)**2 + BALL * (LENGTH - com)**2
    return mass, com, np.diag([J_ALONG, across, across])


def exudyn_kinematic_tree(h):
    import exudyn as exu
    from exudyn.advancedUtilities import CreateSymbolicUserFunction
    from exudyn.itemInterface import MarkerKinematicTreeRigid, MarkerNodeCoordinate, NodeGenericODE2, \
        NodePointGround, ObjectConnectorCoordinate, ObjectConnectorSpringDamper, ObjectKinematicTree, SensorNode

    c, s = math.cos(ALPHA), math.sin(ALPHA)
    rod_frames = [np.column_stack([[c, 0, -s], [0, 1, 0], [s, 0, c]]),  # x down and out, y = hinge axis
                  np.column_stack([[-c, 0, -s], [0, -1, 0], [-s, 0, c]])]
    rod_mass, rod_com, rod_inertia = rod_with_ball()
    mbs = exu.SystemContainer().AddSystem()
    node = mbs.AddNode(NodeGenericODE2(numberOfODE2Coordinates=4, referenceCoordinates=[0.0] * 4,
                                       initialCoordinates=[0.0] * 4, initialCoordinates_t=[OMEGA, 0.0, 0.0, 0.0]))
    tree = mbs.AddObject(ObjectKinematicTree(
        nodeNumber=node, linkParents=[-1, 0, 0, 0],
        jointTypes=[exu.JointType.RevoluteZ, exu.JointType.PrismaticZ, exu.JointType.RevoluteY,
                    exu.JointType.RevoluteY],
        jointTransformations=exu.Matrix3DList([np.eye(3), np.eye(3)] + rod_frames),
        jointOffsets=exu.Vector3DList([[0.0, 0.0, 0.0], [0.0, 0.0, SLIDER_HEIGHT], [OFFSET, 0.0, LENGTH],
                                       [-OFFSET, 0.0, LENGTH]]),
        linkMasses=[ROD, SLIDER, rod_mass, rod_mass],
        linkCOMs=exu.Vector3DList([[0.0, 0.0, LENGTH / 2], [0.0, 0.0, 0.0], [rod_com, 0.0, 0.0],
                                   [rod_com, 0.0, 0.0]]),
        linkInertiasCOM=exu.Matrix3DList([np.diag([J_ACROSS, J_ACROSS, J_ALONG]), np.eye(3) * SLIDER * CUBE**2 / 6,
                                          rod_inertia, rod_inertia]),
        gravity=[0.0, 0.0, -G]))
    for link, side in ((2, 1.0), (3, -1.0)):
        mid = mbs.AddMarker(MarkerKinematicTreeRigid(objectNumber=tree, linkNumber=link,
                                                     localPosition=[LENGTH / 2, 0.0, 0.0]))
        on_slider = mbs.AddMarker(MarkerKinematicTreeRigid(objectNumber=tree, linkNumber=1,
                                                           localPosition=[side * OFFSET, 0.0, 0.0]))
        mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mid, on_slider], stiffness=K, damping=C,
                                                  referenceLength=FREE))
    fixed = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    drive = mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=fixed, coordinate=0)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))]))
    # The symbolic functions must outlive the solve: keep them in this frame.
    offset = CreateSymbolicUserFunction(mbs, _shaft_angle, "offsetUserFunction", drive)
    rate = CreateSymbolicUserFunction(mbs, _shaft_rate, "offsetUserFunction_t", drive)
    mbs.SetObjectParameter(drive, "offsetUserFunction", offset)
    mbs.SetObjectParameter(drive, "offsetUserFunction_t", rate)
    sensor = mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=exu.OutputVariableType.Coordinates,
                                      storeInternal=True, writeToFile=False))
    mbs.Assemble()
    settings = exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF, sensor_period=OUTPUT)
    wall, statistics = exudyn_solve(mbs, settings)
    q = mbs.GetSensorStoredData(sensor)
    return dict(wall_time_s=wall, slider=q[:, 2], hinge=q[:, 3], **statistics)


def deviation(run, reference):
    n = min(len(run["slider"]), len(reference["slider"]))
    return (float(np.max(np.abs(run["slider"][:n] - reference["slider"][:n]))),
            float(np.max(np.abs(run["hinge"][:n] - reference["hinge"][:n]))))


class Study(PeerStudy):
    label, name, repeats, fmu = "R6", "r6_flyball_governor", 2, FMUS / "flyball_governor.fmu"
    settings, xlabel = STEPS, "wall time for 10 s simulated [s]"

    def codes(self):
        return [(OURS, "joint coordinates, spring_damper couplers", lambda h: ours(self.args.fmu, h)),
                (EXUDYN, "KinematicTree (4 coordinates) + ConnectorSpringDamper", exudyn_kinematic_tree)]

    def run(self):
        self.reference = ours(self.args.fmu, REFERENCE_H)
        print(f"R6 reference: ours at h = {REFERENCE_H:g} ({self.reference['wall_time_s']:.2f} s, "
              f"{self.reference['rejected_steps']} rejected substeps)", flush=True)
        return super().run()

    def measure(self, r, code):
        error, hinge_error = deviation(r, self.reference)
        return dict(error=error, hinge_error=hinge_error, reference_h=REFERENCE_H, rho_inf=RHO_INF)

    def panels(self, tables):
        return [Panel(f"slider position error, max over 10 s, against ours at h = {REFERENCE_H:g} [m]",
                      f"R6 stiff flyball governor (rho_inf = {RHO_INF}; labels: h)"),
                Panel("rod hinge angle error, max over 10 s [rad]", "R6: rod hinge angle against the same reference",
                      "hinge_error")]


if __name__ == "__main__":
    Study().main(__doc__)
