"""Shared by the example scripts: a CSV of named columns and a figure of
panels over time, both under an output folder; an FMU instance for a master
loop."""
import contextlib
import pathlib
import shutil

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402


def save_table(path: pathlib.Path, columns: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savetxt(path, np.column_stack(list(columns.values())), delimiter=",", header=",".join(columns), comments="")
    print(f"wrote {path.resolve()}")


def save_figure(path: pathlib.Path, t, panels: list, title: str) -> None:
    """panels: [(y label, {curve label: values})], one axis each, shared time."""
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.6 * len(panels)), sharex=True, squeeze=False,
                             layout="constrained")
    for ax, (label, curves) in zip(axes[:, 0], panels):
        for name, y in curves.items():
            ax.plot(t, y, label=name, lw=1)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        if len(curves) > 1:  # outside the axes: it never hides a curve
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title, fontsize=9)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"wrote {path.resolve()}")


@contextlib.contextmanager
def running_fmu(fmu_path, instance_name="master"):
    """An initialized FMU instance at t = 0 for a master loop, and its value
    references by name; terminated, freed and unpacked away afterwards."""
    md = read_model_description(str(fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzip = extract(str(fmu_path))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName=instance_name)
    try:
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        yield fmu, vr
        fmu.terminate()
    finally:
        fmu.freeInstance()
        shutil.rmtree(unzip, ignore_errors=True)
