"""The valgrind leak check of an FMU binary through a cycle driver
(tests/cpp/fmu_instance_cycles.cpp, fmu_state_cycles.cpp): a few cycles
and many, no valgrind error in either, and no more memory in use at exit
after many than after a few (what stays reachable, runtime pools, does not
grow with the cycles)."""
import pathlib
import re
import shutil
import subprocess

import pytest
from fmpy import extract, read_model_description

from conftest import BUILD

INSTANCE_CYCLES = BUILD / "tests" / "cpp" / "fmu_instance_cycles"
STATE_CYCLES = BUILD / "tests" / "cpp" / "fmu_state_cycles"
SUPPRESSIONS = pathlib.Path(__file__).with_name("ld_so.supp")
needs_valgrind = pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind is installed by scripts/setup.sh")


def run_cycles(driver, fmu, unzip, cycles):
    """The driver's run under valgrind, and the bytes in use at its exit."""
    md = read_model_description(str(fmu))
    binary = pathlib.Path(unzip) / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    uri = (pathlib.Path(unzip) / "resources").as_uri()
    result = subprocess.run(
        ["valgrind", "--leak-check=full", "--errors-for-leak-kinds=definite,indirect,possible",
         f"--suppressions={SUPPRESSIONS}", "--error-exitcode=99", str(driver), str(binary), uri, md.guid,
         str(cycles)], capture_output=True, text=True)
    in_use = re.search(r"in use at exit: ([\d,]+) bytes", result.stderr)
    return result, int(in_use.group(1).replace(",", "")) if in_use else 0


def assert_cycles_leak_nothing(driver, fmu, folder, few, many):
    unzip = extract(str(fmu), str(folder))
    (a, a_in_use), (b, b_in_use) = run_cycles(driver, fmu, unzip, few), run_cycles(driver, fmu, unzip, many)
    for r in (a, b):
        assert r.returncode == 0, r.stderr[-3000:]
        assert "ERROR SUMMARY: 0 errors" in r.stderr
    assert f"{many} cycles" in b.stdout
    assert b_in_use == a_in_use
