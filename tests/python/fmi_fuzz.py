"""Random FMI 2.0 Co-Simulation call sequences against an FMU binary, with
an oracle. Legal and illegal call orders, hostile values (NaN, inf, 1e300,
5e-324, negative), NULL arrays, unknown value references and fmi2Instantiate
variants. Each FMU's sequences run in a child process, so that a crash shows
as a signal and a hang as a timeout. The oracle flags:

  crash      the child died of a signal
  hang       the child did not finish in time
  nan        fmi2GetReal returned a non-finite value with fmi2OK
  accepted   fmi2OK where the standard (or the FMU's documented contract)
             requires an error: a call in a state that does not allow it,
             an unknown or output value reference, a fixed parameter set
             after initialization, a non-finite value, a wrong
             currentCommunicationPoint, a step size <= 0, an undeclared
             capability, a bad fmi2Instantiate
  changed    a refused fmi2SetReal changed a value (read back later)
  reset      after fmi2Reset a legal run differs from a clean one (bit for bit)
  discard    after fmi2Discard the outputs or the time are not the step start's
  silent     fmi2Error or fmi2Discard without a log message
  status     a status the FMU never returns (warning, fatal, pending)

Every sequence is reproducible from (seed, FMU, sequence number):

  python tests/python/fmi_fuzz.py FMU.fmu --seed S --first K --count 1 --verbose

prints the calls of sequence K with their statuses."""
import argparse
import ctypes
import json
import math
import os
import pathlib
import random
import signal
import struct
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
import zipfile

OK, WARNING, DISCARD, ERROR, FATAL, PENDING = range(6)
STATUS = ["OK", "Warning", "Discard", "Error", "Fatal", "Pending"]

INSTANTIATED, INIT, STEP_COMPLETE, STEP_FAILED, TERMINATED, ERROR_STATE = (
    "Instantiated", "InitializationMode", "StepComplete", "StepFailed", "Terminated", "Error")
ALL = {INSTANTIATED, INIT, STEP_COMPLETE, STEP_FAILED, TERMINATED, ERROR_STATE}
GET = {INIT, STEP_COMPLETE, STEP_FAILED, TERMINATED, ERROR_STATE}
SET = {INSTANTIATED, INIT, STEP_COMPLETE}
# Where the standard allows each function (FMI 2.0, 4.2.4; this FMU has no
# asynchronous steps, so no stepInProgress or stepCanceled).
ALLOWED = {
    "SetDebugLogging": ALL, "SetupExperiment": {INSTANTIATED}, "EnterInitializationMode": {INSTANTIATED},
    "ExitInitializationMode": {INIT}, "Terminate": {STEP_COMPLETE, STEP_FAILED}, "Reset": ALL,
    "GetReal": GET, "GetInteger": GET, "GetBoolean": GET, "GetString": GET,
    "SetReal": SET, "SetInteger": SET, "SetBoolean": SET, "SetString": SET,
    "DoStep": {STEP_COMPLETE}, "CancelStep": set(),
    "GetStatus": {STEP_COMPLETE, STEP_FAILED, TERMINATED}, "GetRealStatus": {STEP_COMPLETE, STEP_FAILED, TERMINATED},
    "GetIntegerStatus": {STEP_COMPLETE, STEP_FAILED, TERMINATED},
    "GetBooleanStatus": {STEP_COMPLETE, STEP_FAILED, TERMINATED},
    "GetStringStatus": {STEP_COMPLETE, STEP_FAILED, TERMINATED},
    "GetDirectionalDerivative": GET, "GetRealOutputDerivatives": {STEP_COMPLETE, STEP_FAILED, TERMINATED, ERROR_STATE},
    # FMU state: not after an error; freeing (of NULL too) in every state.
    "FreeFMUstate": ALL, "SetRealInputDerivatives": SET,
}
# Every capability is declared and supported: these are called with NULL
# pointers, never fmi2OK, except freeing a NULL state and calls with no
# references (n = 0), which do nothing.
NULL_ARGUMENTS = ["GetFMUstate", "SetFMUstate", "FreeFMUstate", "SerializedFMUstateSize", "SerializeFMUstate",
                  "DeSerializeFMUstate", "SetRealInputDerivatives", "GetDirectionalDerivative",
                  "GetRealOutputDerivatives"]
NO_REFERENCES = {"SetRealInputDerivatives", "GetDirectionalDerivative", "GetRealOutputDerivatives"}
HOSTILE = [math.nan, math.inf, -math.inf, 1e300, -1e300, 5e-324, -5e-324, 0.0, -0.0, -1.0, 1e-16, 1e10,
           2.2250738585072014e-308, 4294967296.0]
# Substep sizes that are refused (below h_min) or cheap; values from h_min
# to 1e-5 are legal but make each step long (tests cover them one by one).
HOSTILE_H_MAX = [5e-324, 1e-16, 1e-10, 0.0, -1e-3, math.nan, math.inf, 1e300, 1e-5, 0.5]
HOSTILE_STEP = [0.0, -0.01, math.nan, math.inf, -math.inf, 1e300, 5e-324, 1e-16, 1e-9, 1.0]
CATEGORIES = [b"logEvents", b"logStatusError", b"logStep", b"logAll", b"logNoSuchThing", None]

LOGGER = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p)
ALLOCATE = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t)
FREE = ctypes.CFUNCTYPE(None, ctypes.c_void_p)
STEP_FINISHED = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int)


class Callbacks(ctypes.Structure):
    _fields_ = [("logger", LOGGER), ("allocateMemory", ALLOCATE), ("freeMemory", FREE),
                ("stepFinished", STEP_FINISHED), ("componentEnvironment", ctypes.c_void_p)]


class Model:
    """What the oracle needs from modelDescription.xml."""

    def __init__(self, directory):
        root = ET.parse(os.path.join(directory, "modelDescription.xml")).getroot()
        self.guid = root.get("guid")
        self.identifier = root.find("CoSimulation").get("modelIdentifier")
        self.variables = []
        for v in root.find("ModelVariables"):
            real = v.find("Real")
            start = real.get("start") if real is not None else None
            self.variables.append(dict(name=v.get("name"), vr=int(v.get("valueReference")),
                                       causality=v.get("causality"), variability=v.get("variability"),
                                       start=float(start) if start is not None else None))
        self.by_vr = {v["vr"]: v for v in self.variables}
        self.by_name = {v["name"]: v["vr"] for v in self.variables}
        self.outputs = [v["vr"] for v in self.variables if v["causality"] == "output"]
        self.settable = [v["vr"] for v in self.variables if v["causality"] in ("parameter", "input")]
        self.starts = {v["vr"]: v["start"] for v in self.variables if v["start"] is not None}
        self.unknown = max(self.by_vr) + 1


def declare(lib):
    c, d, sz, st = ctypes.c_void_p, ctypes.c_double, ctypes.c_size_t, ctypes.c_int
    p = ctypes.c_void_p
    lib.fmi2Instantiate.restype = c
    lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, st, ctypes.c_char_p, ctypes.c_char_p, p, st, st]
    lib.fmi2FreeInstance.argtypes = [c]
    lib.fmi2FreeInstance.restype = None
    signatures = {
        "SetDebugLogging": [c, st, sz, p], "SetupExperiment": [c, st, d, d, st, d],
        "EnterInitializationMode": [c], "ExitInitializationMode": [c], "Terminate": [c], "Reset": [c],
        "GetReal": [c, p, sz, p], "SetReal": [c, p, sz, p], "GetInteger": [c, p, sz, p], "SetInteger": [c, p, sz, p],
        "GetBoolean": [c, p, sz, p], "SetBoolean": [c, p, sz, p], "GetString": [c, p, sz, p],
        "SetString": [c, p, sz, p], "DoStep": [c, d, d, st], "CancelStep": [c],
        "GetStatus": [c, st, p], "GetRealStatus": [c, st, p], "GetIntegerStatus": [c, st, p],
        "GetBooleanStatus": [c, st, p], "GetStringStatus": [c, st, p],
        "GetFMUstate": [c, p], "SetFMUstate": [c, p], "FreeFMUstate": [c, p],
        "SerializedFMUstateSize": [c, p, p], "SerializeFMUstate": [c, p, p, sz],
        "DeSerializeFMUstate": [c, p, sz, p], "GetDirectionalDerivative": [c, p, sz, p, sz, p, p],
        "SetRealInputDerivatives": [c, p, sz, p, p], "GetRealOutputDerivatives": [c, p, sz, p, p],
    }
    for name, args in signatures.items():
        f = getattr(lib, "fmi2" + name)
        f.argtypes = args
        f.restype = st


def args_text(name, args):
    """The arguments of a call as text: input arrays by their values, output
    arrays as out[n], the component as c."""
    def one(i, a):
        if a is None:
            return "NULL"
        if i == 0:
            return "c"
        if isinstance(a, ctypes.Array) and name.startswith("Get") and i == len(args) - 1:
            return f"out[{len(a)}]"
        if isinstance(a, ctypes.Array):
            return "[" + ", ".join(repr(x) for x in a) + "]"
        if isinstance(a, (int, float, bytes)):
            return repr(a)
        return "&value"
    return "(" + ", ".join(one(i, a) for i, a in enumerate(args)) + ")"


def bits(values):
    return struct.pack(f"{len(values)}d", *values)


class Fuzzer:
    """Runs sequences against one extracted FMU and checks the oracle."""

    def __init__(self, directory, seed, trace_fd=None, verbose=False):
        self.directory = directory
        self.model = Model(directory)
        self.lib = ctypes.CDLL(os.path.join(directory, "binaries", "linux64", self.model.identifier + ".so"))
        declare(self.lib)
        self.seed = seed
        self.trace_fd = trace_fd
        self.verbose = verbose
        self.log = []
        self.logger = LOGGER(lambda env, name, status, category, message: self.log.append((status, message)))
        self.callbacks = Callbacks(self.logger, ALLOCATE(0), FREE(0), STEP_FINISHED(0), None)
        self.resources = pathlib.Path(directory, "resources").resolve().as_uri().encode()
        self.violations = []
        self.calls = 0
        clean = self.instantiate_plain()
        self.clean = self.legal_run(clean)
        self.lib.fmi2FreeInstance(clean)
        assert self.clean is not None, "the FMU does not run: " + repr(self.log[-3:])

    # -- bookkeeping -----------------------------------------------------

    def trace(self, text):
        """Records a call before it is made (a crash leaves it in the file)."""
        self.lines.append(text)
        if self.trace_fd is not None:
            os.write(self.trace_fd, (text + "\n").encode())

    def show(self):
        if self.verbose:
            print(self.lines[-1], flush=True)

    def flag(self, kind, detail):
        self.violations.append(dict(kind=kind, detail=detail, sequence=self.sequence, calls=list(self.lines)))

    def call(self, name, *args, check_message=True):
        """One fmi2 call: traced, its status checked against the state table."""
        self.trace(f"  fmi2{name}{args_text(name, args)} [{self.state}]")
        logged = len(self.log)
        began = time.monotonic()
        status = getattr(self.lib, "fmi2" + name)(*args)
        took = time.monotonic() - began
        self.calls += 1
        self.lines[-1] += f" -> {STATUS[status] if 0 <= status < 6 else status}"
        if took > 0.5:
            self.lines[-1] += f" ({took:.1f} s)"
        self.show()
        if status in (WARNING, FATAL, PENDING) or not 0 <= status < 6:
            self.flag("status", f"fmi2{name} returned {status}")
        if status in (ERROR, DISCARD) and check_message and self.with_logger and args and args[0]:
            if not any(s == status for s, _ in self.log[logged:]):
                self.flag("silent", f"fmi2{name} returned {STATUS[status]} without a log message")
        if status != ERROR and not args[0]:
            self.flag("accepted", f"fmi2{name} on a NULL component returned {STATUS[status]}")
        elif status != ERROR and self.state not in ALLOWED.get(name, set()):
            self.flag("accepted", f"fmi2{name} returned {STATUS[status]} in state {self.state}")
        return status

    # -- instances -------------------------------------------------------

    def instantiate_plain(self):
        self.lines, self.sequence, self.with_logger = [], -1, True
        c = self.lib.fmi2Instantiate(b"clean", 1, self.model.guid.encode(), self.resources,
                                     ctypes.byref(self.callbacks), 0, 0)
        assert c, "the FMU does not instantiate: " + repr(self.log[-3:])
        self.reset_model()
        return c

    def instantiate(self, rng):
        """fmi2Instantiate, now and then with a bad argument (then it must fail)."""
        variant = rng.choice(["plain"] * 12 + ["guid", "uri", "relative", "nul", "type", "name", "empty",
                                               "null guid", "null uri", "no logger", "no callbacks"])
        name, kind, guid, uri = b"fuzz", 1, self.model.guid.encode(), self.resources
        callbacks = ctypes.byref(self.callbacks)
        bad = variant not in ("plain", "no logger", "no callbacks")
        if variant == "guid": guid = b"{00000000-0000-0000-0000-000000000000}"
        if variant == "uri": uri = b"http://example.org/resources"
        if variant == "relative": uri = b"resources"
        if variant == "nul": uri = self.resources.replace(b"/resources", b"/res%00ources")
        if variant == "type": kind = 0
        if variant == "name": name = None
        if variant == "empty": name = b""
        if variant == "null guid": guid = None
        if variant == "null uri": uri = None
        if variant == "no logger":
            self.bare = Callbacks(LOGGER(0), ALLOCATE(0), FREE(0), STEP_FINISHED(0), None)
            callbacks = ctypes.byref(self.bare)
        if variant == "no callbacks": callbacks = None
        self.with_logger = variant not in ("no logger", "no callbacks")
        self.trace(f"  fmi2Instantiate[{variant}]")
        c = self.lib.fmi2Instantiate(name, kind, guid, uri, callbacks, 0, rng.random() < 0.3)
        self.lines[-1] += f" -> {'component' if c else 'NULL'}"
        self.show()
        if c and bad:
            self.flag("accepted", f"fmi2Instantiate with a bad argument ({variant}) returned a component")
        self.reset_model()
        return c

    def reset_model(self):
        self.state = INSTANTIATED
        self.values = dict(self.model.starts)
        self.time = 0.0
        self.start_time, self.stop_time = 0.0, None

    # -- the oracle's legal run ------------------------------------------

    def legal_run(self, c):
        """setupExperiment(0), initialization and three steps of 0.01 s from
        the start values: every output, parameter and input, as bytes (None
        if a call of it failed)."""
        if self.call("SetupExperiment", c, 0, 0.0, 0.0, 0, 0.0) != OK:
            return None
        if self.call("EnterInitializationMode", c) != OK:
            return None
        self.state = INIT
        if self.call("ExitInitializationMode", c) != OK:
            return None
        self.state = STEP_COMPLETE
        for k in range(3):
            if self.call("DoStep", c, 0.01 * k, 0.01, 1) != OK:
                return None
        self.time = 0.01 * 2 + 0.01
        values = self.get(c, self.model.outputs + self.model.settable)
        return bits(values) if values is not None else None

    def get(self, c, vrs):
        array = (ctypes.c_double * len(vrs))()
        status = self.call("GetReal", c, (ctypes.c_uint * len(vrs))(*vrs), len(vrs), array)
        return list(array) if status == OK else None

    # -- actions -----------------------------------------------------------

    def value_for(self, rng, vr):
        name = self.model.by_vr.get(vr, {}).get("name", "")
        if name == "solver.h_max" and rng.random() < 0.5:
            return rng.choice(HOSTILE_H_MAX)
        if name == "solver.max_substeps" and rng.random() < 0.7:
            return rng.choice([0.0, -1.0, 2.5, math.nan, 1e10, 1.0, 3.0, 1000.0])
        if rng.random() < 0.3:
            return rng.choice(HOSTILE)
        start = self.model.starts.get(vr, 0.0)
        noise = 0.0 if name.startswith("solver.") else rng.uniform(-0.1, 0.1)
        return start * rng.uniform(0.5, 1.5) + noise

    def references(self, rng, pool):
        n = rng.choice([0, 1, 1, 1, 2, 3, 5])
        vrs = []
        for _ in range(n):
            r = rng.random()
            vrs.append(rng.choice(pool) if r < 0.8 or not self.model.outputs else
                       rng.choice(self.model.outputs) if r < 0.9 else
                       rng.choice([self.model.unknown, 999999, 2**32 - 1]))
        return vrs

    def set_real(self, rng, c):
        vrs = self.references(rng, self.model.settable or self.model.outputs)
        values = [self.value_for(rng, vr) for vr in vrs]
        null = rng.random() < 0.05 and vrs
        status = self.call("SetReal", c, None if null else (ctypes.c_uint * len(vrs))(*vrs), len(vrs),
                           None if null else (ctypes.c_double * len(vrs))(*values))
        fixed_now = self.state == STEP_COMPLETE
        valid = not null and all(
            vr in self.model.by_vr and self.model.by_vr[vr]["causality"] != "output" and math.isfinite(x) and
            not (fixed_now and self.model.by_vr[vr]["variability"] == "fixed") for vr, x in zip(vrs, values))
        if status == OK and not valid:
            self.flag("accepted", f"fmi2SetReal({vrs}, {values}) returned OK in state {self.state}")
        if status == OK:
            self.values.update(zip(vrs, values))

    def get_real(self, rng, c):
        pool = self.model.outputs + self.model.settable
        vrs = self.references(rng, pool)
        null = rng.random() < 0.05 and vrs
        array = (ctypes.c_double * len(vrs))()
        status = self.call("GetReal", c, None if null else (ctypes.c_uint * len(vrs))(*vrs), len(vrs),
                           None if null else array)
        if status != OK:
            return
        if null or any(vr not in self.model.by_vr for vr in vrs):
            self.flag("accepted", f"fmi2GetReal({'NULL' if null else vrs}) returned OK")
            return
        for vr, x in zip(vrs, array):
            if not math.isfinite(x):
                self.flag("nan", f"fmi2GetReal: {self.model.by_vr[vr]['name']} = {x} with fmi2OK")
            elif vr in self.values and bits([x]) != bits([self.values[vr]]):
                self.flag("changed", f"{self.model.by_vr[vr]['name']} reads {x}, expected {self.values[vr]}")

    def setup(self, rng, c):
        start = rng.choice([0.0, 0.0, 0.0, rng.uniform(-10, 10), 1e9, 1e10, rng.choice(HOSTILE)])
        stop_defined = rng.random() < 0.3
        stop = start + rng.choice([1.0, 0.05, -1.0, math.nan, 1e300])
        status = self.call("SetupExperiment", c, rng.random() < 0.5, rng.choice([1e-6, math.nan, -1.0]), start,
                           stop_defined, stop)
        valid = math.isfinite(start) and (not stop_defined or stop >= start)
        if status == OK and not valid:
            self.flag("accepted", f"fmi2SetupExperiment(start {start}, stop {stop}) returned OK")
        if status == OK:
            self.start_time, self.stop_time = start, stop if stop_defined else None

    def enter(self, rng, c):
        state = self.state
        status = self.call("EnterInitializationMode", c)
        if state == INSTANTIATED:
            self.state = INIT if status == OK else ERROR_STATE

    def exit(self, rng, c):
        state = self.state
        status = self.call("ExitInitializationMode", c)
        if state == INIT:
            self.state = STEP_COMPLETE if status == OK else ERROR_STATE
            self.time = self.start_time

    def step(self, rng, c):
        t = self.time
        if rng.random() < 0.15:
            t += rng.choice([1e-3, -1e-3, 1.0, 1e-6 * max(1.0, abs(t)), math.nan])
        # Wrong beyond round-off (an offset below the resolution of t is none).
        scale = max(abs(t), abs(self.time), abs(self.start_time)) if math.isfinite(t) else 0.0
        wrong = not abs(t - self.time) <= 64 * sys.float_info.epsilon * scale
        H = rng.choice([0.01, 0.001, 0.02, rng.uniform(1e-4, 0.05)])
        if rng.random() < 0.15:
            H = rng.choice(HOSTILE_STEP)
        before = self.get(c, self.model.outputs) if self.state == STEP_COMPLETE else None
        state = self.state
        status = self.call("DoStep", c, t, H, rng.random() < 0.9)
        past_stop = self.stop_time is not None and t + H > self.stop_time + 1e-9 * max(1.0, abs(self.stop_time))
        valid = not wrong and math.isfinite(H) and H > 0 and math.isfinite(t + H) and not past_stop
        if status in (OK, DISCARD) and not valid:
            self.flag("accepted", f"fmi2DoStep({t!r}, {H!r}) at FMU time {self.time!r} returned {STATUS[status]}")
        if state != STEP_COMPLETE:
            return
        if status == ERROR:  # refused: nothing moved
            after = self.get(c, self.model.outputs)
            if before is not None and (after is None or bits(after) != bits(before)):
                self.flag("changed", "a refused fmi2DoStep changed the outputs")
            return
        if status == OK:
            self.time = t + H
            return
        self.state = STEP_FAILED
        after = self.get(c, self.model.outputs)
        if before is not None and (after is None or bits(after) != bits(before)):
            self.flag("discard", "after fmi2Discard the outputs are not those of the step start")
        last = ctypes.c_double()
        if self.call("GetRealStatus", c, 2, ctypes.byref(last)) != OK or bits([last.value]) != bits([self.time]):
            self.flag("discard", f"fmi2LastSuccessfulTime is {last.value!r}, the step started at {self.time!r}")

    def status(self, rng, c):
        name = rng.choice(["GetStatus", "GetRealStatus", "GetIntegerStatus", "GetBooleanStatus",
                           "GetStringStatus"])
        kind = rng.choice([0, 1, 2, 3, 7])
        value = (ctypes.c_double if name == "GetRealStatus" else ctypes.c_int if name != "GetStringStatus"
                 else ctypes.c_char_p)()
        null = rng.random() < 0.2
        status = self.call(name, c, kind, None if null else ctypes.byref(value))
        answers = (name == "GetRealStatus" and kind == 2) or (name == "GetBooleanStatus" and kind == 3)
        if status == OK and (null or not answers):
            self.flag("accepted", f"fmi2{name}(kind {kind}, {'NULL' if null else 'value'}) returned OK")
        if status == OK and name == "GetRealStatus" and bits([value.value]) != bits([self.time]):
            self.flag("changed", f"fmi2LastSuccessfulTime is {value.value!r}, the FMU's time {self.time!r}")

    def other_types(self, rng, c):
        name = rng.choice(["GetInteger", "SetInteger", "GetBoolean", "SetBoolean", "GetString", "SetString"])
        n = rng.choice([0, 1, 2])
        null = rng.random() < 0.3
        vrs = (ctypes.c_uint * n)(*[rng.choice([0, 1, self.model.unknown]) for _ in range(n)])
        values = (ctypes.c_char_p if name.endswith("String") else ctypes.c_int) * n
        status = self.call(name, c, None if null else vrs, n, None if null else values())
        if status == OK and n > 0:
            self.flag("accepted", f"fmi2{name} of {n} values returned OK (the FMU has Real variables only)")

    def null_arguments(self, rng, c):
        name = rng.choice(NULL_ARGUMENTS)
        n = rng.choice([0, 1])  # counts and sizes; pointers NULL
        args = {"GetFMUstate": [None], "SetFMUstate": [None], "FreeFMUstate": [None],
                "SerializedFMUstateSize": [None, None], "SerializeFMUstate": [None, None, n],
                "DeSerializeFMUstate": [None, n, None], "GetDirectionalDerivative": [None, n, None, n, None, None],
                "SetRealInputDerivatives": [None, n, None, None],
                "GetRealOutputDerivatives": [None, n, None, None]}[name]
        status = self.call(name, c, *args)
        if status == OK and not (name == "FreeFMUstate" or (name in NO_REFERENCES and n == 0)):
            self.flag("accepted", f"fmi2{name} returned OK with NULL arguments")

    def logging(self, rng, c):
        chosen = [rng.choice(CATEGORIES) for _ in range(rng.choice([0, 1, 2]))]
        null = rng.random() < 0.1 and chosen
        array = (ctypes.c_char_p * len(chosen))(*chosen)
        status = self.call("SetDebugLogging", c, rng.random() < 0.5, len(chosen), None if null else array)
        known = all(x is not None and x != b"logNoSuchThing" for x in chosen)
        if status == OK and (null or not known):
            self.flag("accepted", f"fmi2SetDebugLogging({chosen}) returned OK")

    def simple(self, name):
        def act(rng, c):
            state = self.state
            status = self.call(name, c)
            if status == OK and name == "Terminate" and state in ALLOWED["Terminate"]:
                self.state = TERMINATED
            if status == OK and name == "Reset":
                self.reset_model()
        return act

    # -- sequences -------------------------------------------------------

    def legal_actions(self):
        return {
            INSTANTIATED: [self.setup, self.set_real, self.enter],
            INIT: [self.set_real, self.get_real, self.exit],
            STEP_COMPLETE: [self.step, self.step, self.step, self.set_real, self.get_real, self.simple("Terminate")],
            STEP_FAILED: [self.get_real, self.status, self.simple("Terminate"), self.simple("Reset")],
            TERMINATED: [self.get_real, self.simple("Reset")],
            ERROR_STATE: [self.get_real, self.simple("Reset")],
        }[self.state]

    def any_action(self):
        return [self.setup, self.enter, self.exit, self.set_real, self.get_real, self.step, self.status,
                self.other_types, self.null_arguments, self.logging, self.simple("Terminate"),
                self.simple("Reset"), self.simple("CancelStep")]

    def run_sequence(self, k):
        rng = random.Random(f"{self.seed}/{self.model.identifier}/{k}")
        self.sequence, self.lines = k, []
        self.trace(f"sequence {k}")
        self.show()
        c = self.instantiate(rng)
        if not c:
            # Calls on no component fail; freeing none is harmless.
            self.with_logger = False
            rng.choice(self.any_action())(rng, None)
            self.lib.fmi2FreeInstance(None)
            return
        bound = self.model.by_name.get("solver.max_substeps")
        if bound is not None and rng.random() < 0.8:
            # A bound of the master's choice keeps hard steps short: a
            # substep of a flexible scene whose Newton fails costs ms.
            if self.call("SetReal", c, (ctypes.c_uint * 1)(bound), 1, (ctypes.c_double * 1)(2000.0)) == OK:
                self.values[bound] = 2000.0
        for _ in range(rng.randint(1, 40)):
            action = rng.choice(self.legal_actions() if rng.random() < 0.7 else self.any_action())
            action(rng, c)
        if rng.random() < 0.25 and self.with_logger:
            self.check_reset(c)
        self.trace("  fmi2FreeInstance")
        self.show()
        self.lib.fmi2FreeInstance(c)

    def check_reset(self, c):
        if self.call("Reset", c) != OK:
            self.flag("reset", "fmi2Reset failed")
            return
        self.reset_model()
        if self.legal_run(c) != self.clean:
            self.flag("reset", "after fmi2Reset a legal run differs from a clean run")


def extract(fmu, directory):
    with zipfile.ZipFile(fmu) as z:
        z.extractall(directory)
    return directory


def child(args):
    """Runs sequences first .. first + count - 1 (or until the budget ends)
    and prints a JSON summary."""
    trace = os.open(args.trace, os.O_WRONLY | os.O_CREAT | os.O_TRUNC) if args.trace else None
    fuzzer = Fuzzer(args.directory, args.seed, trace, args.verbose)
    deadline = time.monotonic() + args.budget if args.budget else math.inf
    k = args.first
    while k < args.first + args.count and time.monotonic() < deadline:
        fuzzer.run_sequence(k)
        k += 1
    print(json.dumps(dict(sequences=k - args.first, calls=fuzzer.calls, violations=fuzzer.violations[:20])))


def run(fmu, seed, count=10**9, budget=None, timeout=120.0, first=0):
    """One FMU's sequences in a child process. Returns (summary, failures):
    failures are human-readable, each with the replay command."""
    fmu = pathlib.Path(fmu)
    with tempfile.TemporaryDirectory() as work:
        directory = extract(fmu, os.path.join(work, "fmu"))
        trace = os.path.join(work, "trace")
        command = [sys.executable, __file__, "--child", directory, "--seed", str(seed), "--first", str(first),
                   "--count", str(count), "--trace", trace] + (["--budget", str(budget)] if budget else [])
        try:
            done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return None, [describe(fmu, seed, "hang", f"no answer within {timeout} s", trace)]
        if done.returncode != 0:
            kind = "crash" if done.returncode < 0 else "child failed"
            why = (signal.Signals(-done.returncode).name if done.returncode < 0 else done.stderr[-2000:])
            return None, [describe(fmu, seed, kind, why, trace)]
        summary = json.loads(done.stdout.splitlines()[-1])
    failures = [f"{fmu.stem}: {v['kind']}: {v['detail']}\n  replay: {replay(fmu, seed, v['sequence'])}\n" +
                "\n".join(v["calls"]) for v in summary["violations"]]
    return summary, failures


def replay(fmu, seed, sequence):
    return f"python tests/python/fmi_fuzz.py {fmu} --seed {seed} --first {sequence} --count 1 --verbose"


def describe(fmu, seed, kind, why, trace):
    lines = pathlib.Path(trace).read_text(errors="replace").splitlines() if os.path.exists(trace) else []
    starts = [i for i, line in enumerate(lines) if line.startswith("sequence ")]
    last = lines[starts[-1]:] if starts else lines[-40:]
    sequence = int(last[0].split()[1]) if starts else 0
    return f"{fmu.stem}: {kind}: {why}\n  replay: {replay(fmu, seed, sequence)}\n" + "\n".join(last[-60:])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmus", nargs="*", help="FMUs (default: build/fmus/*.fmu)")
    parser.add_argument("--seed", type=int, default=None)
    parser.add_argument("--first", type=int, default=0)
    parser.add_argument("--count", type=int, default=10**9)
    parser.add_argument("--budget", type=float, default=None, help="seconds per FMU")
    parser.add_argument("--verbose", action="store_true")
    parser.add_argument("--child", dest="directory", help=argparse.SUPPRESS)
    parser.add_argument("--trace", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.directory:
        return child(args)
    seed = args.seed if args.seed is not None else random.SystemRandom().randrange(10**9)
    print(f"seed {seed}")
    if args.verbose:  # in this process: the calls as they happen
        for fmu in args.fmus:
            with tempfile.TemporaryDirectory() as work:
                fuzzer = Fuzzer(extract(fmu, work), seed, verbose=True)
                for k in range(args.first, args.first + min(args.count, 1000)):
                    fuzzer.run_sequence(k)
                for v in fuzzer.violations:
                    print(f"VIOLATION {v['kind']}: {v['detail']}")
        return 0
    root = pathlib.Path(__file__).resolve().parents[2]
    fmus = args.fmus or sorted((root / "build" / "fmus").glob("*.fmu"))
    failed = 0
    for fmu in fmus:
        timeout = (args.budget or 60.0) + 120.0
        began = time.monotonic()
        summary, failures = run(fmu, seed, args.count, args.budget, timeout, args.first)
        if summary:
            print(f"{pathlib.Path(fmu).stem}: {summary['sequences']} sequences, {summary['calls']} calls, "
                  f"{len(failures)} violations, {time.monotonic() - began:.1f} s", flush=True)
        for f in failures:
            print(f, flush=True)
        failed += len(failures)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
