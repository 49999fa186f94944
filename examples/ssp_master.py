#!/usr/bin/env python3
"""A co-simulation master in a few lines of fmpy: runs an SSP file of a plant
and a controller (build/ssp/*.ssp) with a fixed communication step H. Each
step reads the plant's outputs, passes them to the controller, reads its
commands at once (they depend directly on its inputs) and passes them to the
plant, then steps both FMUs from t to t + H (Gauss-Seidel: no delay in the
loop). Writes every connector over time to a CSV.

    python examples/ssp_master.py build/ssp/robot_arm_pid.ssp --step 1e-3 --stop-time 3 --out out
"""
import argparse
import pathlib
import shutil
import sys

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.ssp.ssd import read_ssd, read_ssv


def run(ssp, step, stop_time):
    """{connector 'component.name': values} and 'time', from t = 0 to stop_time."""
    ssd, unzip = read_ssd(str(ssp)), extract(str(ssp))
    fmus, vr = {}, {}
    for c in ssd.system.elements:
        md = read_model_description(f"{unzip}/{c.source}")
        vr[c.name] = {v.name: v.valueReference for v in md.modelVariables}
        fmus[c.name] = FMU2Slave(guid=md.guid, unzipDirectory=extract(f"{unzip}/{c.source}", f"{unzip}/{c.name}"),
                                 modelIdentifier=md.coSimulation.modelIdentifier, instanceName=c.name)
        fmus[c.name].instantiate()
        fmus[c.name].setupExperiment(startTime=0.0)
        for binding in c.parameterBindings:  # the .ssv: names relative to the component
            for p in read_ssv(str(ssp), binding.source).parameters:
                fmus[c.name].setReal([vr[c.name][p.name]], [float(p.value)])
        fmus[c.name].enterInitializationMode()
        fmus[c.name].exitInitializationMode()
    links = [(x.startElement, vr[x.startElement][x.startConnector], x.endElement, vr[x.endElement][x.endConnector])
             for x in ssd.system.connections]
    # Plant first: its outputs feed the controller, whose outputs feed the plant.
    order = sorted(links, key=lambda link: link[0] != "plant")
    names = [(x.startElement, x.startConnector) for x in ssd.system.connections]
    rows, n = [], int(round(stop_time / step))
    for i in range(n + 1):
        for source, out, target, inp in order:
            fmus[target].setReal([inp], fmus[source].getReal([out]))
        rows.append([i * step] + [fmus[e].getReal([vr[e][name]])[0] for e, name in names])
        if i < n:
            for fmu in fmus.values():
                fmu.doStep(i * step, step)
    for fmu in fmus.values():
        fmu.terminate()
        fmu.freeInstance()
    shutil.rmtree(unzip, ignore_errors=True)
    data = np.array(rows)
    return {"time": data[:, 0], **{f"{e}.{name}": data[:, 1 + k] for k, (e, name) in enumerate(names)}}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("ssp", type=pathlib.Path)
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--stop-time", type=float, default=3.0)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("out"))
    args = parser.parse_args()
    result = run(args.ssp, args.step, args.stop_time)
    args.out.mkdir(parents=True, exist_ok=True)
    csv = args.out / f"{args.ssp.stem}.csv"
    np.savetxt(csv, np.column_stack(list(result.values())), delimiter=",", header=",".join(result), comments="")
    print(f"ssp_master: wrote {csv.resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
