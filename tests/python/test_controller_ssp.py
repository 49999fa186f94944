"""The plant closed by the PID controller FMU, three ways: the SSP files the
build writes (build/ssp/*.ssp) run by fmpy's SSP simulator and by libcosim,
and the example master examples/ssp_master.py. Each run's joint angles are
compared with a monolithic reference: the same two FMUs with the controller
evaluated at every plant substep (a Gauss-Seidel master whose communication
step, 2.5e-4 s, is below the plant's h_max, so it is the substep).

Zero-order-hold coupling errs at first order in the communication step H.
At H = 1e-3 the measured largest angle differences from the reference over
1.5 s (a step of every setpoint that drives the torques into their limits;
the largest differences come in the first 0.05 s) are, robot_arm /
flexible_robot_arm:
  Gauss-Seidel (examples/ssp_master.py)  0.012 / 0.021 rad
  fmpy's SSP simulator                   0.099 / 0.048 rad (0.046 / 0.026 at H / 2)
  libcosim                               0.085 / 0.053 rad
fmpy's simulator and libcosim are Jacobi masters: every FMU steps with the
others' outputs of the step start, so the controller sees each measurement
one step late."""
import subprocess
import sys

import numpy as np
import pytest
from fmpy.ssp.simulation import simulate_ssp
from fmpy.ssp.ssd import read_ssd, read_ssv
from libcosimpy.CosimEnums import CosimVariableType
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver

from conftest import BUILD, EXAMPLES

sys.path.insert(0, str(EXAMPLES))
import ssp_master  # noqa: E402

STOP, H, H_REFERENCE = 1.5, 1e-3, 2.5e-4
ANGLES = {"robot_arm_pid": [f"j{i}.angle" for i in range(1, 7)],
          "flexible_robot_arm_pid": ["shoulder.angle", "elbow.angle"]}
# Largest angle difference from the reference allowed at H (rad), about 1.5
# times the measured one.
GAUSS_SEIDEL = {"robot_arm_pid": 0.02, "flexible_robot_arm_pid": 0.035}
JACOBI = {"robot_arm_pid": 0.15, "flexible_robot_arm_pid": 0.08}


@pytest.fixture(scope="module", params=sorted(ANGLES))
def system(request):
    """(name, SSP path, reference run)."""
    ssp = BUILD / "ssp" / f"{request.param}.ssp"
    return request.param, ssp, ssp_master.run(ssp, H_REFERENCE, STOP)


def difference(system, times, angles):
    """Largest |angle - reference| over the run, over the joints; times and
    angles[name] are the run's samples of the plant output `name`."""
    name, _, reference = system
    assert times[-1] == pytest.approx(STOP, abs=1e-9 * STOP / H) and len(times) >= STOP / H
    return max(np.max(np.abs(angles[n] - np.interp(times, reference["time"], reference[f"plant.{n}"])))
               for n in ANGLES[name])


def test_ssp_holds_the_system_and_is_valid(system):
    name, ssp, _ = system
    ssd = read_ssd(str(ssp))  # validates against the SSP 1.0 schema
    components = {c.name: c for c in ssd.system.elements}
    assert sorted(components) == ["controller", "plant"]
    assert len(ssd.system.connections) == 2 * len(ANGLES[name])
    binding = components["controller"].parameterBindings[0]
    parameters = {p.name: float(p.value) for p in read_ssv(str(ssp), binding.source).parameters}  # validates
    assert len([p for p in parameters if p.startswith("Kp[")]) == len(ANGLES[name])


def test_reference_settles_at_the_setpoints(system):
    # Every joint has come most of the way (the integral action, which holds
    # the arm against gravity, settles them within 0.01 rad by 3 s): the
    # reference is a closed loop that works, not just any run.
    name, ssp, reference = system
    parameters = {p.name: float(p.value) for p in read_ssv(str(ssp), "resources/controller.ssv").parameters}
    for k, n in enumerate(ANGLES[name]):
        setpoint = parameters[f"setpoint[{k + 1}]"]
        assert abs(reference[f"plant.{n}"][-1] - setpoint) < 0.2 * abs(setpoint), n


def test_example_master_loop_tracks_the_reference(system):
    run = ssp_master.run(system[1], H, STOP)
    error = difference(system, run["time"], {n: run[f"plant.{n}"] for n in ANGLES[system[0]]})
    print(f"{system[0]}: Gauss-Seidel at H = {H}: {error:.3g} rad")
    assert error < GAUSS_SEIDEL[system[0]]


def test_fmpy_ssp_simulator_tracks_the_reference(system):
    """fmpy's simulate_ssp reads the .ssd but applies only a parameter set
    passed to it, with names prefixed by the component: the .ssv is read and
    passed so. Its rows carry the step's start time with the outputs at the
    step's end, and it starts every connector at 0 (the plant's first step
    gets no torque)."""
    name, ssp, _ = system
    parameters = read_ssv(str(ssp), "resources/controller.ssv")
    for p in parameters.parameters:
        p.name = f"controller.{p.name}"
    errors = []
    for step in [H, H / 2]:
        run = simulate_ssp(str(ssp), stop_time=STOP - step / 2, step_size=step, parameter_set=parameters)
        errors.append(difference(system, run["time"] + step, {n: run[f"plant.{n}"] for n in ANGLES[name]}))
    print(f"{name}: fmpy SSP at H = {H}, H / 2: {errors[0]:.3g}, {errors[1]:.3g} rad")
    assert errors[0] < JACOBI[name]
    assert 1.6 < errors[0] / errors[1] < 2.6  # first order in H: a coupling error, nothing else


def test_libcosim_runs_the_ssp_and_tracks_the_reference(system):
    """libcosim reads the .ssp archive itself, the .ssv included."""
    name, ssp, _ = system
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_ssp_file(str(ssp), step_size=int(round(H * 1e9)))
    plant = execution.slave_index_from_instance_name("plant")
    refs = {v.name.decode(): v.reference for v in execution.slave_variables(plant)}
    observer = CosimObserver.create_time_series(buffer_size=2 * int(STOP / H))
    execution.add_observer(observer)
    last = CosimObserver.create_last_value()
    execution.add_observer(last)
    for n in ANGLES[name]:
        observer.start_time_series(plant, value_reference=refs[n], variable_type=CosimVariableType.REAL)
    # One step past the end: the time-series observer returns no sample of
    # the last step (libcosimpy 0.0.6; the execution itself reaches the target).
    assert execution.simulate_until(target_time=int(round((STOP + H) * 1e9)))
    angles, times = {}, None
    for n in ANGLES[name]:
        times_ns, _, values = observer.time_series_real_samples(plant, refs[n], from_step=0,
                                                                sample_count=2 * int(STOP / H))
        times, angles[n] = np.array(times_ns) * 1e-9, np.array(values)
    controller = execution.slave_index_from_instance_name("controller")
    controller_refs = {v.name.decode(): v.reference for v in execution.slave_variables(controller)}
    parameters = {p.name: float(p.value) for p in read_ssv(str(ssp), "resources/controller.ssv").parameters}
    names = sorted(parameters)
    assert last.last_real_values(controller, [controller_refs[n] for n in names]) == [parameters[n] for n in names]
    error = difference(system, times, angles)
    print(f"{name}: libcosim at H = {H}: {error:.3g} rad")
    assert error < JACOBI[name]


def test_example_master_command_writes_every_connector(tmp_path):
    ssp = BUILD / "ssp" / "flexible_robot_arm_pid.ssp"
    result = subprocess.run([sys.executable, str(EXAMPLES / "ssp_master.py"), str(ssp), "--step", "0.01",
                             "--stop-time", "0.05", "--out", str(tmp_path)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    header, *rows = (tmp_path / "flexible_robot_arm_pid.csv").read_text().splitlines()
    assert header.split(",") == ["time", "plant.shoulder.angle", "controller.command[1]", "plant.elbow.angle",
                                 "controller.command[2]"]
    assert len(rows) == 6 and float(rows[-1].split(",")[0]) == pytest.approx(0.05)
