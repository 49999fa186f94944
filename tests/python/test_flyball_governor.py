"""R6, the stiff flyball governor (IFToMM A05): coupler springs k = 8e5 N/m,
c = 4e4 N s/m against a slow governor motion. Checked against its steady
state derived by hand (effective potential in the frame turning with the
shaft) and run at a step far above its stiff time scales."""
import math

import numpy as np
from fmpy import simulate_fmu
from scipy.optimize import fsolve

from conftest import FMUS, load_scene, packed, simulate_fixed_step

G, OMEGA = 9.81, 2 * math.pi
A, L, RHO = 0.01, 1.0, 3000.0
ROD, BALL, SLIDER = RHO * A * A * L, 5.0, 3.0
OFFSET, K, FREE = 0.05, 8e5, 0.5
J_ALONG, J_ACROSS = ROD * 2 * A * A / 12, ROD * (L * L + A * A) / 12
ALPHA = math.radians(30.0)


def effective_potential_gradient(x):
    """d/d(phi, z) of the effective potential, both sides together:
    V = 2 [rod and ball weight + k (l - l0)^2 / 2 - Omega^2 I_axis / 2] + m_s g z,
    phi the rods' angle below horizontal, z the slider centre's height,
    I_axis a rod's and ball's moment of inertia about the shaft axis, l the
    spring length from the rod's midpoint to the slider, 0.05 m off-axis."""
    phi, z = x
    c, s = math.cos(phi), math.sin(phi)
    dz = 1.0 - 0.5 * s - z  # rod midpoint above the spring's slider end
    length = math.hypot(0.5 * c, dz)
    tension = K * (length - FREE)
    dl_dphi = (-0.25 * c * s - 0.5 * c * dz) / length
    dl_dz = -dz / length
    d_inertia = 2 * s * c * (J_ALONG - J_ACROSS) - ROD * (OFFSET + 0.5 * c) * s - 2 * BALL * (OFFSET + c) * s
    dphi = 2 * (-(0.5 * ROD + BALL) * G * c + tension * dl_dphi - 0.5 * OMEGA ** 2 * d_inertia)
    return [dphi, 2 * tension * dl_dz + SLIDER * G]


def steady_state():
    return fsolve(effective_potential_gradient, [ALPHA, 0.5], xtol=1e-13)


def test_governor_started_at_its_hand_derived_steady_state_stays_there(tmp_path):
    phi, z = steady_state()
    assert 0.30 < phi < 0.33 and 0.68 < z < 0.70  # the rods rise from 30 to about 17.9 degrees
    scene = load_scene("flyball_governor")
    for joint in scene["joints"]:
        if joint["name"] in ("hinge1", "hinge2"):
            joint["initial"] = {"coordinates": [phi - ALPHA]}
        if joint["name"] == "guide":
            joint["initial"] = {"coordinates": [z - 0.5]}
    # h = 1e-2: 80 times the springs' damping time m/c, and k h^2 / m = 16.
    r = simulate_fmu(packed(scene, tmp_path), stop_time=10.0, output=["hinge1.angle", "hinge2.angle",
                                                                      "guide.position", "shaft_drive.angle"])
    # Measured: 3e-14.
    assert np.max(np.abs(r["hinge1.angle"] - (phi - ALPHA))) < 1e-11
    assert np.max(np.abs(r["hinge2.angle"] - (phi - ALPHA))) < 1e-11
    assert np.max(np.abs(r["guide.position"] - (z - 0.5))) < 1e-11
    assert abs(r["shaft_drive.angle"][-1] - OMEGA * 10.0) < 1e-9


def test_governor_from_the_benchmark_start_at_a_large_step():
    # From 30 degrees (springs at their free length) the governor swings
    # about its steady state. At h = 1e-2 and 5e-3 the slow motion follows a
    # run at h = 1e-4 to second order (measured 2.6e-3 and 6.5e-4 m), and the
    # stiff springs stay within their static stretch (tension / k, 6e-5 m).
    outputs = ["guide.position", "coupler1.length", "coupler2.length", "hinge1.angle", "hinge2.angle"]
    runs = {h: simulate_fixed_step(FMUS / "flyball_governor.fmu", stop_time=10.0, output=outputs,
                            start_values={"solver.h_max": h}) for h in (1e-2, 5e-3, 1e-4)}
    phi, z = steady_state()
    swing = runs[1e-2]["guide.position"] + 0.5
    assert swing.min() < z < swing.max()  # it swings about the steady state
    error = {h: np.max(np.abs(runs[h]["guide.position"] - runs[1e-4]["guide.position"])) for h in (1e-2, 5e-3)}
    assert error[1e-2] < 5e-3
    assert 3.0 < error[1e-2] / error[5e-3] < 5.0
    for r in runs.values():
        assert np.max(np.abs(r["coupler1.length"] - FREE)) < 1e-4
        assert np.max(np.abs(r["coupler2.length"] - r["coupler1.length"])) < 1e-12  # symmetric
        assert np.max(np.abs(r["hinge1.angle"] - r["hinge2.angle"])) < 1e-9
