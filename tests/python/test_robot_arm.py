"""The robot arm example: six torque inputs driven by a master's PD loop."""
import sys

import numpy as np

from conftest import DISCARD, EXAMPLES, FMUS, OK, Slave

sys.path.insert(0, str(EXAMPLES / "robot_arm"))
import control  # noqa: E402


def test_pd_loop_through_the_torque_inputs_settles():
    data = control.run(FMUS / "robot_arm.fmu")
    error = control.TARGET - data[-1, 1:7]
    assert abs(error[0]) < 1e-4  # base yaw: no gravity torque, no sag
    assert np.all(np.abs(error) < 0.1)  # the others sag under gravity (no compensation)
    assert np.all(np.abs(data[-1, 1:7] - data[-200, 1:7]) < 5e-3)  # nearly at rest


def test_an_unstable_master_loop_ends_in_a_clean_discard():
    # Explicit feedback with KD dt / J >> 1 on the tool roll grows without
    # bound; the FMU must stop with fmi2Discard and finite outputs.
    s = Slave(FMUS / "robot_arm.fmu")
    try:
        s.start()
        t, status = 0.0, OK
        for _ in range(2000):
            q, qd = s.get("j6.angle"), s.get("j6.angle_rate")
            s.set("j6.torque", 30.0 * (0.5 - q) - 5.0 * qd)
            status = s.step(t, 1e-3)
            if status != OK:
                break
            t += 1e-3
        assert status == DISCARD
        assert s.fmu.getRealStatus(2) == t  # fmi2LastSuccessfulTime: the step start
        values = s.get(*[f"j{i}.angle" for i in range(1, 7)], "tool.position.x")
        assert np.all(np.isfinite(values))
    finally:
        s.free()
