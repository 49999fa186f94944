#!/usr/bin/env python3
"""Packs the PID controller FMU (controller/pid.hpp) with a number of channels
fixed here: modelDescription.xml, resources/pid_controller.txt (channel count
and GUID, read by the binary at fmi2Instantiate) and the binary of each
platform built, renamed to the model identifier as mfbd-pack does for scenes.

    python controller/pack_controller.py --channels 6 -o pid_controller.fmu \\
        [--binaries build/fmu_binaries] [--platform all|linux64|win64] [--name pid_controller]
"""
import argparse
import pathlib
import re
import sys
import uuid
import xml.etree.ElementTree as ET

from packing import write_zip, xml_text

FORMAT = "mfbd-pid/1"
PLATFORMS = {"linux64": ".so", "win64": ".dll"}
# One block of value references per kind, in the binary's order (pid.hpp, Kind):
# value reference = block * channels + channel index (0-based).
# (name, causality, variability, start, description); start None: calculated.
KINDS = [
    ("setpoint", "input", "continuous", 0.0, "reference value r"),
    ("measurement", "input", "continuous", 0.0, "measured value y"),
    ("command", "output", "continuous", None, "u = clamp(Kp e + I + D, u_min, u_max), e = r - y"),
    ("Kp", "parameter", "tunable", 1.0, "proportional gain"),
    ("Ki", "parameter", "tunable", 0.0, "integral gain: I' = Ki e (frozen while u is at a limit and Ki e pushes "
                                        "it further)"),
    ("Kd", "parameter", "tunable", 0.0, "derivative gain: D = Kd (w - x)/Tf, x' = (w - x)/Tf, w = c r - y"),
    ("Tf", "parameter", "tunable", 0.01, "derivative filter time constant, s (> 0)"),
    ("c", "parameter", "tunable", 0.0, "setpoint weight in the derivative (0: derivative of -y only)"),
    ("u_min", "parameter", "tunable", -1e20, "lower command limit"),
    ("u_max", "parameter", "tunable", 1e20, "upper command limit"),
]


def variables(channels):
    """[(name, value reference, causality, variability, start, description)] in XML order."""
    return [(f"{name}[{k + 1}]", block * channels + k, causality, variability, start, description)
            for block, (name, causality, variability, start, description) in enumerate(KINDS)
            for k in range(channels)]


def model_description(name, channels, guid):
    root = ET.Element("fmiModelDescription", fmiVersion="2.0", modelName=name, guid=guid,
                      description=f"PID controller with {channels} independent channels (setpoint, measurement "
                                  "-> command), limits with clamping anti-windup, filtered derivative; "
                                  "continuous law stepped exactly for held or ramped inputs",
                      generationTool="MFBD-FMU controller/pack_controller.py", variableNamingConvention="structured",
                      numberOfEventIndicators="0")
    ET.SubElement(root, "CoSimulation", modelIdentifier=name, needsExecutionTool="false",
                  canHandleVariableCommunicationStepSize="true", canInterpolateInputs="true",
                  maxOutputDerivativeOrder="0", canRunAsynchronuously="false",
                  canBeInstantiatedOnlyOncePerProcess="false", canNotUseMemoryManagementFunctions="true",
                  canGetAndSetFMUstate="true", canSerializeFMUstate="true", providesDirectionalDerivative="false")
    categories = ET.SubElement(root, "LogCategories")
    ET.SubElement(categories, "Category", name="logStatusError", description="Calls that return fmi2Error")
    ET.SubElement(root, "DefaultExperiment", startTime="0")
    model_variables = ET.SubElement(root, "ModelVariables")
    for name_k, vr, causality, variability, start, description in variables(channels):
        attributes = dict(name=name_k, valueReference=str(vr), causality=causality, variability=variability,
                          description=description)
        if causality == "parameter":
            attributes["initial"] = "exact"
        v = ET.SubElement(model_variables, "ScalarVariable", **attributes)
        ET.SubElement(v, "Real", **({} if start is None else {"start": repr(start)}))
    structure = ET.SubElement(root, "ModelStructure")
    outputs, initial = ET.SubElement(structure, "Outputs"), ET.SubElement(structure, "InitialUnknowns")
    for k in range(channels):  # XML indices are 1-based: index = value reference + 1
        command, setpoint, measurement = 2 * channels + k + 1, k + 1, channels + k + 1
        ET.SubElement(outputs, "Unknown", index=str(command), dependencies=f"{setpoint} {measurement}")
        ET.SubElement(initial, "Unknown", index=str(command))
    return xml_text(root)


def pack(out, channels, binaries, platform="all", name="pid_controller"):
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]{0,63}", name):
        raise ValueError(f"--name '{name}': expected a C identifier of at most 64 characters")
    if not 1 <= channels <= 100000:
        raise ValueError(f"--channels {channels}: expected a whole number from 1 to 100000")
    if platform != "all" and platform not in PLATFORMS:
        raise ValueError(f"--platform '{platform}': expected all, {', '.join(PLATFORMS)}")
    guid = "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, f"{FORMAT} {name} channels={channels}")) + "}"
    entries = {"modelDescription.xml": model_description(name, channels, guid),
               "resources/pid_controller.txt": f"format {FORMAT}\nchannels {channels}\nguid {guid}\n"}
    for p, extension in PLATFORMS.items():
        binary = pathlib.Path(binaries) / p / f"pid_controller{extension}"
        if platform in ("all", p) and binary.is_file():
            entries[f"binaries/{p}/{name}{extension}"] = binary.read_bytes()
        elif platform == p:
            raise ValueError(f"--platform {p}: no {binary} (build it first)")
    if not any(n.startswith("binaries/") for n in entries):
        raise ValueError(f"binaries folder '{binaries}' has no pid_controller binary (build the project first)")
    write_zip(out, entries)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--channels", type=int, required=True)
    parser.add_argument("-o", "--out", type=pathlib.Path, required=True)
    parser.add_argument("--binaries", type=pathlib.Path,
                        default=pathlib.Path(__file__).resolve().parents[1] / "build" / "fmu_binaries")
    parser.add_argument("--platform", default="all")
    parser.add_argument("--name", default="pid_controller")
    args = parser.parse_args()
    try:
        pack(args.out, args.channels, args.binaries, args.platform, args.name)
    except ValueError as e:
        print(f"pack_controller: {e}", file=sys.stderr)
        return 1
    print(f"pack_controller: wrote {args.out} ({args.channels} channels)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
