"""1000 instantiate/free cycles of the FMU binary under valgrind leak nothing."""
import pathlib
import re
import shutil
import subprocess

import pytest
from fmpy import extract, read_model_description

from conftest import BUILD

HARNESS = BUILD / "tests" / "cpp" / "fmu_instance_cycles"
SUPPRESSIONS = pathlib.Path(__file__).with_name("ld_so.supp")


def run_cycles(fmu, unzip, cycles):
    md = read_model_description(str(fmu))
    binary = pathlib.Path(unzip) / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    uri = (pathlib.Path(unzip) / "resources").as_uri()
    result = subprocess.run(
        ["valgrind", "--leak-check=full", "--errors-for-leak-kinds=definite,indirect,possible",
         f"--suppressions={SUPPRESSIONS}", "--error-exitcode=99", str(HARNESS), str(binary), uri, md.guid,
         str(cycles)], capture_output=True, text=True)
    in_use = re.search(r"in use at exit: ([\d,]+) bytes", result.stderr)
    return result, int(in_use.group(1).replace(",", "")) if in_use else 0


@pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind is installed by scripts/setup.sh")
def test_thousand_instantiate_free_cycles_leak_nothing(pendulum_fmu, tmp_path):
    unzip = extract(str(pendulum_fmu), str(tmp_path))
    few, few_in_use = run_cycles(pendulum_fmu, unzip, 10)
    many, many_in_use = run_cycles(pendulum_fmu, unzip, 1000)
    for r in (few, many):
        assert r.returncode == 0, r.stderr[-3000:]
        assert "ERROR SUMMARY: 0 errors" in r.stderr
    assert "1000 cycles" in many.stdout
    # What is still reachable at exit (runtime pools) does not grow with cycles.
    assert many_in_use == few_in_use
