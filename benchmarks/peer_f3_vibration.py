#!/usr/bin/env python3
"""F3 cantilever vibration, our FMU against Exudyn: error of the first
bending frequency against Euler-Bernoulli, f1 = 1.875104^2/(2 pi) sqrt(EI/(rho A L^4)),
over the paired refinements (elements n, substep h) = (2, 1e-2), (4, 1e-2), (8, 5e-3),
(16, 2.5e-3), (32, 1.25e-3) and the finer steps on n = 2 and 4
(peer_common.refinement_grid), and the wall time of the run.

Same procedure for both codes: L = 1, EI = 1, rho A = 1, EA = 1e6, clamped
root, a tip force 0.01 EI/L^2 sin^2(pi t/0.02 s) for 0.02 s (the
cantilever_vibration scene), free vibration to 10 s, tip y sampled every
0.01 s; f1 from a least-squares fit of the first four bending modes
(undamped sinusoids, frequencies fitted, amplitudes solved linearly) to the
tip signal over 1 s <= t <= 10 s. Generalized-alpha rho_inf = 0.9 (the
scene's), Newton increment tolerance 1e-12.

Ours: examples/cantilever_vibration (3D corotational beam, shear-rigid,
consistent centre-line mass, shallow-arch local strain, lumped rotary inertia, rho J = (2e-6, 1e-6, 1e-6)).
Exudyn: ObjectBeamGeometricallyExact2D (GA = EA, rho I = 1e-6); the pulse is a
LoadForceVector with a symbolic load user function. Shear and rotary inertia
move f1 by about 1e-6 relative, below every error measured here.

Ours by tolerance: our FMU driven by fmi2SetupExperiment's relative
tolerance 1e-2 ... 1e-6 (peer_common.FLEXIBLE_TOLERANCES)
over the 10 s (stopTime passed), h_max = the output
interval 0.01 s (the coarsest h of the pairs), the FMU's choice of
integrator (generalized-alpha, the local error split at h_max for
flexible bodies; benchmarks/README.md "Tolerance proportionality"), Newton
tolerance following the error tolerance. One series over every mesh of the
pairs (a user picks the mesh for the spatial error, the tolerance for the
time error): n = 32's f1 at h = 1.25e-3 and 6.25e-4, extrapolated in h,
is 9e-6 from Euler-Bernoulli (space and fit), a tenth of the 1e-4 the
fixed-step series of both codes reach at best; its runs level off
there, the coarser ones higher. The tolerance and the mesh are in the CSV
(columns tolerance, elements; h_or_elements holds the tolerance too).
Exudyn's explicit solvers are left out: DOPRI5 at tolerance 1e-3 on n = 32
took 51 s for the first 0.1 s (123,307 steps of about 8e-7 s, held by the
stability of the beam's shear and axial modes, rho I = 1e-6 against
GA = EA = 1e6), about 5,000 s for the 10 s; RK44 needs steps as short.
Writes f3_vibration_precision.csv and .png.
"""

import numpy as np
from scipy.optimize import least_squares

from peer_common import EXUDYN, OURS, Panel, PeerStudy, our_run, cantilever_scene, exudyn_beam_line_2d, \
    exudyn_clamp_coordinates, exudyn_explicit_settings, exudyn_settings, exudyn_solve, mesh_and_step, \
    refinement_grid, tolerance_series

L, EI, RHO_A, EA, RHO_I = 1.0, 1.0, 1.0, 1e6, 1e-6
PULSE, FORCE = 0.02, 0.01 * EI / L**2
BETA_L = np.array([1.875104, 4.694091, 7.854757, 10.995541])
EXACT = BETA_L**2 / (2 * np.pi) * np.sqrt(EI / (RHO_A * L**4))  # f1 = 0.559596 Hz
PAIRS = [(2, 1e-2), (4, 1e-2), (8, 5e-3), (16, 2.5e-3), (32, 1.25e-3)]
GRID = refinement_grid(PAIRS)  # PAIRS plus finer steps on the two coarsest meshes
STOP, OUTPUT, FIT_FROM = 10.0, 0.01, 1.0
RHO_INF = 0.9


def first_frequency(t, y, modes=EXACT):
    """f1 from a fit of undamped modes (plus offset) to y(t), t >= FIT_FROM,
    one per frequency of `modes` (default: the four Euler-Bernoulli ones).
    Starting guesses: the spectral peak of each mode, searched within
    0.6 ... 1.8 times its exact frequency (a coarse mesh moves the
    higher modes far from it, and a fit started there can settle wrongly)."""
    keep = t >= FIT_FROM - 1e-9
    t, y = t[keep], (y[keep] - y[keep].mean()) / y[keep].std()
    pad = 16 * len(t)
    spectrum = np.abs(np.fft.rfft(y * np.hanning(len(t)), pad))
    frequencies = np.fft.rfftfreq(pad, t[1] - t[0])
    guesses = []
    for f in modes:
        band = (frequencies > 0.6 * f) & (frequencies < 1.8 * f)
        guesses.append(frequencies[band][np.argmax(spectrum[band])] if band.any() else f)

    def residual(f):
        w = 2 * np.pi * np.asarray(f)
        basis = np.column_stack([np.ones_like(t)] + [g(wi * t) for wi in w for g in (np.cos, np.sin)])
        return basis @ np.linalg.lstsq(basis, y, rcond=None)[0] - y

    guesses = np.array(guesses)
    fit = least_squares(residual, guesses, x_scale=0.01 * guesses, xtol=1e-13, ftol=1e-13, gtol=1e-13)
    return float(fit.x[0])


def vibration_scene(n):
    scene = cantilever_scene("cantilever_vibration", n)
    scene["solver"]["rho_inf"] = RHO_INF
    return scene


def ours(fmu, signal, h, modes=EXACT, tolerance=None):
    """f1 of our run (peer_common.our_run): `signal` (a tip's y) sampled
    every OUTPUT from t = OUTPUT on."""
    run = our_run(fmu, h, OUTPUT, STOP, tolerance)
    s, wall, statistics = run.sample([signal], STOP, OUTPUT)
    tip = s[1:, 0]  # from t = OUTPUT on
    t = OUTPUT * np.arange(1, len(tip) + 1)
    return dict(wall_time_s=wall, f1=first_frequency(t, tip, modes), **statistics,
                **({"tolerance": tolerance} if tolerance else {}))


def exudyn_pulse(mbs, node, force):
    """The tip force pulse force sin^2(pi t/PULSE) along y for t < PULSE on an
    Exudyn node, as a symbolic user function; returns it (it must stay alive
    through the solve)."""
    import exudyn as exu
    from exudyn.advancedUtilities import CreateSymbolicUserFunction
    from exudyn.itemInterface import LoadForceVector, MarkerNodePosition

    def pulse(mbs, t, loadVector):
        s = exu.symbolic.sin(np.pi / PULSE * t)
        return [0, exu.symbolic.IfThenElse(t < PULSE, force * s * s, exu.symbolic.Real(0.0)), 0]

    load = mbs.AddLoad(LoadForceVector(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=node)),
                                       loadVector=[0.0, 0.0, 0.0]))
    function = CreateSymbolicUserFunction(mbs, pulse, "loadVectorUserFunction", load)
    mbs.SetLoadParameter(load, "loadVectorUserFunction", function)
    return function


def exudyn_beam_2d(n, h, solver=None, tolerance=None, stop=STOP):
    """Exudyn's run: generalized-alpha at substep h, or one of its explicit
    solvers (RK44 at h, DOPRI5 / ODE23 to `tolerance`); `stop` shorter than
    STOP only to time a trial (no f1 then)."""
    import exudyn as exu
    from exudyn.itemInterface import SensorNode

    mbs = exu.SystemContainer().AddSystem()
    nodes = exudyn_beam_line_2d(mbs, n, L, RHO_A, RHO_I, EI, EA, EA)
    exudyn_clamp_coordinates(mbs, nodes[0], 3)
    pulse = exudyn_pulse(mbs, nodes[-1], FORCE)  # alive through the solve
    sensor = mbs.AddSensor(SensorNode(nodeNumber=nodes[-1], outputVariableType=exu.OutputVariableType.Position,
                                      storeInternal=True, writeToFile=False))
    mbs.Assemble()
    settings = (exudyn_explicit_settings(solver, stop, h, tolerance, sensor_period=OUTPUT) if solver
                else exudyn_settings(end_time=stop, h=h, rho_inf=RHO_INF, sensor_period=OUTPUT, sparse=n >= 16))
    wall, statistics = exudyn_solve(mbs, settings)
    if stop < STOP:
        return dict(wall_time_s=wall, **statistics)
    data = mbs.GetSensorStoredData(sensor)
    return dict(wall_time_s=wall, f1=first_frequency(data[:, 0], data[:, 2]), **statistics)


def frequency_error(r, exact=EXACT[0]):
    """f1's relative error against `exact` (Euler-Bernoulli's here), and
    the run's tolerance and mesh where it has them."""
    return dict(error=abs(r["f1"] / exact - 1), f1_hz=r["f1"],
                **{k: r[k] for k in ("tolerance", "elements") if k in r})


class Study(PeerStudy):
    label, name, repeats = "F3", "f3_vibration", 2
    settings, xlabel = GRID, "wall time for 10 s simulated [s]"
    annotate = staticmethod(mesh_and_step)

    def codes(self):
        fmus = {n: self.pack(vibration_scene(n), f"vibration{n}") for n, _ in self.settings}
        by_tolerance = tolerance_series(
            PAIRS, lambda n, tol: ours(fmus[n], f"beam.node{n}.position.y", None, tolerance=tol))
        return [(OURS, "3D corotational beam, consistent mass, shallow-arch strain",
                 lambda n, h: ours(fmus[n], f"beam.node{n}.position.y", h)),
                *by_tolerance,
                (EXUDYN, "BeamGeometricallyExact2D", exudyn_beam_2d)]

    def measure(self, r, code):
        return frequency_error(r)

    def panels(self, tables):
        return [Panel("relative error of the first bending frequency",
                      f"F3 cantilever: f1 against Euler-Bernoulli {EXACT[0]:.6f} Hz (labels: elements / substep)")]


if __name__ == "__main__":
    Study().main(__doc__)
