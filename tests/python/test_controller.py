"""The PID controller FMU (controller/): its law against closed-form
solutions of the continuous PID, refusals, FMU state, and the same packaging
checks as the plant FMUs (fmpy validation, linux64 and win64 binaries, the
win64 DLL under Wine against the linux64 binary)."""
import math
import re
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.validation import validate_fmu

from conftest import BUILD, ERROR, OK, ROOT, Slave
from leak_check import INSTANCE_CYCLES, assert_cycles_leak_nothing, needs_valgrind
from test_platforms import (LINUX_SYSTEM, MASTER, MASTER_EXE, WINDOWS_SYSTEM, pe_imports, run_master,  # noqa: F401
                            version_needs, windows_path, wine)

CONTROLLERS = sorted((BUILD / "controllers").glob("*.fmu"))
PID2 = BUILD / "controllers" / "pid_controller_2.fmu"


@pytest.fixture
def pid():
    s = Slave(PID2)
    yield s
    s.free()


def started(s, values=None):
    """Instantiated with the given start values, initialized at t = 0."""
    return s.start(values or {})


def test_there_are_controllers_for_both_systems():
    assert [p.name for p in CONTROLLERS] == ["pid_controller_2.fmu", "pid_controller_6.fmu"]


@pytest.mark.parametrize("fmu", CONTROLLERS, ids=lambda p: p.name)
def test_fmpy_validates_the_controller(fmu):
    assert validate_fmu(str(fmu)) == []


@pytest.mark.parametrize("fmu", CONTROLLERS, ids=lambda p: p.name)
def test_start_values_in_the_xml_are_the_binarys(fmu):
    md = read_model_description(str(fmu))
    s = Slave(fmu)
    try:
        assert s.instantiate(), s.messages()
        assert s.call("enterInitializationMode") == OK
        for v in md.modelVariables:
            if v.start is not None:
                assert s.get(v.name) == float(v.start), v.name
    finally:
        s.free()


def test_proportional_and_integral_are_exact_for_held_inputs(pid):
    # e = 0.5 held: u(t) = Kp e + Ki e t, whatever the steps.
    s = started(pid, {"setpoint[1]": 1.5, "measurement[1]": 1.0, "Kp[1]": 2.0, "Ki[1]": 3.0})
    assert s.get("command[1]") == 1.0
    t = 0.0
    for h in [0.1, 0.013, 0.25, 1e-4, 0.5]:
        assert s.step(t, h) == OK
        t += h
        assert abs(s.get("command[1]") - (1.0 + 1.5 * t)) < 1e-14
    assert s.get("command[2]") == 0.0  # channel 2 untouched


def test_filtered_derivative_of_a_measurement_step_decays_exactly(pid):
    # x' = (w - x)/Tf with w = -y: after y jumps by 1, D = Kd (w - x)/Tf = -(Kd/Tf) exp(-t/Tf).
    kd, tf = 0.3, 0.02
    s = started(pid, {"Kp[2]": 0.0, "Kd[2]": kd, "Tf[2]": tf})
    assert s.set("measurement[2]", 1.0) == OK
    assert s.get("command[2]") == -kd / tf  # the kick at once: direct feedthrough
    t = 0.0
    for h in [0.005, 0.01, 0.003, 0.03]:
        assert s.step(t, h) == OK
        t += h
        assert abs(s.get("command[2]") - (-kd / tf * math.exp(-t / tf))) < 1e-13 * kd / tf


def test_ramped_inputs_give_the_continuous_solution(pid):
    # y = a t from fmi2SetRealInputDerivatives: e = -a t, I = -Ki a t^2/2,
    # D = -Kd a (1 - exp(-t/Tf)), P = -Kp a t; one step of H.
    a, kp, ki, kd, tf, H = 0.7, 1.3, 2.1, 0.4, 0.05, 0.08
    s = started(pid, {"Kp[1]": kp, "Ki[1]": ki, "Kd[1]": kd, "Tf[1]": tf})
    s.fmu.setRealInputDerivatives([s.vr["measurement[1]"]], [1], [a])
    assert s.step(0.0, H) == OK
    expected = -kp * a * H - ki * a * H * H / 2 - kd * a * (1 - math.exp(-H / tf))
    assert abs(s.get("command[1]") - expected) < 1e-15 * 10
    assert abs(s.get("measurement[1]") - a * H) < 1e-16  # the input ends at its ramp's end value
    assert s.step(H, H) == OK  # the derivative was used up: held from here on
    assert abs(s.get("measurement[1]") - a * H) < 1e-16


def test_clamping_stops_the_integral_at_the_limit(pid):
    # Kp = 0, Ki = 1, e = 1, u_max = 0.5: I climbs 0.125 a step to the limit
    # and stays there; when e turns negative it leaves the limit at once.
    s = started(pid, {"setpoint[1]": 1.0, "Kp[1]": 0.0, "Ki[1]": 1.0, "u_max[1]": 0.5})
    commands = []
    for k in range(8):
        assert s.step(0.125 * k, 0.125) == OK
        commands.append(s.get("command[1]"))
    assert commands == [0.125, 0.25, 0.375, 0.5, 0.5, 0.5, 0.5, 0.5]
    assert s.set("setpoint[1]", -1.0) == OK
    assert s.step(1.0, 0.125) == OK
    assert s.get("command[1]") == 0.375  # without anti-windup: 1.0 - 0.125 = 0.875, still at the limit


def test_bad_values_are_refused_and_change_nothing(pid):
    s = started(pid)
    before = s.get("Tf[1]", "u_min[2]", "u_max[2]")
    assert s.set("Tf[1]", 0.0) == ERROR
    assert "fmi2SetReal: Tf[1]: expected a filter time constant > 0 s" in s.messages()
    assert s.call("setReal", [s.vr["u_min[2]"], s.vr["u_max[2]"]], [5.0, 4.0]) == ERROR
    assert "u_min[2]: expected u_min <= u_max of the channel" in s.messages()
    assert s.call("setReal", [s.vr["u_min[2]"], s.vr["u_max[2]"]], [3.0, 4.0]) == OK  # together: fine
    assert s.set("command[1]", 1.0) == ERROR and "command[1] is an output" in s.messages()
    assert s.call("setReal", [999], [1.0]) == ERROR and "unknown value reference 999" in s.messages()
    assert s.set("Kp[1]", float("nan")) == ERROR and "Kp[1]: expected a finite number" in s.messages()
    assert s.get("Tf[1]") == before[0]
    assert s.call("setRealInputDerivatives", [s.vr["measurement[1]"]], [2], [1.0]) == ERROR
    assert "order 2" in s.messages()
    assert s.step(0.5, 0.1) == ERROR and "not the FMU's time" in s.messages()


def test_wrong_guid_is_refused(pid):
    assert not pid.instantiate(guid="{00000000-0000-0000-0000-000000000000}")
    assert "is not this FMU's" in pid.messages()


def drive(s, t0, n, seed):
    """n steps of 0.01 with random inputs; the commands after each."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        s.fmu.setReal([s.vr["setpoint[1]"], s.vr["measurement[2]"]], list(rng.normal(size=2)))
        s.fmu.setRealInputDerivatives([s.vr["measurement[1]"]], [1], [rng.normal()])
        assert s.step(t0 + 0.01 * k, 0.01) == OK
        out.append(s.get("command[1]", "command[2]"))
    return out


def test_state_replays_bit_for_bit_and_serializes_into_a_fresh_instance(pid):
    s = started(pid, {"Ki[1]": 2.0, "Kd[1]": 0.1, "Kd[2]": 0.2, "u_max[2]": 0.3, "Ki[2]": 5.0})
    drive(s, 0.0, 5, 1)
    state = s.fmu.getFMUstate()
    first = drive(s, 0.05, 20, 2)
    s.fmu.setFMUstate(state)
    assert drive(s, 0.05, 20, 2) == first
    blob = s.fmu.serializeFMUstate(state)
    s.fmu.freeFMUstate(state)
    other = Slave(PID2, instance_name="other")
    try:
        started(other)
        copy = other.fmu.deSerializeFMUstate(blob)
        other.fmu.setFMUstate(copy)
        other.fmu.freeFMUstate(copy)
        assert drive(other, 0.05, 20, 2) == first
        for bad, why in [(blob[:-1], "bytes, expected"), (b"XXXX" + blob[4:], "format MFBDPID1")]:
            with pytest.raises(Exception):
                other.fmu.deSerializeFMUstate(bad)
            assert why in other.messages()
    finally:
        other.free()


def test_a_state_of_a_controller_with_other_channels_is_refused(pid):
    six = Slave(BUILD / "controllers" / "pid_controller_6.fmu", instance_name="six")
    try:
        started(six)
        blob = six.fmu.serializeFMUstate(six.fmu.getFMUstate())
        started(pid)
        with pytest.raises(Exception):
            pid.fmu.deSerializeFMUstate(blob)
        assert "the state has 6 channels, this controller 2" in pid.messages()
    finally:
        six.free()


# --- the platforms, as tests/python/test_platforms.py checks the plant FMUs -----


@pytest.mark.parametrize("fmu", CONTROLLERS, ids=lambda p: p.name)
def test_controller_carries_linux64_for_glibc_2_17_and_win64_with_system_dlls(fmu, tmp_path):
    with zipfile.ZipFile(fmu) as z:
        assert sorted(n for n in z.namelist() if n.startswith("binaries/")) == \
            ["binaries/linux64/pid_controller.so", "binaries/win64/pid_controller.dll"]
    extract(str(fmu), str(tmp_path))
    so = tmp_path / "binaries" / "linux64" / "pid_controller.so"
    needed = subprocess.run(["readelf", "-d", str(so)], capture_output=True, text=True, check=True).stdout
    assert set(re.findall(r"\(NEEDED\)\s+Shared library: \[(.+?)\]", needed)) <= LINUX_SYSTEM
    versions = set().union(*version_needs(so).values())
    assert not [v for v in versions if v.startswith(("GLIBCXX_", "CXXABI_"))]
    assert all(tuple(int(x) for x in v[6:].split(".")) <= (2, 17) for v in versions if v.startswith("GLIBC_"))
    imports = pe_imports(tmp_path / "binaries" / "win64" / "pid_controller.dll")
    assert "KERNEL32.dll" in imports and {name.lower() for name in imports} <= WINDOWS_SYSTEM, imports


def test_controller_win64_under_wine_matches_linux64(tmp_path, wine):
    """Both binaries by the same C master, with gains, limits and a held
    error that ramps channel 1 into its limit: outputs equal to 1e-15."""
    unzip = tmp_path / "with space"
    extract(str(PID2), str(unzip))
    md = read_model_description(str(PID2))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    starts = {"setpoint[1]": 1.0, "measurement[2]": -0.5, "Kp[1]": 0.7, "Ki[1]": 2.0, "u_max[1]": 2.5,
              "Ki[2]": 0.3, "Kd[2]": 0.1}
    args = [vr["command[1]"], vr["command[2]"]] + [f"{vr[n]}={v!r}" for n, v in starts.items()]
    linux = run_master([str(MASTER)], unzip / "binaries" / "linux64" / "pid_controller.so", unzip / "resources",
                       md, args, 1.0)
    command, env = wine
    windows = run_master([command, str(MASTER_EXE)], windows_path(unzip / "binaries" / "win64" / "pid_controller.dll"),
                         windows_path(unzip / "resources"), md, args, 1.0, env)
    assert linux[-1][1] == 2.5 and linux[50][1] == pytest.approx(0.7 + 2.0 * 0.5, abs=1e-12)
    assert np.max(np.abs(np.array(windows) - np.array(linux))) <= 1e-15


def test_packer_refuses_bad_arguments(tmp_path):
    pack = [sys.executable, str(ROOT / "controller" / "pack_controller.py"), "-o", str(tmp_path / "x.fmu")]
    result = subprocess.run(pack + ["--channels", "0"], capture_output=True, text=True)
    assert result.returncode == 1 and "--channels 0: expected a whole number from 1" in result.stderr
    result = subprocess.run(pack + ["--channels", "3", "--platform", "darwin64"], capture_output=True, text=True)
    assert result.returncode == 1 and "--platform 'darwin64'" in result.stderr
    result = subprocess.run(pack + ["--channels", "3", "--binaries", str(tmp_path)], capture_output=True, text=True)
    assert result.returncode == 1 and "has no pid_controller binary" in result.stderr


@needs_valgrind
def test_controller_instantiate_free_cycles_leak_nothing(tmp_path):
    assert_cycles_leak_nothing(INSTANCE_CYCLES, PID2, tmp_path, 10, 300)
