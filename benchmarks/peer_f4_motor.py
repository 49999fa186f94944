#!/usr/bin/env python3
"""F4 spin-up beam driven through a motor (issue 5): a rigid hub on a driven
revolute joint, the beam's root welded to the hub. Our FMU against Exudyn,
error against run time over paired refinements (elements n, substep h) =
(2, 8e-3), (4, 4e-3), (8, 2e-3), (16, 1e-3), (32, 5e-4) and the finer steps on n = 2
and 4; each run simulates 7 s
(outputs every 0.04 s) and yields the tip deflection in the rotating frame at
t = 7 s. Error: against a converged run of our FMU (n = 64 and 128 at
h = 5e-4, extrapolated in n, order 2), written to f4_motor_reference.csv
with the same extrapolation of Exudyn's runs and, for comparison, the
prescribed-root-node reference of peer_f4_spin_up.py when its CSV is there.

Same data for both codes: the beam of peer_f4_spin_up.py (L = 10, EA = 2.8e7,
GA = 1e7, EI = 1.4e4, rho A = 1.2, rho I = 6e-4); hub: mass 10 kg, inertia
2 kg m^2 about the spin axis, its centre on the axis at the beam's root;
motor angle theta(t) of peer_f4_spin_up.py; generalized-alpha rho_inf = 0.8;
Newton stops on the increment, 1e-12.

Ours: the spin_up_beam scene with its "driven" support replaced by a body
"hub" on a revolute joint to ground with the drive theta(t) and a fixed
joint from the hub to node 0 of the beam (so a virtual body, welded to the
node by a flexible body joint): as tests/python/test_mfbd.py
test_motor_driven_hub_reproduces_the_prescribed_root_node.
Exudyn: the same in 2D: ObjectRigidBody2D hub (NodeRigidBody2D) on an
ObjectJointRevolute2D to ground, driven by an ObjectConnectorCoordinate on
the hub's rotation coordinate whose offset is theta(t) (Exudyn symbolic user
functions, as peer_f4_spin_up.py); the fixed joint hub - root node is an
ObjectJointRevolute2D (positions) plus an ObjectConnectorCoordinate between
the two rotation coordinates (a 2D weld, 3 constraints);
ObjectBeamGeometricallyExact2D elements.
Writes f4_motor_precision.csv, f4_motor_reference.csv and f4_motor_precision.png.
"""

import numpy as np

from peer_common import EXUDYN, OURS, FmuRun, Panel, PeerStudy, exudyn_beam_line_2d, exudyn_settings, exudyn_solve, \
    exudyn_spin_up_drive, extrapolated_references, extrapolated_value, load_scene, mesh_and_step, read_csv, \
    refinement_grid
from peer_f4_spin_up import EA, EI, GA, L, OMEGA, RHO_A, RHO_I, RHO_INF, T_UP, hub_angle

HUB_MASS, HUB_INERTIA = 10.0, 2.0
PAIRS = [(2, 8e-3), (4, 4e-3), (8, 2e-3), (16, 1e-3), (32, 5e-4)]
GRID = refinement_grid(PAIRS)  # PAIRS plus finer steps on the two coarsest meshes
REFERENCE = [(64, 5e-4), (128, 5e-4)]
STOP, OUTPUT = 7.0, 0.04  # the metric is at STOP; every h divides OUTPUT


def tip_deflection(t, tip_xy):
    """Tip deflection in the frame turning with the hub, at time t."""
    theta = float(hub_angle(t))
    return float(-np.sin(theta) * tip_xy[0] + np.cos(theta) * tip_xy[1])


def motor_scene(n):
    scene = load_scene("spin_up_beam")
    body = scene["flexible_bodies"][0]
    body["beam"]["elements"] = n
    angle = body.pop("supports")[0]["angle"]
    body["outputs"] = {"nodes": [n]}
    scene["bodies"] = [{"name": "hub", "mass": HUB_MASS, "inertia": [1, 1, HUB_INERTIA], "position": [0, 0, 0]}]
    scene["joints"] = [
        {"name": "motor", "type": "revolute", "parent": "ground", "child": "hub", "position": [0, 0, 0],
         "axis": [0, 0, 1], "drive": angle},
        {"name": "root", "type": "fixed", "parent": "hub", "child": {"flexible": "beam", "node": 0}}]
    return scene


def ours(fmu, n, h):
    run = FmuRun(fmu, {"solver.h_max": h, "solver.rho_inf": RHO_INF})
    names = [f"beam.node{n}.position.{c}" for c in "xy"]
    s, wall, statistics = run.sample(names, STOP, OUTPUT)
    return dict(wall_time_s=wall, tip=tip_deflection(STOP, s[-1]), **statistics)


def exudyn_motor_2d(n, h):
    import exudyn as exu
    from exudyn.itemInterface import MarkerBodyPosition, MarkerNodeCoordinate, MarkerNodePosition, \
        NodePointGround, NodeRigidBody2D, ObjectConnectorCoordinate, ObjectGround, ObjectJointRevolute2D, \
        ObjectRigidBody2D, SensorNode

    mbs = exu.SystemContainer().AddSystem()
    nodes = exudyn_beam_line_2d(mbs, n, L, RHO_A, RHO_I, EI, EA, GA)
    hub_node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0.0, 0.0, 0.0]))
    hub = mbs.AddObject(ObjectRigidBody2D(nodeNumber=hub_node, mass=HUB_MASS, inertia=HUB_INERTIA))
    ground = mbs.AddObject(ObjectGround())
    ground_node = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    # Motor: revolute joint hub - ground, and its angle driven by a coordinate constraint.
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
        mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0])),
        mbs.AddMarker(MarkerBodyPosition(bodyNumber=hub, localPosition=[0.0, 0.0, 0.0]))]))
    drive = mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=hub_node, coordinate=2))]))
    functions = exudyn_spin_up_drive(mbs, drive, OMEGA, T_UP)  # alive through the solve
    # Fixed joint hub - root node: positions and rotations equal.
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
        mbs.AddMarker(MarkerBodyPosition(bodyNumber=hub, localPosition=[0.0, 0.0, 0.0])),
        mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[0]))]))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=hub_node, coordinate=2)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=2))]))
    sensor = mbs.AddSensor(SensorNode(nodeNumber=nodes[-1], outputVariableType=exu.OutputVariableType.Position,
                                      storeInternal=True, writeToFile=False))
    mbs.Assemble()
    settings = exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF, sensor_period=OUTPUT, sparse=n >= 16)
    wall, statistics = exudyn_solve(mbs, settings)
    data = mbs.GetSensorStoredData(sensor)
    assert abs(data[-1, 0] - STOP) < 1e-9, data[-1, 0]
    return dict(wall_time_s=wall, tip=tip_deflection(STOP, data[-1, 1:3]), **statistics)


class Study(PeerStudy):
    label, name, repeats = "F4 motor", "f4_motor", 2
    settings, xlabel = GRID, "wall time for 7 s simulated [s]"
    annotate = staticmethod(mesh_and_step)
    tables = ("precision", "reference")

    def codes(self):
        return [(OURS, "hub on driven revolute, fixed joint to 3D corotational beam",
                 lambda n, h: ours(self.fmus[n], n, h)),
                (EXUDYN, "RigidBody2D hub, Revolute2D + coordinate drive, weld to BeamGeometricallyExact2D",
                 exudyn_motor_2d)]

    def run(self):
        self.fmus = {n: self.pack(motor_scene(n), f"motor{n}") for n, _ in self.settings + REFERENCE}
        runs = [(code, run) for code, _, run in self.codes()]
        reference, values = extrapolated_references("F4 motor", runs, REFERENCE, "tip", "tip_deflection_7s_m")
        self.reference = values[OURS]
        print(f"F4 motor reference tip deflection at 7 s: ours {values[OURS]:.9f} m, Exudyn {values[EXUDYN]:.9f} m "
              f"(difference {abs(values[OURS] - values[EXUDYN]):.1e} m)")
        spin_up = self.args.out / "f4_spin_up_reference.csv"
        if spin_up.exists():  # the prescribed-root-node version (peer_f4_spin_up.py)
            for r in read_csv(spin_up):
                if r["h_or_elements"] == "extrapolated":
                    reference.append(dict(r, kind=r["kind"] + ", prescribed root node (f4_spin_up_reference.csv)"))
                    print(f"  prescribed root node, {r['code']}: {float(r['tip_deflection_7s_m']):.9f} m")
        return dict(super().run(), reference=reference)

    def measure(self, r, code):
        """The tip deflection's error at 7 s."""
        return dict(error=abs(r["tip"] - self.reference), tip_deflection_7s_m=r["tip"])

    def panels(self, tables):
        reference = extrapolated_value(tables["reference"], "tip_deflection_7s_m")
        return [Panel("tip deflection error at t = 7 s [m]",
                      f"F4 motor-driven hub: tip deflection at 7 s vs converged {reference:.6f} m\n"
                      "(labels: elements / substep)")]


if __name__ == "__main__":
    Study().main(__doc__)
