#!/usr/bin/env python3
"""F5 flexible slider-crank (Simo & Vu-Quoc; Jonker), our FMU against Exudyn:
error of the rod's mid-span deflection curve against run time, over paired
refinements (elements n, substep h) = PAIRS below; each run simulates 0.4 s.

Problem (examples/flexible_slider_crank): rigid crank 0.15 m, its angle
driven by a smooth spin-up to 150 rad/s over T = 0.15 s, then constant,
theta(t) = (omega/T)(t^2/2 + (T/(2 pi))^2 (cos(2 pi t/T) - 1)) up to T, then
omega T/2 + omega (t - T); flexible steel rod 0.30 m, circle d = 6 mm,
E = 200 GPa, nu = 0.3, rho = 7870 (EA = 5.655e6 N, GA = 1.928e6 N with the
shear factor 6(1+nu)/(7+6nu), EI = 12.72 N m^2, rho A = 0.2225 kg/m,
rho I = 5.007e-7 kg m); massless slider on a prismatic joint along x,
pinned to the rod's end. No gravity. Generalized-alpha rho_inf = 0.8;
Newton stops on the increment, 1e-12.

Metric: mid-span deflection d(t) = the transverse offset of the rod's mid
node from the chord through its end nodes (tests/python/test_mfbd.py
slider_crank_midspan_deflection), sampled every 1 ms over 0 < t <= 0.4 s.
error = max over the samples of |d(t) - d_ref(t)|, d_ref a converged run of
the same code (REFERENCE below). The two codes' converged curves are
compared with each other (f5_slider_crank_reference.csv: max difference and
the largest deflection); the error of each code's runs against the other
code's reference is in the CSV too (error_vs_other_reference).

Ours: the scene as it is (crank on a driven revolute joint; rod ends on
revolute joints to the crank and to the massless slider: two virtual bodies
and flexible body joints; 3D corotational beam, 6 coordinates per node).
Exudyn, 2D: crank ObjectRigidBody2D on an ObjectJointRevolute2D to ground,
its rotation coordinate driven by an ObjectConnectorCoordinate whose offset
is theta(t) (symbolic user functions); ObjectBeamGeometricallyExact2D rod;
crank pin ObjectJointRevolute2D (crank point - rod node 0); the massless
slider on its prismatic joint with a pin to the rod's end is modelled by
what it imposes, an ObjectConnectorCoordinate holding the end node's y at 0
(Exudyn cannot carry a massless body without a singular mass matrix).
Wall time: the whole 0.4 s run, outputs every 1 ms in both codes.

Ours by tolerance: our FMU driven by fmi2SetupExperiment's relative
tolerance 1e-2 ... 1e-6 (peer_common.FLEXIBLE_TOLERANCES)
over the 0.4 s (stopTime passed), h_max = the
output interval 1e-3 s, the FMU's choice of integrator (generalized-alpha,
the local error split at h_max for flexible bodies), Newton tolerance
following the error tolerance. One series over every mesh of the pairs (a
user picks the mesh for the spatial error, the tolerance for the time
error; n = 32's runs at tolerance 1e-7 and 1e-8 are 6.8e-8 and 3.9e-7 m from the
n = 64 reference, whose own time error, about a quarter of n = 32's
1.4e-6 m at twice its step, is about 4e-7 m: the spatial error is below
that, far below the levels compared, 1e-3 ... 1e-5 m, and the measure
resolves nothing under about 4e-7 m); error against our reference as for
every run of ours. The tolerance is in the CSV (column tolerance, and elements).
Exudyn's explicit solvers are left out: they do not take the crank's
ObjectJointRevolute2D ("explicit integrator detected object ... which
contains constraints that cannot be solved", at once, DOPRI5 tried).
Writes f5_slider_crank_precision.csv, f5_slider_crank_reference.csv and
f5_slider_crank_precision.png (error against wall time; the curves).
"""

import numpy as np

from peer_common import EXUDYN, OURS, Panel, PeerStudy, our_run, draw_curves, exudyn_beam_line_2d, exudyn_settings, \
    exudyn_solve, exudyn_spin_up_drive, figure, load_scene, save_figure, sweep, tolerance_series

CRANK, ROD, OMEGA, T_UP = 0.15, 0.30, 150.0, 0.15
E, NU, RHO, D = 2e11, 0.3, 7870.0, 0.006
AREA, I_AREA = np.pi * D**2 / 4, np.pi * D**4 / 64
EA, EI = E * AREA, E * I_AREA
GA = 6 * (1 + NU) / (7 + 6 * NU) * E / (2 * (1 + NU)) * AREA
RHO_A, RHO_I = RHO * AREA, RHO * I_AREA
CRANK_MASS, CRANK_INERTIA = 0.1, 7.5e-4
STOP, OUTPUT = 0.4, 1e-3
PAIRS = [(2, 5e-4), (4, 2.5e-4), (8, 1.25e-4), (16, 6.25e-5), (32, 3.125e-5)]  # every h divides OUTPUT
REFERENCE = (64, 1.5625e-5)
RHO_INF = 0.8


def midspan_deflection(p0, pm, pn):
    """Offset of the mid node pm from the chord p0 -> pn (arrays (time, 2)),
    positive to the left of the chord."""
    chord = pn - p0
    chord /= np.linalg.norm(chord, axis=1)[:, None]
    offset = pm - 0.5 * (p0 + pn)
    return chord[:, 0] * offset[:, 1] - chord[:, 1] * offset[:, 0]


def slider_crank_scene(n):
    scene = load_scene("flexible_slider_crank")
    scene["flexible_bodies"][0]["beam"]["elements"] = n
    scene["flexible_bodies"][0]["outputs"] = {"nodes": [0, n // 2, n]}
    scene["solver"]["rho_inf"] = RHO_INF
    return scene


def ours(fmu, n, h, tolerance=None):
    """Substeps of h, or driven by a tolerance (peer_common.our_run)."""
    run = our_run(fmu, h, OUTPUT, STOP, tolerance)
    names = [f"rod.node{i}.position.{c}" for i in (0, n // 2, n) for c in "xy"]
    s, wall, statistics = run.sample(names, STOP, OUTPUT)
    p = s[1:].reshape(-1, 3, 2)  # from t = OUTPUT on
    return dict(wall_time_s=wall, deflection=midspan_deflection(p[:, 0], p[:, 1], p[:, 2]), **statistics,
                **({"tolerance": tolerance, "elements": n} if tolerance else {}))


def exudyn_slider_crank_2d(n, h):
    import exudyn as exu
    from exudyn.itemInterface import MarkerBodyPosition, MarkerNodeCoordinate, MarkerNodePosition, \
        NodePointGround, NodeRigidBody2D, ObjectConnectorCoordinate, ObjectGround, ObjectJointRevolute2D, \
        ObjectRigidBody2D, SensorNode

    mbs = exu.SystemContainer().AddSystem()
    nodes = exudyn_beam_line_2d(mbs, n, ROD, RHO_A, RHO_I, EI, EA, GA, start=CRANK)
    crank_node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[CRANK / 2, 0.0, 0.0]))
    crank = mbs.AddObject(ObjectRigidBody2D(nodeNumber=crank_node, mass=CRANK_MASS, inertia=CRANK_INERTIA))
    ground = mbs.AddObject(ObjectGround())
    ground_node = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    fixed = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
        mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0])),
        mbs.AddMarker(MarkerBodyPosition(bodyNumber=crank, localPosition=[-CRANK / 2, 0.0, 0.0]))]))
    drive = mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
        fixed, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=crank_node, coordinate=2))]))
    functions = exudyn_spin_up_drive(mbs, drive, OMEGA, T_UP)  # alive through the solve
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
        mbs.AddMarker(MarkerBodyPosition(bodyNumber=crank, localPosition=[CRANK / 2, 0.0, 0.0])),
        mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[0]))]))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
        fixed, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[-1], coordinate=1))]))
    sensors = [mbs.AddSensor(SensorNode(nodeNumber=nodes[i], outputVariableType=exu.OutputVariableType.Position,
                                        storeInternal=True, writeToFile=False)) for i in (0, n // 2, n)]
    mbs.Assemble()
    settings = exudyn_settings(end_time=STOP, h=h, rho_inf=RHO_INF, sensor_period=OUTPUT, sparse=n >= 16)
    wall, statistics = exudyn_solve(mbs, settings)
    data = [mbs.GetSensorStoredData(s) for s in sensors]
    t = data[0][:, 0]
    keep = t > 0.5 * OUTPUT  # the sensors also store t = 0
    assert np.allclose(t[keep], OUTPUT * np.arange(1, keep.sum() + 1), atol=1e-9), t[:3]
    return dict(wall_time_s=wall, deflection=midspan_deflection(*(d[keep, 1:3] for d in data)), **statistics)


class Study(PeerStudy):
    label, name, repeats = "F5", "f5_slider_crank", 2
    settings, xlabel = PAIRS, "wall time for 0.4 s simulated [s]"
    tables, curves = ("precision", "reference"), True

    def codes(self):
        return [(OURS, "crank on driven revolute, massless slider, 3D corotational rod",
                 lambda n, h: ours(self.fmus[n], n, h)),
                (EXUDYN, "RigidBody2D crank, coordinate drive, BeamGeometricallyExact2D rod", exudyn_slider_crank_2d),
                *tolerance_series(PAIRS, lambda n, tol: ours(self.fmus[n], n, None, tol))]

    def run(self):
        """Each code's converged curve first (REFERENCE), then the sweep
        against it; the runs' curves are kept for the figure."""
        self.fmus = {n: self.pack(slider_crank_scene(n), f"crank{n}")
                     for n in {n for n, _ in self.settings + [REFERENCE]}}
        self.reference, reference_rows = {}, []
        for code, _, run, *tolerances in self.codes():
            if tolerances:
                continue  # the tolerance-driven series: no reference run of its own
            r = run(*REFERENCE)
            self.reference[code] = r["deflection"]
            reference_rows.append(dict(code=code, h_or_elements=REFERENCE[0], wall_time_s=r["wall_time_s"],
                                       error="", h_s=REFERENCE[1],
                                       max_abs_deflection_m=float(np.abs(r["deflection"]).max()),
                    **{k: r[k] for k in ("tolerance", "elements") if k in r}))
            print(f"F5 reference {code:9s} n={REFERENCE[0]} h={REFERENCE[1]:.1e}: largest |deflection| "
                  f"{np.abs(r['deflection']).max():.6e} m, wall {r['wall_time_s']:.2f} s", flush=True)
        self.agreement = float(np.abs(self.reference[OURS] - self.reference[EXUDYN]).max())
        for row in reference_rows:
            row["max_abs_difference_between_codes_m"] = self.agreement
        print(f"F5 converged curves, ours against Exudyn: max |difference| {self.agreement:.3e} m "
              f"({self.agreement / np.abs(self.reference[OURS]).max():.2e} of the largest deflection)", flush=True)
        self.results = {}
        rows = sweep(self.label, self.codes(), self.settings, self.args.repeats, self.measure, self.results)
        return dict(precision=rows, reference=reference_rows)

    def measure(self, r, code):
        other = EXUDYN if code == OURS else OURS
        return dict(error=float(np.abs(r["deflection"] - self.reference[code]).max()),
                    error_vs_other_reference=float(np.abs(r["deflection"] - self.reference[other]).max()),
                    max_abs_deflection_m=float(np.abs(r["deflection"]).max()),
                    **{k: r[k] for k in ("tolerance", "elements") if k in r})

    def draw(self, tables, png):
        fig, (a, b) = figure(2, (12, 4.8))
        self.draw_panel(a, tables["precision"], Panel(
            "max |d(t) - d_ref(t)| over 0..0.4 s [m]",
            f"F5 slider-crank: mid-span deflection vs converged run of the same code\n"
            f"(n = {REFERENCE[0]}, h = {REFERENCE[1]:g}; labels: elements, h = 1e-3/n)"))
        t = OUTPUT * np.arange(1, len(self.reference[OURS]) + 1)
        coarse = self.settings[1]
        draw_curves(b, t, [(1e3 * self.reference[OURS], "C0-", 1.5, f"{OURS}, n = {REFERENCE[0]}"),
                           (1e3 * self.reference[EXUDYN], "C3--", 1.5, f"{EXUDYN}, n = {REFERENCE[0]}"),
                           (1e3 * self.results[(OURS, coarse)]["deflection"], "C9:", 1, f"{OURS}, n = {coarse[0]}"),
                           (1e3 * self.results[(EXUDYN, coarse)]["deflection"], "C1:", 1,
                            f"{EXUDYN}, n = {coarse[0]}")],
                    "mid-span deflection [mm]", f"converged curves differ by at most {self.agreement:.2e} m")
        save_figure(fig, png)


if __name__ == "__main__":
    Study().main(__doc__)
