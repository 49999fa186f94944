"""Every packed FMU: valid for fmpy (schema and semantics), self-contained
(every NEEDED library is C/C++ runtime or ships inside), runs on any x86-64,
consistent GUID."""
import pathlib
import re
import subprocess
import zipfile
from xml.etree import ElementTree

import pytest
from fmpy import extract, read_model_description
from fmpy.validation import validate_fmu

from conftest import PACKER, example_fmus

RUNTIME = re.compile(r"^(ld-linux-x86-64\.so\.2|libc\.so\.6|libm\.so\.6|libdl\.so\.2|librt\.so\.1|"
                     r"libpthread\.so\.0|libstdc\+\+\.so\.6|libgcc_s\.so\.1)$")


def dynamic_section(path):
    out = subprocess.run(["readelf", "-d", str(path)], capture_output=True, text=True, check=True).stdout
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[(.+?)\]", out)
    runpath = re.findall(r"\((?:RUNPATH|RPATH)\)\s+Library (?:runpath|rpath): \[(.+?)\]", out)
    return needed, runpath


def test_there_are_example_fmus():
    assert len(example_fmus()) >= 1


@pytest.mark.parametrize("fmu", example_fmus(), ids=lambda p: p.name)
def test_fmpy_validates(fmu):
    assert validate_fmu(str(fmu)) == []


@pytest.mark.parametrize("fmu", example_fmus(), ids=lambda p: p.name)
def test_entries_are_deflated_and_read_back(fmu):
    """Every entry compressed with deflate (the binaries shrink to about a
    third), each reading back with its CRC checked, at the fixed time
    1980-01-01 so the same inputs pack to the same archive."""
    with zipfile.ZipFile(fmu) as z:
        infos = z.infolist()
        assert [i.compress_type for i in infos] == [zipfile.ZIP_DEFLATED] * len(infos)
        assert sum(i.compress_size for i in infos) < 0.5 * sum(i.file_size for i in infos)
        assert z.testzip() is None
        assert {i.date_time for i in infos} == {(1980, 1, 1, 0, 0, 0)}


@pytest.mark.parametrize("fmu", example_fmus(), ids=lambda p: p.name)
def test_binary_is_self_contained(fmu, tmp_path):
    extract(str(fmu), str(tmp_path))
    md = read_model_description(str(fmu))
    bindir = tmp_path / "binaries" / "linux64"
    shipped = {p.name for p in bindir.iterdir()}
    main = bindir / f"{md.coSimulation.modelIdentifier}.so"
    assert main.name in shipped
    for lib in bindir.iterdir():
        needed, runpath = dynamic_section(lib)
        for name in needed:
            assert RUNTIME.match(name) or name in shipped, f"{lib.name} needs {name}, neither runtime nor shipped"
        if any(not RUNTIME.match(n) for n in needed):
            assert runpath == ["$ORIGIN"], f"{lib.name}: RUNPATH {runpath}"
    # The loader resolves every non-runtime library inside the FMU.
    ldd = subprocess.run(["ldd", str(main)], capture_output=True, text=True, check=True).stdout
    for line in ldd.splitlines():
        m = re.match(r"\s*(\S+) => (\S+)", line)
        if m and not RUNTIME.match(m.group(1)):
            assert pathlib.Path(m.group(2)).parent == bindir, line


def test_binary_runs_on_any_x86_64(tmp_path):
    """AVX instructions (VEX-encoded: mnemonics v...) only in the beam
    kernel's AVX2 variant, which runs only where the processor has AVX2
    (elementForceVectors). Code built for AVX2 that leaks into shared
    functions (an inlined helper emitted out of line, link-time
    optimisation) would be an illegal instruction on older processors."""
    fmu = example_fmus()[0]
    extract(str(fmu), str(tmp_path))
    md = read_model_description(str(fmu))
    main = tmp_path / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    listing = subprocess.run(["objdump", "-d", "-C", "--no-show-raw-insn", str(main)],
                             capture_output=True, text=True, check=True).stdout
    with_avx, function = set(), None
    for line in listing.splitlines():
        header = re.match(r"^[0-9a-f]+ <(.+)>:$", line)
        if header:
            function = header.group(1)
            continue
        fields = line.split("\t")
        if len(fields) >= 2 and re.match(r"v[a-z]", fields[1].strip()):
            with_avx.add(function)
    assert with_avx, "the AVX2 variant of the beam kernel is missing"
    assert all("elementForceVectorsAvx2" in f for f in with_avx), sorted(with_avx)


@pytest.mark.parametrize("fmu", example_fmus(), ids=lambda p: p.name)
def test_guid_is_the_hash_of_the_shipped_scene(fmu, tmp_path):
    with zipfile.ZipFile(fmu) as z:
        (tmp_path / "scene.json").write_bytes(z.read("resources/scene.json"))
    guid = subprocess.run([str(PACKER), "--guid", str(tmp_path / "scene.json")], capture_output=True, text=True,
                          check=True).stdout.strip()
    assert read_model_description(str(fmu)).guid == guid
    # Any change of the scene changes the GUID.
    (tmp_path / "scene.json").write_bytes(z_read(fmu).replace(b'"pendulum"', b'"pendulum2"'))
    other = subprocess.run([str(PACKER), "--guid", str(tmp_path / "scene.json")], capture_output=True, text=True,
                           check=True).stdout.strip()
    assert other != guid


def z_read(fmu):
    with zipfile.ZipFile(fmu) as z:
        return z.read("resources/scene.json") + b" "


def test_model_description_declares_only_what_works(pendulum_fmu):
    md = read_model_description(str(pendulum_fmu))
    cs = md.coSimulation
    assert cs.canHandleVariableCommunicationStepSize is True
    assert cs.canNotUseMemoryManagementFunctions is True
    assert cs.needsExecutionTool is False and cs.canBeInstantiatedOnlyOncePerProcess is False
    # FMU state and input derivatives: test_fmu_state.py, test_input_derivatives.py.
    assert cs.canGetAndSetFMUstate is True and cs.canSerializeFMUstate is True
    assert cs.canInterpolateInputs is True
    with zipfile.ZipFile(pendulum_fmu) as z:
        root = ElementTree.fromstring(z.read("modelDescription.xml"))
    assert root.find("VendorAnnotations/Tool[@name='MFBD-FMU']/InputDerivatives").get("maxOrder") == "2"
    # Not implemented yet, so declared false (their functions return fmi2Error).
    assert cs.canGetAndSetFMUstate is True and cs.canSerializeFMUstate is True
    assert cs.canInterpolateInputs is True
    # Output and directional derivatives (tests/python/test_derivatives.py).
    assert cs.providesDirectionalDerivative is True and cs.maxOutputDerivativeOrder == 2
    assert md.variableNamingConvention == "structured"
    names = {v.name: v for v in md.modelVariables}
    assert names["hinge.torque"].causality == "input"
    assert names["hinge.damping"].variability == "tunable"
    assert names["length"].variability == "fixed" and names["mass"].variability == "fixed"
    assert names["gravity.y"].variability == "fixed"
    assert names["solver.h_max"].causality == "parameter" and names["solver.rho_inf"].causality == "parameter"
    for n in ["hinge.angle", "hinge.angle_rate", "hinge.reaction_force.x", "hinge.reaction_torque.z",
              "bob.position.x", "bob.orientation.w", "bob.velocity.y", "bob.angular_velocity.z"]:
        assert names[n].causality == "output", n
    # Reactions depend directly on the input torque; positions do not.
    deps = {u.variable.name: [d.name for d in (u.dependencies or [])] for u in md.outputs}
    assert deps["hinge.reaction_torque.z"] == ["hinge.torque"]
    assert deps["bob.position.x"] == []
