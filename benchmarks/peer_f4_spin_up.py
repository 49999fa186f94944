#!/usr/bin/env python3
"""F4 spin-up beam (Simo & Vu-Quoc), our FMU against Exudyn, error against
run time over paired refinements (elements n, substep h) = (2, 8e-3),
(2, 8e-3), (4, 4e-3), (8, 2e-3), (16, 1e-3), (32, 5e-4) and the finer steps on n = 2 and 4; each run simulates 20 s and yields
  * error: the tip deflection in the rotating frame at t = 7 s against a
    converged run of our FMU (n = 64 and 128 at h = 5e-4, extrapolated in n
    with the measured order 2; written to f4_spin_up_reference.csv with the
    same extrapolation of Exudyn's, as a cross-check);
  * elongation_error: the mean over 17 s <= t <= 20 s (steady spin at
    6 rad/s) of the beam's elongation, the polyline length through the nodes
    minus L, against the extensible bar's closed form tan(kL)/k - L =
    5.143175e-4 m (k^2 = rho A omega^2/EA); rho A omega^2 L^3/(3 EA) =
    5.142857e-4 m of shared/benchmarks is its first term, 3.2e-8 m lower
    (elongation_error_vs_linear in the CSV).
Wall time: the whole 20 s run (outputs every 0.04 s in both codes).

Same data for both codes: L = 10, EA = 2.8e7, GA = 1e7, EI = 1.4e4,
rho A = 1.2, rho I = 6e-4, hub angle prescribed at the root node,
theta(t) = (6/15)(t^2/2 + (15/(2 pi))^2 (cos(2 pi t/15) - 1)) up to 15 s, then
45 + 6 (t - 15); generalized-alpha rho_inf = 0.8; Newton stops on the
increment, 1e-12.

Ours: examples/spin_up_beam (3D corotational Timoshenko beam, consistent
centre-line mass, shallow-arch local strain, 6 coordinates per node; "driven" support).
Exudyn: ObjectBeamGeometricallyExact2D (2D Simo-Reissner, 3 coordinates per
node); root x, y held by coordinate constraints and the root rotation
coordinate driven by a coordinate constraint whose offset is theta(t), given
as an Exudyn symbolic user function (an expression tree evaluated in C++, so
no Python call per Newton iteration).

Ours by tolerance: our FMU driven by fmi2SetupExperiment's relative
tolerance 1e-2 ... 1e-6 (peer_common.FLEXIBLE_TOLERANCES)
over the 20 s (stopTime passed), h_max = the output
interval 0.04 s, the FMU's choice of integrator (generalized-alpha, the
local error split at h_max for flexible bodies), Newton tolerance
following the error tolerance. One series over every mesh of the pairs (a user
picks the mesh for the spatial error, the tolerance for the time error):
n = 32 at h = 5e-4 has its tip deflection 3e-8 m from the reference, below
every error its runs reach (its steady elongation, though, is 2.0e-8 m
from the closed form at every h: a floor at a fifth of the 1e-7 m level).
The tolerance is in the CSV (column tolerance, and elements).
Exudyn's explicit solvers are left out: under DOPRI5 (tolerance 1e-3,
n = 32; 0.04 s for the 20 s, 101 steps) the offset user function of the
driving coordinate constraint is not applied: the beam stays at rest
(elongation 0, tip "deflection" -L sin(theta(7 s)) = 8.376 m). Exudyn's
explicit solvers hold coordinate constraints at their values, without the
drive, so the problem cannot be posed to them this way.
Writes f4_spin_up_precision.csv, f4_spin_up_reference.csv and f4_spin_up_precision.png.
"""

import numpy as np

from peer_common import EXUDYN, OURS, Panel, PeerStudy, our_run, exudyn_beam_line_2d, exudyn_clamp_coordinates, \
    exudyn_explicit_settings, exudyn_settings, exudyn_solve, exudyn_spin_up_drive, extrapolated_references, extrapolated_value, load_scene, \
    mesh_and_step, refinement_grid, spin_up_angle, tolerance_series

L, EA, GA, EI, RHO_A, RHO_I = 10.0, 2.8e7, 1e7, 1.4e4, 1.2, 6e-4
T_UP, OMEGA = 15.0, 6.0
ELONGATION_LINEAR = RHO_A * OMEGA**2 * L**3 / (3 * EA)  # 5.142857e-4 m (shared/benchmarks F4)
# The same bar with the centrifugal load on the displaced position,
# EA u'' + rho A omega^2 (x + u) = 0, u(0) = 0, u'(L) = 0: u(L) = tan(kL)/k - L,
# k^2 = rho A omega^2 / EA. 3.2e-8 m above the linear value; both codes model it.
_K = np.sqrt(RHO_A * OMEGA**2 / EA)
ELONGATION = np.tan(_K * L) / _K - L  # 5.143175e-4 m
PAIRS = [(2, 8e-3), (4, 4e-3), (8, 2e-3), (16, 1e-3), (32, 5e-4)]
GRID = refinement_grid(PAIRS)  # PAIRS plus finer steps on the two coarsest meshes
REFERENCE = [(64, 5e-4), (128, 5e-4)]
STOP, OUTPUT, T_TIP, STEADY = 20.0, 0.04, 7.0, (17.0, 20.0)  # every h divides OUTPUT
RHO_INF = 0.8


def hub_angle(t):
    return spin_up_angle(np.asarray(t, dtype=float), OMEGA, T_UP)


def measures(t, nodes):
    """nodes: (time, node, xy). Tip deflection in the rotating frame at T_TIP
    and mean elongation over the steady window."""
    k = int(np.argmin(np.abs(t - T_TIP)))
    assert abs(t[k] - T_TIP) < 1e-6, t[k]
    theta = hub_angle(t[k])
    tip = float(-np.sin(theta) * nodes[k, -1, 0] + np.cos(theta) * nodes[k, -1, 1])
    length = np.sum(np.linalg.norm(np.diff(nodes, axis=1), axis=2), axis=1)
    steady = (t >= STEADY[0] - 1e-9) & (t <= STEADY[1] + 1e-9)
    elongation = float(np.mean(length[steady]) - L) if steady.any() else float("nan")
    return tip, elongation


def spin_up_scene(n):
    scene = load_scene("spin_up_beam")
    body = scene["flexible_bodies"][0]
    body["beam"]["elements"] = n
    body["outputs"] = {"nodes": "all"}
    return scene


def ours(fmu, n, h, stop, tolerance=None):
    """Substeps of h, or driven by a tolerance (peer_common.our_run)."""
    run = our_run(fmu, h, OUTPUT, stop, tolerance, {"solver.rho_inf": RHO_INF})
    names = [f"beam.node{i}.position.{c}" for i in range(n + 1) for c in "xy"]
    s, wall, statistics = run.sample(names, stop, OUTPUT)
    samples = s[1:]  # from t = OUTPUT on
    times = OUTPUT * np.arange(1, len(samples) + 1)
    tip, elongation = measures(times, samples.reshape(len(times), n + 1, 2))
    return dict(wall_time_s=wall, tip=tip, elongation=elongation, **statistics,
                **({"tolerance": tolerance, "elements": n} if tolerance else {}))


def exudyn_beam_2d(n, h, stop, solver=None, tolerance=None):
    """Exudyn's run: generalized-alpha at substep h, or one of its explicit
    solvers (RK44 at h, DOPRI5 / ODE23 to `tolerance`); a `stop` before
    T_TIP only to time a trial (no measures then)."""
    import exudyn as exu
    from exudyn.itemInterface import SensorNode

    mbs = exu.SystemContainer().AddSystem()
    nodes = exudyn_beam_line_2d(mbs, n, L, RHO_A, RHO_I, EI, EA, GA)
    root = exudyn_clamp_coordinates(mbs, nodes[0], 3)
    drive = exudyn_spin_up_drive(mbs, root[2], OMEGA, T_UP)  # alive through the solve
    sensors = [mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=exu.OutputVariableType.Position,
                                        storeInternal=True, writeToFile=False)) for node in nodes]
    mbs.Assemble()
    settings = (exudyn_explicit_settings(solver, stop, h, tolerance, sensor_period=OUTPUT) if solver
                else exudyn_settings(end_time=stop, h=h, rho_inf=RHO_INF, sensor_period=OUTPUT, sparse=n >= 16))
    wall, statistics = exudyn_solve(mbs, settings)
    if stop < T_TIP:
        return dict(wall_time_s=wall, **statistics)
    data = [mbs.GetSensorStoredData(s) for s in sensors]
    t = data[0][:, 0]
    tip, elongation = measures(t, np.stack([d[:, 1:3] for d in data], axis=1))
    return dict(wall_time_s=wall, tip=tip, elongation=elongation, **statistics)


class Study(PeerStudy):
    label, name, repeats = "F4", "f4_spin_up", 2
    settings, xlabel = GRID, "wall time for 20 s simulated [s]"
    annotate = staticmethod(mesh_and_step)
    tables = ("precision", "reference")

    def runs(self, stop):
        return [(OURS, lambda n, h: ours(self.fmus[n], n, h, stop)), (EXUDYN, lambda n, h: exudyn_beam_2d(n, h, stop))]

    def codes(self):
        models = {OURS: "3D corotational beam, consistent mass, shallow-arch strain", EXUDYN: "BeamGeometricallyExact2D"}
        return [(code, models[code], run) for code, run in self.runs(STOP)] + tolerance_series(
            PAIRS, lambda n, tol: ours(self.fmus[n], n, None, STOP, tol))

    def run(self):
        self.fmus = {n: self.pack(spin_up_scene(n), f"spin{n}")
                     for n in {n for n, _ in self.settings + REFERENCE}}
        reference, values = extrapolated_references("F4", self.runs(T_TIP), REFERENCE, "tip", "tip_deflection_7s_m")
        self.reference = values[OURS]
        print(f"F4 reference tip deflection at 7 s: ours {values[OURS]:.9f} m, Exudyn {values[EXUDYN]:.9f} m",
              flush=True)
        return dict(super().run(), reference=reference)

    def measure(self, r, code):
        """Tip deflection and steady elongation errors."""
        return dict(error=abs(r["tip"] - self.reference), elongation_error=abs(r["elongation"] - ELONGATION),
                    elongation_error_vs_linear=abs(r["elongation"] - ELONGATION_LINEAR), tip_deflection_7s_m=r["tip"],
                    elongation_m=r["elongation"], **{k: r[k] for k in ("tolerance", "elements") if k in r})

    def panels(self, tables):
        reference = extrapolated_value(tables["reference"], "tip_deflection_7s_m")
        return [Panel("tip deflection error at t = 7 s [m]",
                      f"F4 spin-up: tip deflection (rotating frame) at 7 s vs converged {reference:.6f} m"),
                Panel("|mean elongation over 17-20 s - tan(kL)/k + L| [m]",
                      f"F4 steady elongation vs {ELONGATION:.6e} m (labels: elements / substep)", "elongation_error")]


if __name__ == "__main__":
    Study().main(__doc__)
