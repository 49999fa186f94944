#!/usr/bin/env python3
"""Writes an SSP 1.0 file of a plant FMU closed by a PID controller FMU, from a
system description (controller/systems/*.json):

    SystemStructure.ssd          the system: components plant and controller, connectors, connections,
                                 the default experiment (libcosim's fixed step in an annotation)
    resources/<plant>.fmu        both FMUs, as given
    resources/<controller>.fmu
    resources/controller.ssv     the controller's gains, limits and setpoints (parameter values)

    python controller/make_ssp.py SYSTEM.json --plant PLANT.fmu --controller PID.fmu -o OUT.ssp

Channel k of the controller measures the plant output `measurement` and
drives the plant input `command`; its setpoint is a start value in the .ssv.
"""
import argparse
import json
import pathlib
import sys
import xml.etree.ElementTree as ET
import zipfile

from packing import write_zip, xml_text

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
OSP = "http://opensimulationplatform.com/SSP/OSPAnnotations"
PARAMETERS = ["Kp", "Ki", "Kd", "Tf", "c", "u_min", "u_max"]
FMU_TYPE = "application/x-fmu-sharedlibrary"


def fmu_variables(path):
    """{name: causality} of an FMU's model description."""
    with zipfile.ZipFile(path) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    return {v.get("name"): v.get("causality", "local") for v in root.iter("ScalarVariable")}


def checked_channels(system, plant, controller):
    """The system's channels, each plant name checked against the plant FMU."""
    channels = system["channels"]
    if sum(1 for name in controller if name.startswith("command[")) != len(channels):
        raise ValueError(f"the controller FMU does not have {len(channels)} channels")
    for k, ch in enumerate(channels):
        for key, causality in (("measurement", "output"), ("command", "input")):
            name = ch.get(key)
            if plant.get(name) != causality:
                raise ValueError(f"channels[{k}].{key}: '{name}' is not an {causality} of the plant")
        unknown = set(ch) - {"measurement", "command", "setpoint", *PARAMETERS}
        if unknown:
            raise ValueError(f"channels[{k}]: unknown keys {sorted(unknown)}")
    return channels


def connector(parent, name, kind):
    c = ET.SubElement(parent, f"{{{SSD}}}Connector", name=name, kind=kind)
    ET.SubElement(c, f"{{{SSC}}}Real")


def system_structure(system, channels, plant_source, controller_source):
    root = ET.Element(f"{{{SSD}}}SystemStructureDescription", version="1.0", name=system["name"])
    sys_el = ET.SubElement(root, f"{{{SSD}}}System", name=system["name"],
                           description=system.get("description", ""))
    elements = ET.SubElement(sys_el, f"{{{SSD}}}Elements")
    plant = ET.SubElement(elements, f"{{{SSD}}}Component", name="plant", source=plant_source, type=FMU_TYPE)
    plant_connectors = ET.SubElement(plant, f"{{{SSD}}}Connectors")
    controller = ET.SubElement(elements, f"{{{SSD}}}Component", name="controller", source=controller_source,
                               type=FMU_TYPE)
    controller_connectors = ET.SubElement(controller, f"{{{SSD}}}Connectors")
    for k, ch in enumerate(channels):
        connector(plant_connectors, ch["command"], "input")
        connector(plant_connectors, ch["measurement"], "output")
        connector(controller_connectors, f"measurement[{k + 1}]", "input")
        connector(controller_connectors, f"command[{k + 1}]", "output")
    bindings = ET.SubElement(controller, f"{{{SSD}}}ParameterBindings")
    ET.SubElement(bindings, f"{{{SSD}}}ParameterBinding", source="resources/controller.ssv")
    connections = ET.SubElement(sys_el, f"{{{SSD}}}Connections")
    for k, ch in enumerate(channels):
        ET.SubElement(connections, f"{{{SSD}}}Connection", startElement="plant", startConnector=ch["measurement"],
                      endElement="controller", endConnector=f"measurement[{k + 1}]")
        ET.SubElement(connections, f"{{{SSD}}}Connection", startElement="controller",
                      startConnector=f"command[{k + 1}]", endElement="plant", endConnector=ch["command"])
    experiment = ET.SubElement(root, f"{{{SSD}}}DefaultExperiment", startTime="0", stopTime=repr(system["stop_time"]))
    annotations = ET.SubElement(experiment, f"{{{SSD}}}Annotations")
    annotation = ET.SubElement(annotations, f"{{{SSC}}}Annotation", type="com.opensimulationplatform")
    ET.SubElement(annotation, f"{{{OSP}}}Algorithm").append(
        ET.Element(f"{{{OSP}}}FixedStepAlgorithm", baseStepSize=repr(system["step_size"])))
    return root


def parameter_values(system, channels):
    root = ET.Element(f"{{{SSV}}}ParameterSet", version="1.0", name=f"{system['name']} controller")
    parameters = ET.SubElement(root, f"{{{SSV}}}Parameters")
    for k, ch in enumerate(channels):
        for key in ["setpoint", *PARAMETERS]:
            if key in ch:
                p = ET.SubElement(parameters, f"{{{SSV}}}Parameter", name=f"{key}[{k + 1}]")
                ET.SubElement(p, f"{{{SSV}}}Real", value=repr(float(ch[key])))
    return root


def make_ssp(system_path, plant_fmu, controller_fmu, out):
    system = json.loads(pathlib.Path(system_path).read_text())
    channels = checked_channels(system, fmu_variables(plant_fmu), fmu_variables(controller_fmu))
    plant_source = f"resources/{pathlib.Path(plant_fmu).name}"
    controller_source = f"resources/{pathlib.Path(controller_fmu).name}"
    for prefix, uri in (("ssd", SSD), ("ssc", SSC), ("ssv", SSV), ("osp", OSP)):
        ET.register_namespace(prefix, uri)
    write_zip(out, {"SystemStructure.ssd": xml_text(system_structure(system, channels, plant_source,
                                                                     controller_source)),
                    "resources/controller.ssv": xml_text(parameter_values(system, channels)),
                    plant_source: pathlib.Path(plant_fmu), controller_source: pathlib.Path(controller_fmu)})


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("system", type=pathlib.Path)
    parser.add_argument("--plant", type=pathlib.Path, required=True)
    parser.add_argument("--controller", type=pathlib.Path, required=True)
    parser.add_argument("-o", "--out", type=pathlib.Path, required=True)
    args = parser.parse_args()
    try:
        make_ssp(args.system, args.plant, args.controller, args.out)
    except (ValueError, KeyError) as e:
        print(f"make_ssp: {args.system}: {e}", file=sys.stderr)
        return 1
    print(f"make_ssp: wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
