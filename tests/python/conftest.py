"""Shared fixtures: where the build put things, packing scene variants, and a
thin FMI 2.0 CS driver over fmpy that returns statuses and captures the log."""
import ctypes
import json
import os
import pathlib
import shutil
import subprocess

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

ROOT = pathlib.Path(__file__).resolve().parents[2]
# MFBD_BUILD: another build folder (parallel work on one checkout).
BUILD = pathlib.Path(os.environ.get("MFBD_BUILD", ROOT / "build"))
FMUS = BUILD / "fmus"
PACKER = BUILD / "mfbd-pack"
EXAMPLES = ROOT / "examples"

OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3


def example_fmus():
    return sorted(FMUS.glob("*.fmu"))


def load_scene(name: str) -> dict:
    return json.loads((EXAMPLES / name / f"{name}.json").read_text())


def pack(scene, directory: pathlib.Path, name: str = "scene") -> subprocess.CompletedProcess:
    """Runs mfbd-pack on a scene (dict or raw text); the .fmu is directory/name.fmu."""
    text = scene if isinstance(scene, str) else json.dumps(scene, indent=1)
    path = directory / f"{name}.json"
    path.write_text(text)
    return subprocess.run([str(PACKER), str(path), "-o", str(directory / f"{name}.fmu")],
                          capture_output=True, text=True)


def packed(scene, directory: pathlib.Path, name: str = "scene") -> pathlib.Path:
    result = pack(scene, directory, name)
    assert result.returncode == 0, result.stderr
    return directory / f"{name}.fmu"


class Slave:
    """One FMU instance driven call by call. Methods return the fmi2Status
    instead of raising, and every log message is kept in self.log."""

    def __init__(self, fmu, unzip_dir=None, instance_name="instance"):
        self.md = read_model_description(str(fmu))
        self.unzip_dir = unzip_dir or extract(str(fmu))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.log = []
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzip_dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=instance_name)
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = fmi2CallbackLoggerTYPE(self._logger)
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(lambda n, s: None)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(lambda p: None)
        self._callbacks.componentEnvironment = None

    def _logger(self, env, name, status, category, message):
        self.log.append((status, category.decode(), message.decode()))

    def messages(self):
        return "\n".join(m for _, _, m in self.log)

    def instantiate(self, logging_on=False, resource_uri=None, guid=None):
        """Raw fmi2Instantiate; returns True if a component came back."""
        uri = resource_uri or (pathlib.Path(self.unzip_dir) / "resources").as_uri()
        self.fmu.component = self.fmu.fmi2Instantiate(
            self.fmu.instanceName.encode(), 1, (guid or self.md.guid).encode(), uri.encode(),
            ctypes.byref(self._callbacks), 0, 1 if logging_on else 0)
        return bool(self.fmu.component)

    def call(self, function, *args):
        try:
            getattr(self.fmu, function)(*args)
            return OK
        except FMICallException as e:
            return e.status

    def refuses(self, message, function, *args):
        """Whether the call returns fmi2Error and the log then holds `message`."""
        return self.call(function, *args) == ERROR and message in self.messages()

    def start(self, start_values=None, start_time=0.0, stop_time=None, tolerance=None):
        assert self.instantiate(), self.messages()
        assert self.call("setupExperiment", tolerance, start_time, stop_time) == OK, self.messages()
        for name, value in (start_values or {}).items():
            assert self.set(name, value) == OK, self.messages()
        assert self.call("enterInitializationMode") == OK, self.messages()
        assert self.call("exitInitializationMode") == OK, self.messages()
        return self

    def set(self, name, value):
        return self.call("setReal", [self.vr[name]], [float(value)])

    def get(self, *names):
        values = self.fmu.getReal([self.vr[n] for n in names])
        return values[0] if len(names) == 1 else values

    def step(self, t, h):
        return self.call("doStep", t, h, 1)

    def free(self):
        if self.fmu.component:
            self.fmu.fmi2FreeInstance(self.fmu.component)
            self.fmu.component = None
        self.fmu.freeLibrary()


@pytest.fixture
def pendulum_fmu():
    return FMUS / "pendulum.fmu"


@pytest.fixture
def slave(pendulum_fmu):
    s = Slave(pendulum_fmu)
    yield s
    s.free()
    shutil.rmtree(s.unzip_dir, ignore_errors=True)


def simulate_fixed_step(fmu, **options):
    """fmpy's simulate_fmu without an FMI tolerance (fmpy otherwise passes
    the DefaultExperiment's): substeps of solver.h_max, for tests of what a
    fixed step does (its order, its energy drift)."""
    from fmpy import simulate_fmu
    md = read_model_description(str(fmu))
    md.defaultExperiment.tolerance = None
    return simulate_fmu(str(fmu), model_description=md, relative_tolerance=None, **options)
