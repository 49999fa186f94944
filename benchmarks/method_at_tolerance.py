#!/usr/bin/env python3
"""One scene, one integrator (solver.method), one tolerance: the error of
the final outputs against an independent reference and the wall time of
the run through the FMU, as a C master drives it (benchmarks/fmu_loop.c).

    python benchmarks/method_at_tolerance.py pendulum --method dormand_prince --tolerance 1e-8
    python benchmarks/method_at_tolerance.py pendulum --method generalized_alpha --tolerance 1e-6 --h-max 1e-3

References: pendulum (R1: bob position at `stop`) and double_pendulum (R2:
the second bar's centre) from their equations of motion by scipy's DOP853
at rtol 1e-13. Timing as the peer studies (peer_common): enter
initialization mode .. the last fmi2DoStep, the best of `repeats` runs.
`measure()` is the function to reuse in a study."""
import argparse
import ctypes
import pathlib
import re
import shutil
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import solve_ivp

from peer_common import Slave, fmu_loop, load_scene, packed

G = 9.81


def pendulum_reference(stop):
    theta = solve_ivp(lambda t, y: [y[1], -G * np.cos(y[0])], (0, stop), [0.0, 0.0], method="DOP853",
                      rtol=1e-13, atol=1e-13).y[0, -1]
    return np.array([np.cos(theta), np.sin(theta)])


def double_pendulum_reference(stop):
    def rhs(t, y):
        p1, p2, w1, w2 = y
        d = p1 - p2
        M = np.array([[4 / 3, 0.5 * np.cos(d)], [0.5 * np.cos(d), 1 / 3]])
        f = -np.array([0.5 * np.sin(d) * w2 ** 2 + 1.5 * G * np.cos(p1),
                       -0.5 * np.sin(d) * w1 ** 2 + 0.5 * G * np.cos(p2)])
        return [w1, w2, *np.linalg.solve(M, f)]
    p1, p2 = solve_ivp(rhs, (0, stop), [0, 0, 0, 0], method="DOP853", rtol=1e-13, atol=1e-13).y[:2, -1]
    return np.array([np.cos(p1) + 0.5 * np.cos(p2), np.sin(p1) + 0.5 * np.sin(p2)])


# scene -> (outputs compared, reference at `stop`)
REFERENCES = {
    "pendulum": (["bob.position.x", "bob.position.y"], pendulum_reference),
    "double_pendulum": (["bar2.position.x", "bar2.position.y"], double_pendulum_reference),
}


def measure(name, method, tolerance, stop=10.0, step=0.1, h_max=None, repeats=5, folder=None):
    """Packs the example `name` with solver.method = method (and h_max,
    default the communication step), runs it to `stop` at the FMI tolerance
    (None: none) with communication steps `step`, best of `repeats`.
    Returns dict(error (Euclidean, of the reference's outputs), wall_time_s,
    substeps, factorizations, rejected, integrator (the log line))."""
    outputs, reference = REFERENCES[name]
    scene = load_scene(name)
    scene["solver"].update(method=method, h_max=h_max or step)
    own = folder is None
    folder = pathlib.Path(folder or tempfile.mkdtemp(prefix="mfbd-method-"))
    try:
        fmu = packed(scene, folder, f"{name}_{method}")
        exact = reference(stop)
        best = None
        for _ in range(repeats):
            result = _run(fmu, outputs, tolerance, stop, step)
            if best is None or result["wall_time_s"] < best["wall_time_s"]:
                best = result
        best["error"] = float(np.linalg.norm(best.pop("final") - exact))
        return best
    finally:
        if own:
            shutil.rmtree(folder, ignore_errors=True)


def _run(fmu, outputs, tolerance, stop, step):
    s = Slave(fmu)
    try:
        assert s.instantiate(logging_on=True), s.messages()
        s.call("setDebugLogging", True, ["logStatistics", "logEvents"])
        assert s.call("setupExperiment", tolerance, 0.0, None) == 0, s.messages()
        component = ctypes.cast(s.fmu.component, ctypes.c_void_p).value
        do_step = ctypes.cast(s.fmu.dll.fmi2DoStep, ctypes.c_void_p).value
        get_real = ctypes.cast(s.fmu.dll.fmi2GetReal, ctypes.c_void_p).value
        references = (ctypes.c_uint * len(outputs))(*(s.vr[n] for n in outputs))
        steps = int(round(stop / step))
        samples = np.zeros((steps + 1, len(outputs)))
        reached = ctypes.c_double(0.0)
        loop = fmu_loop()
        start = time.perf_counter()
        assert s.call("enterInitializationMode") == 0 and s.call("exitInitializationMode") == 0, s.messages()
        failed = loop(do_step, get_real, component, step, steps, references, len(outputs), samples.ctypes.data,
                      ctypes.byref(reached))
        wall = time.perf_counter() - start
        assert failed == 0, f"failed at t = {reached.value}: {s.messages()[-500:]}"
        assert s.call("terminate") == 0
        log = s.messages()
        found = {k: int(m.group(1)) for k, p in (("substeps", r"substeps (\d+)"), ("factorizations", r"factorizations (\d+)"),
                                                  ("rejected", r"rejected (\d+)")) if (m := re.search(p, log))}
        line = next((x for x in log.splitlines() if x.startswith("integrator: ")), "")
        return dict(final=samples[-1], wall_time_s=wall, integrator=line, **found)
    finally:
        s.free()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", choices=sorted(REFERENCES))
    parser.add_argument("--method", default="automatic", choices=["automatic", "generalized_alpha", "dormand_prince"])
    parser.add_argument("--tolerance", type=float, default=1e-6, help="FMI relative tolerance (<= 0: none)")
    parser.add_argument("--stop", type=float, default=10.0)
    parser.add_argument("--step", type=float, default=0.1, help="communication step, s")
    parser.add_argument("--h-max", type=float, default=None, help="solver.h_max (default: the communication step)")
    parser.add_argument("--repeats", type=int, default=5)
    a = parser.parse_args()
    r = measure(a.scene, a.method, a.tolerance if a.tolerance > 0 else None, a.stop, a.step, a.h_max, a.repeats)
    print(f"{a.scene} {a.method} tolerance {a.tolerance:g}: error {r['error']:.3e}, time {1e3 * r['wall_time_s']:.3f} ms, "
          f"substeps {r.get('substeps')}, factorizations {r.get('factorizations')}, rejected {r.get('rejected')}")
    print(r["integrator"])


if __name__ == "__main__":
    sys.exit(main())
