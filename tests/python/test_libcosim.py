"""A second importer: the same FMU in libcosim (libcosimpy) gives fmpy's results."""
import os

import numpy as np
from fmpy import simulate_fmu
from libcosimpy.CosimEnums import CosimVariableType
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave

OUTPUTS = ["hinge.angle", "hinge.angle_rate", "bob.position.x", "bob.position.y", "hinge.reaction_force.x"]


def test_libcosim_matches_fmpy(pendulum_fmu):
    log_output_level(CosimLogLevel.ERROR)
    step, stop = 0.01, 3.0
    execution = CosimExecution.from_step_size(step_size=int(round(step * 1e9)))
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=os.fspath(pendulum_fmu), instance_name="pendulum"))
    refs = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    observer = CosimObserver.create_time_series()
    execution.add_observer(observer)
    for name in OUTPUTS:
        observer.start_time_series(index, value_reference=refs[name], variable_type=CosimVariableType.REAL)
    execution.real_initial_value(index, refs["angle0"], 0.2)
    assert execution.simulate_until(target_time=int(round(stop * 1e9)))

    reference = simulate_fmu(pendulum_fmu, stop_time=stop, output_interval=step, start_values={"angle0": 0.2},
                             output=OUTPUTS)
    for name in OUTPUTS:
        # libcosimpy returns (times in ns, step numbers, values).
        times_ns, _, values = observer.time_series_real_samples(index, refs[name], from_step=0, sample_count=400)
        times = np.array(times_ns) * 1e-9
        values = np.array(values)
        expected = np.interp(times, reference["time"], reference[name])
        at_grid = np.isin(np.round(times / step).astype(int), np.round(reference["time"] / step).astype(int))
        assert at_grid.all()
        assert len(values) >= 250
        assert np.max(np.abs(values - expected)) < 1e-9, name
