#!/usr/bin/env python3
"""Error against run time for the IFToMM pendulum (R1), through the FMU.

For substep sizes h and spectral radii rho_inf: wall time of the run (10 s of
simulated time, communication step 0.1 s), the largest bob position error
against the exact solution (Jacobi elliptic functions) over all output points,
the error at t = 10 s against the published R1 values, and Newton iterations
per substep. Writes pendulum_precision.csv and .png, and prints the measured
convergence order.
"""
import argparse
import pathlib
import re
import sys
import time

import numpy as np
from scipy.special import ellipj, ellipk

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests" / "python"))
from conftest import FMUS, Slave  # noqa: E402

G, L = 9.81, 1.0
R1_AT_10S = (0.275087462576, -0.961419205099)


def exact_position(t):
    """Released at rest from horizontal: sin(theta/2) = k sn(K - w t, k), theta from down."""
    k = np.sin(np.pi / 4.0)
    sn, _, _, _ = ellipj(ellipk(k * k) - np.sqrt(G / L) * t, k * k)
    theta = 2.0 * np.arcsin(k * sn)
    return L * np.sin(theta), -L * np.cos(theta)


def run(fmu, h, rho, stop=10.0, communication=0.1):
    s = Slave(fmu)
    try:
        assert s.instantiate(logging_on=True)
        s.call("setDebugLogging", True, ["logStep"])
        s.call("setupExperiment", None, 0.0, None)
        s.set("solver.h_max", h)
        s.set("solver.rho_inf", rho)
        start = time.perf_counter()
        s.call("enterInitializationMode")
        s.call("exitInitializationMode")
        t, errors = 0.0, []
        n = int(round(stop / communication))
        positions = []
        for k in range(n):
            assert s.step(t, communication) == 0, s.messages()
            t = (k + 1) * communication
            positions.append((t, *s.get("bob.position.x", "bob.position.y")))
        wall = time.perf_counter() - start
        p = np.array(positions)
        ex, ey = exact_position(p[:, 0])
        errors = np.hypot(p[:, 1] - ex, p[:, 2] - ey)
        at10 = np.hypot(p[-1, 1] - R1_AT_10S[0], p[-1, 2] - R1_AT_10S[1])
        last = [m for _, c, m in s.log if c == "logStep"][-1]
        substeps, iterations = map(int, re.search(r"substeps (\d+), Newton iterations (\d+)", last).groups())
        return wall, errors.max(), at10, iterations / substeps, substeps
    finally:
        s.free()


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("benchmarks/results"))
    parser.add_argument("--fmu", type=pathlib.Path, default=FMUS / "pendulum.fmu")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    steps = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5]
    rhos = [0.0, 0.5, 0.8, 1.0]
    rows = []
    for rho in rhos:
        for h in steps:
            wall, err, at10, its, substeps = min((run(args.fmu, h, rho) for _ in range(3)), key=lambda r: r[0])
            rows.append((h, rho, wall, err, at10, its, substeps))
            print(f"h={h:8.1e} rho_inf={rho:3.1f}  wall {wall*1e3:8.2f} ms  max error {err:9.2e} m  "
                  f"error at 10 s {at10:9.2e} m  Newton it/step {its:4.2f}")
    data = np.array(rows)
    csv = args.out / "pendulum_precision.csv"
    np.savetxt(csv, data, delimiter=",", comments="",
               header="h_s,rho_inf,wall_time_s,max_position_error_m,error_at_10s_m,newton_iterations_per_step,substeps")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    orders = {}
    for rho in rhos:
        d = data[data[:, 1] == rho]
        a.loglog(d[:, 2], d[:, 3], "o-", label=f"rho_inf = {rho}")
        b.loglog(d[:, 0], d[:, 3], "o-", label=f"rho_inf = {rho}")
        fit = d[d[:, 0] <= 1e-3]  # asymptotic range
        orders[rho] = np.polyfit(np.log(fit[:, 0]), np.log(fit[:, 3]), 1)[0]
    a.set_xlabel("wall time for 10 s simulated [s]")
    a.set_ylabel("max bob position error [m]")
    a.set_title("R1 pendulum through the FMU: error against run time")
    b.set_xlabel("substep h [s]")
    b.set_ylabel("max bob position error [m]")
    b.set_title("convergence: " + ", ".join(f"{r}: {o:.2f}" for r, o in orders.items()), fontsize=9)
    for ax in (a, b):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    png = args.out / "pendulum_precision.png"
    fig.savefig(png, dpi=110)
    for rho, o in orders.items():
        print(f"measured convergence order (h <= 1e-3), rho_inf = {rho}: {o:.3f}")
    print(f"wrote {csv.resolve()}\nwrote {png.resolve()}")


if __name__ == "__main__":
    main()
