"""1000 instantiate/free cycles of the FMU binary under valgrind leak nothing."""
from leak_check import INSTANCE_CYCLES, assert_cycles_leak_nothing, needs_valgrind


@needs_valgrind
def test_thousand_instantiate_free_cycles_leak_nothing(pendulum_fmu, tmp_path):
    assert_cycles_leak_nothing(INSTANCE_CYCLES, pendulum_fmu, tmp_path, 10, 1000)
