#!/usr/bin/env python3
"""R5 slider-crank, our FMU against Exudyn: crank r = 0.5 m driven at
omega = 2 pi rad/s, coupler l = 2 m, slider line offset e = 0.1 m, 2 s (two
turns), against the exact kinematics (shared/benchmarks R5)
x(theta) = r cos(theta) + sqrt(l^2 - (r sin(theta) - e)^2), theta = omega t,
and its time derivative. Over substeps h = 1e-2 ... 1e-4:
  * error: the slider position, max over the samples of |x(t) - x(theta)|;
  * velocity_error: the slider velocity against omega dx/dtheta, max.
The mechanism has no degree of freedom left (the crank is driven), so an
index-3 solver puts the positions on the constraints at every step whatever
h is: the position error is round-off in both codes and only the cost
differs. The velocities come from the integrator's update formula and
converge with h. Slider sampled every 0.01 s in both codes.

Both codes: generalized-alpha rho_inf = 0.8 (the scene's default), Newton
on the increment, 1e-12.
Ours: build/fmus/slider_crank.fmu (crank and coupler on revolute joints,
slider on a prismatic joint; the loop is cut at the slider pin; the crank
joint is driven, a constraint row).
Exudyn: RigidBody2D crank, coupler and slider, RevoluteJoint2D at the three
pins, PrismaticJoint2D for the slider on its line; the crank's rotation
coordinate driven by a CoordinateConstraint whose offset is omega t
(Exudyn symbolic user functions, evaluated in C++). Index-3 redundant
coordinates (9 coordinates, 9 constraint rows). Exudyn does not project
the initial velocities onto the constraints: they are given here from the
exact kinematics (with zero initial velocities its velocity error stays at
0.157 m/s at every h).
Writes r5_slider_crank_precision.csv and .png.
"""

import numpy as np

from peer_common import EXUDYN, FMUS, OURS, FmuRun, Panel, PeerStudy, exudyn_settings, exudyn_solve

R, LC, E, OMEGA, G = 0.5, 2.0, 0.1, 2 * np.pi, 9.81
STOP, OUTPUT = 2.0, 0.01
STEPS = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4]
RHO_INF = 0.8
# Ours driven by an error tolerance; Exudyn's explicit solvers do not take
# the joint constraints of this model (Exudyn: explicit integration only
# eliminates coordinate constraints), so its generalized-alpha stays alone.
TOLERANCES = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
# Bodies of examples/slider_crank at theta = 0: mass, inertia about z, centre, angle.
X0 = R + np.sqrt(LC**2 - E**2)
BODIES = [(1.0, 1.0 * R**2 / 12, (R / 2, 0.0), 0.0),  # crank
          (2.0, 2.0 * LC**2 / 12, ((R + X0) / 2, E / 2), np.arctan2(E, X0 - R)),  # coupler
          (1.0, 0.01, (X0, E), 0.0)]  # slider


def exact(t):
    """Slider x and xdot at the crank angle omega t."""
    theta = OMEGA * np.asarray(t)
    s, c = R * np.sin(theta) - E, R * np.cos(theta)
    d = np.sqrt(LC**2 - s**2)
    return c + d, OMEGA * (-R * np.sin(theta) - s * c / d)


def initial_velocities():
    """(vx, vy, angular rate) of crank, coupler and slider at theta = 0 on
    the velocity constraints (Exudyn starts from what it is given)."""
    phi = BODIES[1][3]
    coupler_rate = -R * OMEGA / (LC * np.cos(phi))  # from R sin(theta) + LC sin(phi) = E
    pin = np.array([0.0, OMEGA * R])
    half = 0.5 * LC * np.array([np.cos(phi), np.sin(phi)])
    coupler = pin + coupler_rate * np.array([-half[1], half[0]])
    return [[0.0, OMEGA * R / 2, OMEGA], [coupler[0], coupler[1], coupler_rate], [exact(0.0)[1], 0.0, 0.0]]


def metrics(t, x, v):
    x_exact, v_exact = exact(t)
    return dict(error=float(np.max(np.abs(x - x_exact))), velocity_error=float(np.max(np.abs(v - v_exact))),
                rho_inf=RHO_INF)


def ours(fmu, h, tolerance=None):
    """Substeps of h, or driven by an error tolerance (the integrator the
    FMU chooses, h_max the communication step)."""
    parameters = {"solver.h_max": OUTPUT} if tolerance else {"solver.h_max": h, "solver.rho_inf": RHO_INF}
    run = FmuRun(fmu, parameters, tolerance=tolerance)
    names = ["slider.position.x", "slider.velocity.x"]
    s, wall, statistics = run.sample(names, STOP, OUTPUT)
    t = OUTPUT * np.arange(len(s))
    return dict(wall_time_s=wall, **metrics(t, s[:, 0], s[:, 1]), **statistics,
                **({"tolerance": tolerance} if tolerance else {}))


def _crank_angle(mbs, t, itemNumber, lOffset):
    return OMEGA * t


def _crank_rate(mbs, t, itemNumber, lOffset):
    import exudyn as exu
    return exu.symbolic.Real(OMEGA)


def exudyn_rigid_bodies(h):
    import exudyn as exu
    from exudyn.advancedUtilities import CreateSymbolicUserFunction
    from exudyn.itemInterface import LoadMassProportional, MarkerBodyMass, MarkerBodyPosition, MarkerBodyRigid, \
        MarkerNodeCoordinate, NodePointGround, NodeRigidBody2D, ObjectConnectorCoordinate, ObjectGround, \
        ObjectJointPrismatic2D, ObjectJointRevolute2D, ObjectRigidBody2D, SensorBody

    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.AddObject(ObjectGround())
    nodes, bodies = [], []
    for (mass, inertia, centre, angle), velocity in zip(BODIES, initial_velocities()):
        nodes.append(mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[centre[0], centre[1], angle],
                                                 initialVelocities=velocity)))
        bodies.append(mbs.AddObject(ObjectRigidBody2D(mass=mass, inertia=inertia, nodeNumber=nodes[-1])))
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=bodies[-1])),
                                         loadVector=[0.0, -G, 0.0]))
    crank, coupler, slider = bodies
    half = LC / 2

    def point(body, local):
        return mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=list(local) + [0.0]))

    for a, pa, b, pb in ((ground, (0, 0), crank, (-R / 2, 0)), (crank, (R / 2, 0), coupler, (-half, 0)),
                         (coupler, (half, 0), slider, (0, 0))):
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[point(a, pa), point(b, pb)]))
    guide = [mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[X0, E, 0.0])),
             mbs.AddMarker(MarkerBodyRigid(bodyNumber=slider, localPosition=[0.0, 0.0, 0.0]))]
    mbs.AddObject(ObjectJointPrismatic2D(markerNumbers=guide, axisMarker0=[1.0, 0.0, 0.0],
                                         normalMarker1=[0.0, 1.0, 0.0], constrainRotation=True))
    fixed = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    drive = mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=fixed, coordinate=0)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=2))]))
    # The symbolic functions must outlive the solve: keep them in this frame.
    offset = CreateSymbolicUserFunction(mbs, _crank_angle, "offsetUserFunction", drive)
    rate = CreateSymbolicUserFunction(mbs, _crank_rate, "offsetUserFunction_t", drive)
    mbs.SetObjectParameter(drive, "offsetUserFunction", offset)
    mbs.SetObjectParameter(drive, "offsetUserFunction_t", rate)
    sensors = [mbs.AddSensor(SensorBody(bodyNumber=slider, outputVariableType=k, storeInternal=True,
                                        writeToFile=False))
               for k in (exu.OutputVariableType.Position, exu.OutputVariableType.Velocity)]
    mbs.Assemble()
    settings = exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF, sensor_period=OUTPUT)
    wall, statistics = exudyn_solve(mbs, settings)
    position, velocity = (mbs.GetSensorStoredData(s) for s in sensors)
    return dict(wall_time_s=wall, **metrics(position[:, 0], position[:, 1], velocity[:, 1]), **statistics)


class Study(PeerStudy):
    label, name, repeats, fmu = "R5", "r5_slider_crank", 3, FMUS / "slider_crank.fmu"
    settings, xlabel = STEPS, "wall time for 2 s simulated [s]"

    def codes(self):
        return [(OURS, "revolute + prismatic tree, cut at the slider pin, driven crank",
                 lambda h: ours(self.args.fmu, h)),
                (OURS, "by tolerance (Dormand-Prince 5(4))", lambda tol: ours(self.args.fmu, None, tol),
                 TOLERANCES),
                (EXUDYN, "RigidBody2D + Revolute/PrismaticJoint2D, driven coordinate", exudyn_rigid_bodies)]

    def panels(self, tables):
        return [Panel("slider position error, max |x - x(theta)| [m]",
                      f"R5 slider-crank: position against exact x(theta) (rho_inf = {RHO_INF}; labels: h)",
                      floor=1e-17),
                Panel("slider velocity error, max |v - omega dx/dtheta| [m/s]",
                      "R5: slider velocity against the exact derivative", "velocity_error")]


if __name__ == "__main__":
    Study().main(__doc__)
