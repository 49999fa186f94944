#!/usr/bin/env python3
"""Cantilever with a rigid tip body on a fixed joint (issue 5), our FMU
against Exudyn: error of the first bending frequency against the analytic
value, over paired refinements (elements n, substep h) = (2, 1e-2),
(4, 1e-2), (8, 5e-3), (16, 2.5e-3), (32, 1.25e-3) and the finer steps on n = 2 and 4,
and the wall time of the run.

Problem: clamped Euler-Bernoulli beam L = 1, EI = 10, rho A = 1 (EA = 1e7,
rho I = 1e-6); at its end a rigid body of mass M = 1 kg (mu = M/(rho A L) = 1)
and no rotary inertia, its centre at the beam's end, on a fixed joint.
Analytic frequencies (tests/python/test_mfbd.py tip_mass_frequencies): roots
l of 1 + cos l cosh l + mu l (cos l sinh l - sin l cosh l) = 0,
f = l^2 sqrt(EI/(rho A L^4))/(2 pi): f1 = 0.7837757 Hz (l = 1.2479174), then
8.18, 25.6, 52.9 Hz.

Procedure (that of peer_f3_vibration.py, in both codes): a tip force pulse
0.01 EI/L^2 sin^2(pi t/0.02 s) for 0.02 s on the beam's end node, free
vibration to 10 s, the tip body's y sampled every 0.01 s, f1 from a
least-squares fit of four modes over 1-10 s (starting guesses from the
spectrum near the analytic frequencies; the fourth, above the sampling's
Nyquist frequency, enters aliased, which the fit represents exactly).
Generalized-alpha rho_inf = 0.9; Newton stops on the increment, 1e-12.

Ours: the tests' scene: a body "tip" (mass 1, inertia 0) on a fixed joint whose
parent is the point at 1.0 along the flexible body (a virtual body welded to
the end node); 3D corotational beam, shear-rigid, consistent centre-line mass.
Exudyn, 2D: ObjectBeamGeometricallyExact2D (GA = EA: shear-rigid in effect),
root clamped by three coordinate constraints; the tip body an
ObjectRigidBody2D (mass 1, inertia 0) on its own NodeRigidBody2D, welded to
the end node by an ObjectJointRevolute2D (positions) and an
ObjectConnectorCoordinate between the rotation coordinates (the weld's
rotation row makes the zero-inertia body's matrix regular, as our fixed
joint does); the pulse a LoadForceVector with a symbolic user function.

Ours by tolerance: our FMU driven by fmi2SetupExperiment's relative
tolerance 1e-2 ... 1e-6 (peer_common.FLEXIBLE_TOLERANCES)
over the 10 s (stopTime passed), h_max = the output
interval 0.01 s (the coarsest h of the pairs), the FMU's choice of
integrator (generalized-alpha, the local error split at h_max for
flexible bodies), Newton tolerance following the error tolerance. One
series over every mesh of the pairs (a user picks the mesh for the
spatial error, the tolerance for the time error): n = 32's f1 at h =
1.25e-3 and 6.25e-4, extrapolated in h, is 5e-7 from the analytic value,
below every error its runs reach. The tolerance and the mesh are in the CSV
(columns tolerance, elements).
Exudyn's explicit solvers are left out: they do not take the weld's
ObjectJointRevolute2D ("explicit integrator detected object ... which
contains constraints that cannot be solved", at once, DOPRI5 tried).
Writes tip_mass_precision.csv and .png.
"""

import numpy as np
from scipy.optimize import brentq

from peer_common import EXUDYN, OURS, Panel, PeerStudy, exudyn_beam_line_2d, exudyn_clamp_coordinates, \
    exudyn_settings, exudyn_solve, mesh_and_step, refinement_grid, tolerance_series
from peer_f3_vibration import OUTPUT, PULSE, STOP, exudyn_pulse, first_frequency, frequency_error, ours

L, EI, RHO_A, EA, RHO_I, TIP_MASS = 1.0, 10.0, 1.0, 1e7, 1e-6, 1.0
FORCE = 0.01 * EI / L**2
PAIRS = [(2, 1e-2), (4, 1e-2), (8, 5e-3), (16, 2.5e-3), (32, 1.25e-3)]
GRID = refinement_grid(PAIRS)  # PAIRS plus finer steps on the two coarsest meshes
RHO_INF = 0.9


def tip_mass_frequencies(mu=TIP_MASS / (RHO_A * L), count=4):
    """The first `count` bending frequencies (Hz) of a clamped Euler-Bernoulli
    beam with a tip point mass mu rho A L."""
    g = lambda l: 1 + np.cos(l) * np.cosh(l) + mu * l * (np.cos(l) * np.sinh(l) - np.sin(l) * np.cosh(l))
    x = np.linspace(0.1, 4 * count, 40000)
    v = g(x)
    roots = [brentq(g, x[i], x[i + 1]) for i in np.nonzero(np.sign(v[:-1]) != np.sign(v[1:]))[0][:count]]
    return np.array(roots)**2 * np.sqrt(EI / (RHO_A * L**4)) / (2 * np.pi)


EXACT = tip_mass_frequencies()  # 0.7837757, 8.1785, 25.615, 52.945 Hz


def tip_mass_scene(n):
    return {"format": "mfbd-scene/1", "name": "tip_mass", "solver": {"h_max": 1e-3, "rho_inf": RHO_INF},
            "parameters": {"pulse": {"value": PULSE}},
            "bodies": [{"name": "tip", "mass": TIP_MASS, "inertia": [0, 0, 0], "position": [L, 0, 0]}],
            "joints": [{"name": "weld", "type": "fixed", "parent": {"flexible": "beam", "at": 1.0}, "child": "tip"}],
            "flexible_bodies": [{
                "name": "beam", "beam": {"start": [0, 0, 0], "end": [L, 0, 0], "elements": n, "section_y": [0, 1, 0]},
                "section": {"EA": EA, "GJ": EI, "EIy": EI, "EIz": EI, "rhoA": RHO_A,
                            "rhoJ": [2 * RHO_I, RHO_I, RHO_I]},
                "supports": [{"node": 0, "type": "clamp"}],
                "loads": [{"node": n, "force": [0, FORCE, 0], "scale": "if(pulse - t, sin(pi*t/pulse)^2, 0)"}],
                "outputs": {"nodes": [n]}}]}


def exudyn_beam_2d(n, h):
    import exudyn as exu
    from exudyn.itemInterface import MarkerBodyPosition, MarkerNodeCoordinate, MarkerNodePosition, NodeRigidBody2D, \
        ObjectConnectorCoordinate, ObjectJointRevolute2D, ObjectRigidBody2D, SensorBody

    mbs = exu.SystemContainer().AddSystem()
    nodes = exudyn_beam_line_2d(mbs, n, L, RHO_A, RHO_I, EI, EA, EA)
    exudyn_clamp_coordinates(mbs, nodes[0], 3)
    tip_node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[L, 0.0, 0.0]))
    tip = mbs.AddObject(ObjectRigidBody2D(nodeNumber=tip_node, mass=TIP_MASS, inertia=0.0))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
        mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1])),
        mbs.AddMarker(MarkerBodyPosition(bodyNumber=tip, localPosition=[0.0, 0.0, 0.0]))]))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[-1], coordinate=2)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=tip_node, coordinate=2))]))
    pulse = exudyn_pulse(mbs, nodes[-1], FORCE)  # alive through the solve
    sensor = mbs.AddSensor(SensorBody(bodyNumber=tip, outputVariableType=exu.OutputVariableType.Position,
                                      storeInternal=True, writeToFile=False))
    mbs.Assemble()
    settings = exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF, sensor_period=OUTPUT, sparse=n >= 16)
    wall, statistics = exudyn_solve(mbs, settings)
    data = mbs.GetSensorStoredData(sensor)
    return dict(wall_time_s=wall, f1=first_frequency(data[:, 0], data[:, 2], EXACT), **statistics)


class Study(PeerStudy):
    label, name, repeats = "tip mass", "tip_mass", 2
    settings, xlabel = GRID, "wall time for 10 s simulated [s]"
    annotate = staticmethod(mesh_and_step)

    def codes(self):
        fmus = {n: self.pack(tip_mass_scene(n), f"tip{n}") for n, _ in self.settings}
        by_tolerance = tolerance_series(PAIRS, lambda n, tol: ours(fmus[n], "tip.position.y", None, EXACT, tol))
        return [(OURS, "3D corotational beam, tip body on a fixed joint",
                 lambda n, h: ours(fmus[n], "tip.position.y", h, EXACT)),
                *by_tolerance,
                (EXUDYN, "BeamGeometricallyExact2D, RigidBody2D welded", exudyn_beam_2d)]

    def measure(self, r, code):
        return frequency_error(r, EXACT[0])

    def panels(self, tables):
        return [Panel("relative error of the first bending frequency",
                      "Cantilever with a rigid tip body (mu = 1) on a fixed joint: f1 against "
                      f"{EXACT[0]:.7f} Hz\n(labels: elements / substep)")]


if __name__ == "__main__":
    Study().main(__doc__)
