"""Masters keep time differently: fmpy and fmusim pass t0 + n H, others add
t += H, libcosim counts integer nanoseconds and passes the difference of two
of them as the step (which then differs from H in its last bit). Every
example FMU must give the same outputs whichever drives it, and its time
must be the master's."""
import numpy as np
import pytest

from conftest import OK, Slave, example_fmus

H, STEPS = 0.01, 30  # 0.3 s


def grid(n):  # t0 + n H (t0 = 0), step H
    return n * H, H


def accumulate():
    t = 0.0
    while True:
        yield t, H
        t += H


def nanoseconds(n):  # integer nanoseconds; the step lands on the next point exactly
    k, dk = n * round(H * 1e9), round(H * 1e9)
    return k / 1e9, (k + dk) / 1e9 - k / 1e9


def drive(fmu, master):
    """Outputs after each step (rows), and whether the FMU's time was the
    master's after every step."""
    s = Slave(fmu)
    try:
        s.start()
        outputs = [v for v in s.md.modelVariables if v.causality == "output"]
        vrs = [v.valueReference for v in outputs]
        rows, times_agree = [], True
        points = accumulate()
        for n in range(STEPS):
            t, h = next(points) if master == "accumulate" else (grid(n) if master == "grid" else nanoseconds(n))
            assert s.step(t, h) == OK, s.messages()
            times_agree &= s.fmu.getRealStatus(2) == t + h  # fmi2LastSuccessfulTime
            rows.append(s.fmu.getReal(vrs))
        return outputs, np.array(rows), times_agree
    finally:
        s.free()


def scales(outputs, runs):
    """Per output: the largest |value| over the runs, or the scale of its
    kind if that is larger, so that a signal which is zero to round-off (the
    reaction torque along a free axis) counts on the scale of its kind. A
    kind's scale is its largest output, or what related kinds imply through
    the scene's size L (forces times L for torques, angular rates times L
    for velocities), 1 for angles and quaternion components, and at least
    1e-6 (SI): a kind that is zero to round-off throughout (the reactions
    of a free body) has no scale of its own."""
    own = np.max([np.max(np.abs(r), axis=0) for r in runs], axis=0)
    kinds = [v.unit or "1" for v in outputs]
    largest = {k: max(own[i] for i in range(len(own)) if kinds[i] == k) for k in set(kinds)}
    at = lambda k: largest.get(k, 0.0)
    L = max(at("m"), 1e-3) if "m" in largest else 1.0
    kind = {k: max(v, 1e-6) for k, v in largest.items()}
    for unit, implied in (("N.m", at("N") * L), ("N", at("N.m") / L), ("m/s", at("rad/s") * L),
                          ("rad/s", at("m/s") / L), ("rad", 1.0), ("1", 1.0), ("m", L)):
        if unit in kind:
            kind[unit] = max(kind[unit], implied)
    return np.maximum(own, [kind[k] for k in kinds])


# Bricard's constraints are redundant: its reactions are the minimum-norm
# multipliers, unique, so they agree too. (n_four_bar passes no singular
# configuration in 0.3 s.)
@pytest.mark.parametrize("fmu", example_fmus(), ids=lambda f: f.stem)
def test_every_master_gets_the_same_outputs_and_its_own_time(fmu):
    outputs, a, grid_times = drive(fmu, "grid")
    _, b, accumulated_times = drive(fmu, "accumulate")
    _, c, nanosecond_times = drive(fmu, "nanoseconds")
    assert grid_times and accumulated_times and nanosecond_times
    scale = scales(outputs, [a, b, c])
    worst = {}
    for name, other in (("t += H", b), ("integer ns", c)):
        deviation = np.max(np.abs(other - a), axis=0) / scale
        k = int(np.argmax(deviation))
        worst[name] = (outputs[k].name, float(deviation[k]))
    assert all(d <= 1e-6 for _, d in worst.values()), worst
