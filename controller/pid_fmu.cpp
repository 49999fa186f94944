// The PID controller (pid.hpp) as an FMI 2.0 Co-Simulation FMU. The number of
// channels is fixed when the FMU is packed (controller/pack_controller.py): the
// binary reads it, with the GUID, from resources/pid_controller.txt.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <new>
#include <string>

#include "fmi2Functions.h"
#include "entry_point.hpp"
#include "math/number_text.hpp"
#include "pid.hpp"
#include "resource_uri.hpp"

namespace {

using mfbd::pid::Kind;

// The FMU's states, one bit each, so that a function's allowed states are a mask.
enum class Phase : unsigned { Instantiated = 1, Initialization = 2, Stepping = 4, Terminated = 8 };
constexpr unsigned kInstantiated = 1, kInitialization = 2, kStepping = 4, kTerminated = 8;
constexpr unsigned kAny = kInstantiated | kInitialization | kStepping | kTerminated;
constexpr unsigned kSet = kInstantiated | kInitialization | kStepping;
constexpr unsigned kGet = kInitialization | kStepping | kTerminated;
constexpr unsigned kStatus = kStepping | kTerminated;

struct Controller {
  std::string name, guid;
  fmi2CallbackFunctions callbacks{};
  bool logging = false;
  Phase phase = Phase::Instantiated;
  mfbd::pid::State state;
  double startTime = 0;

  std::size_t channels() const { return state.channels.size(); }
  void log(fmi2Status status, const char* category, const std::string& message) const {
    if (!callbacks.logger || (!logging && status < fmi2Warning)) return;
    callbacks.logger(callbacks.componentEnvironment, name.c_str(), status, category,
                     mfbd::loggerFormat(message).c_str());
  }
  fmi2Status fail(const char* function, const std::string& why) const {
    log(fmi2Error, "logStatusError", std::string(function) + ": " + why);
    return fmi2Error;
  }
  // Whether the present state allows a function (`mask`: the states that do).
  bool allow(const char* function, unsigned mask) const {
    if (static_cast<unsigned>(phase) & mask) return true;
    fail(function, "not allowed in the present state of the FMU (FMI 2.0 section 4.2.4)");
    return false;
  }
  std::string variable(fmi2ValueReference vr) const {
    return std::string(mfbd::pid::kKindNames[vr / channels()]) + "[" + std::to_string(vr % channels() + 1) + "]";
  }
  // The variable of a value reference, or false with the reason logged.
  bool locate(const char* function, fmi2ValueReference vr, Kind& kind, std::size_t& channel) const {
    if (vr >= mfbd::pid::kKinds * channels()) {
      fail(function, "unknown value reference " + std::to_string(vr) + " (this controller has " +
                         std::to_string(mfbd::pid::kKinds * channels()) + " Real variables)");
      return false;
    }
    kind = Kind(vr / channels());
    channel = vr % channels();
    return true;
  }
};

// Runs `body` on the controller when its state allows `function`; no
// exception leaves (fmu_src/entry_point.hpp, shared with the plant).
template <class Body>
fmi2Status guarded(fmi2Component c, const char* function, unsigned mask, Body body) {
  return mfbd::guardedCall<Controller>(c, function, mask, body);
}

// The status functions' guard: after a step, with a value to write.
template <class Body>
fmi2Status statusCall(fmi2Component c, const char* function, const void* value, Body body) {
  return guarded(c, function, kStatus, [&](Controller* ctl) {
    return value ? body(ctl) : ctl->fail(function, "null value pointer");
  });
}

// resources/pid_controller.txt: "format mfbd-pid/1", "channels N", "guid G".
std::string readResources(const std::string& uri, std::size_t& channels, std::string& guid) {
  std::string dir, why;
  if (!mfbd::resourceUriToPath(uri, dir, why)) return "fmuResourceLocation: " + why;
  std::ifstream in(dir + "/pid_controller.txt");
  if (!in) return "cannot read " + dir + "/pid_controller.txt";
  std::string key, format;
  long long n = 0;
  while (in >> key) {
    if (key == "format") in >> format;
    else if (key == "channels") in >> n;
    else if (key == "guid") in >> guid;
    else return "pid_controller.txt: unknown key '" + key + "'";
  }
  if (format != "mfbd-pid/1") return "pid_controller.txt: format '" + format + "', expected mfbd-pid/1";
  if (n < 1 || n > 100000) return "pid_controller.txt: channels must be a whole number from 1 to 100000";
  channels = std::size_t(n);
  return "";
}

}  // namespace

extern "C" {

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions,
                              fmi2Boolean /*visible*/, fmi2Boolean loggingOn) {
  auto refuse = [&](const std::string& message) -> fmi2Component {
    mfbd::reportInstantiateError(functions, instanceName, message.c_str());
    return nullptr;
  };
  if (const char* why = mfbd::instantiateArgumentError(instanceName, fmuType, fmuGUID, fmuResourceLocation))
    return refuse(why);
  try {
    std::size_t channels = 0;
    std::string guid;
    const std::string why = readResources(fmuResourceLocation, channels, guid);
    if (!why.empty()) return refuse(why);
    if (guid != fmuGUID) return refuse(std::string("GUID ") + fmuGUID + " is not this FMU's " + guid);
    auto* ctl = new Controller;
    ctl->name = instanceName;
    ctl->guid = guid;
    if (functions) ctl->callbacks = *functions;
    ctl->logging = loggingOn;
    ctl->state.channels.resize(channels);
    return ctl;
  } catch (const std::exception& e) {
    return refuse(e.what());
  }
}

void fmi2FreeInstance(fmi2Component c) { delete static_cast<Controller*>(c); }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t n, const fmi2String categories[]) {
  return guarded(c, "fmi2SetDebugLogging", kAny, [&](Controller* ctl) {
    if (n > 0 && !categories) return ctl->fail("fmi2SetDebugLogging", "null categories");
    for (size_t i = 0; i < n; ++i)
      if (!categories[i] || std::strcmp(categories[i], "logStatusError") != 0)
        return ctl->fail("fmi2SetDebugLogging", "unknown log category (this FMU has logStatusError)");
    ctl->logging = loggingOn;
    return fmi2OK;
  });
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean, fmi2Real, fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime) {
  return guarded(c, "fmi2SetupExperiment", kInstantiated, [&](Controller* ctl) {
    if (!std::isfinite(startTime)) return ctl->fail("fmi2SetupExperiment", "startTime must be finite");
    if (stopTimeDefined && !(stopTime >= startTime))
      return ctl->fail("fmi2SetupExperiment", "stopTime must be >= startTime");
    ctl->startTime = ctl->state.time = startTime;
    return fmi2OK;
  });
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
  return guarded(c, "fmi2EnterInitializationMode", kInstantiated, [&](Controller* ctl) {
    ctl->phase = Phase::Initialization;
    return fmi2OK;
  });
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
  return guarded(c, "fmi2ExitInitializationMode", kInitialization, [&](Controller* ctl) {
    for (auto& ch : ctl->state.channels) mfbd::pid::initialize(ch);
    ctl->phase = Phase::Stepping;
    return fmi2OK;
  });
}

fmi2Status fmi2Terminate(fmi2Component c) {
  return guarded(c, "fmi2Terminate", kStepping, [&](Controller* ctl) {
    ctl->phase = Phase::Terminated;
    return fmi2OK;
  });
}

fmi2Status fmi2Reset(fmi2Component c) {
  return guarded(c, "fmi2Reset", kAny, [&](Controller* ctl) {
    ctl->state = mfbd::pid::State{0, std::vector<mfbd::pid::Channel>(ctl->channels())};
    ctl->startTime = 0;
    ctl->phase = Phase::Instantiated;
    return fmi2OK;
  });
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[]) {
  return guarded(c, "fmi2GetReal", kGet, [&](Controller* ctl) {
    if (n > 0 && (!vr || !value)) return ctl->fail("fmi2GetReal", "null array");
    Kind kind;
    std::size_t k;
    for (size_t i = 0; i < n; ++i)
      if (!ctl->locate("fmi2GetReal", vr[i], kind, k)) return fmi2Error;
    for (size_t i = 0; i < n; ++i) {
      ctl->locate("fmi2GetReal", vr[i], kind, k);
      const auto& ch = ctl->state.channels[k];
      value[i] = kind == mfbd::pid::Command ? mfbd::pid::command(ch) : ch.value[kind];
    }
    return fmi2OK;
  });
}

// Checks the whole call first (a refused call changes nothing), on a copy of
// the channels so that u_min and u_max set together are checked together.
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[]) {
  const char* f = "fmi2SetReal";
  return guarded(c, f, kSet, [&](Controller* ctl) {
    if (n > 0 && (!vr || !value)) return ctl->fail(f, "null array");
    std::vector<mfbd::pid::Channel> next = ctl->state.channels;
    for (size_t i = 0; i < n; ++i) {
      Kind kind;
      std::size_t k;
      if (!ctl->locate(f, vr[i], kind, k)) return fmi2Error;
      const std::string variable = ctl->variable(vr[i]);
      if (kind == mfbd::pid::Command) return ctl->fail(f, variable + " is an output, which cannot be set");
      if (!std::isfinite(value[i])) return ctl->fail(f, variable + ": expected a finite number");
      next[k].value[kind] = value[i];
      if (kind == mfbd::pid::Setpoint) next[k].setpointRate = 0;  // a new value: no ramp until one is given
      if (kind == mfbd::pid::Measurement) next[k].measurementRate = 0;
    }
    for (std::size_t k = 0; k < next.size(); ++k)
      for (int kind = mfbd::pid::Kp; kind < mfbd::pid::kKinds; ++kind) {
        const std::string why = mfbd::pid::refusal(next[k], Kind(kind), next[k].value[kind]);
        if (!why.empty()) return ctl->fail(f, ctl->variable(fmi2ValueReference(kind * next.size() + k)) + ": " + why);
      }
    ctl->state.channels.swap(next);
    return fmi2OK;
  });
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[]) {
  const char* f = "fmi2SetRealInputDerivatives";
  return guarded(c, f, kSet, [&](Controller* ctl) {
    if (n > 0 && (!vr || !order || !value)) return ctl->fail(f, "null array");
    for (size_t i = 0; i < n; ++i) {
      Kind kind;
      std::size_t k;
      if (!ctl->locate(f, vr[i], kind, k)) return fmi2Error;
      if (kind != mfbd::pid::Setpoint && kind != mfbd::pid::Measurement)
        return ctl->fail(f, ctl->variable(vr[i]) + " is not an input");
      if (order[i] != 1)
        return ctl->fail(f, "order " + std::to_string(order[i]) + ": expected 1 (inputs are ramped, not curved)");
      if (!std::isfinite(value[i])) return ctl->fail(f, "expected a finite derivative");
    }
    for (size_t i = 0; i < n; ++i) {
      auto& ch = ctl->state.channels[vr[i] % ctl->channels()];
      (vr[i] / ctl->channels() == mfbd::pid::Setpoint ? ch.setpointRate : ch.measurementRate) = value[i];
    }
    return fmi2OK;
  });
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean) {
  return guarded(c, "fmi2DoStep", kStepping, [&](Controller* ctl) {
    const double now = ctl->state.time;
    const double scale = std::max({std::fabs(t), std::fabs(now), std::fabs(ctl->startTime)});
    if (!(std::fabs(t - now) <= 8 * 2.220446049250313e-16 * scale))
      return ctl->fail("fmi2DoStep", "currentCommunicationPoint " + mfbd::numberText(t) +
                                         " is not the FMU's time " + mfbd::numberText(now));
    if (!(h > 0) || !std::isfinite(t + h))
      return ctl->fail("fmi2DoStep", "communicationStepSize must be a finite number > 0");
    for (auto& ch : ctl->state.channels) mfbd::pid::step(ch, h);
    ctl->state.time = t + h;
    return fmi2OK;
  });
}

fmi2Status fmi2CancelStep(fmi2Component c) {
  return c ? static_cast<Controller*>(c)->fail("fmi2CancelStep", "steps complete at once") : fmi2Error;
}

// --- FMU state: the whole pid::State, in memory or as bytes ---------------------

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state) {
  return guarded(c, "fmi2GetFMUstate", kAny, [&](Controller* ctl) {
    if (!state) return ctl->fail("fmi2GetFMUstate", "null FMUstate pointer");
    try {
      if (*state) *static_cast<mfbd::pid::State*>(*state) = ctl->state;  // the master reuses a state it owns
      else *state = new mfbd::pid::State(ctl->state);
    } catch (const std::bad_alloc&) {
      return ctl->fail("fmi2GetFMUstate", "out of memory");
    }
    return fmi2OK;
  });
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
  return guarded(c, "fmi2SetFMUstate", kAny, [&](Controller* ctl) {
    const auto* s = static_cast<const mfbd::pid::State*>(state);
    if (!s) return ctl->fail("fmi2SetFMUstate", "null FMUstate");
    if (s->channels.size() != ctl->channels())
      return ctl->fail("fmi2SetFMUstate", "the state has " + std::to_string(s->channels.size()) +
                                              " channels, this controller " + std::to_string(ctl->channels()));
    ctl->state = *s;
    return fmi2OK;
  });
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state) {
  return guarded(c, "fmi2FreeFMUstate", kAny, [&](Controller* ctl) {
    if (!state) return ctl->fail("fmi2FreeFMUstate", "null FMUstate pointer");
    delete static_cast<mfbd::pid::State*>(*state);
    *state = nullptr;
    return fmi2OK;
  });
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size) {
  return guarded(c, "fmi2SerializedFMUstateSize", kAny, [&](Controller* ctl) {
    if (!state || !size) return ctl->fail("fmi2SerializedFMUstateSize", "null argument");
    *size = mfbd::pid::serialize(*static_cast<const mfbd::pid::State*>(state)).size();
    return fmi2OK;
  });
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
  return guarded(c, "fmi2SerializeFMUstate", kAny, [&](Controller* ctl) {
    if (!state || !bytes) return ctl->fail("fmi2SerializeFMUstate", "null argument");
    const std::string data = mfbd::pid::serialize(*static_cast<const mfbd::pid::State*>(state));
    if (size != data.size())
      return ctl->fail("fmi2SerializeFMUstate", "size " + std::to_string(size) + ", expected " +
                                                    std::to_string(data.size()) + " (fmi2SerializedFMUstateSize)");
    std::memcpy(bytes, data.data(), size);
    return fmi2OK;
  });
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate* state) {
  return guarded(c, "fmi2DeSerializeFMUstate", kAny, [&](Controller* ctl) {
    if (!state) return ctl->fail("fmi2DeSerializeFMUstate", "null FMUstate pointer");
    try {
      auto s = mfbd::pid::deserialize(bytes, size, ctl->channels());
      if (*state) *static_cast<mfbd::pid::State*>(*state) = std::move(s);
      else *state = new mfbd::pid::State(std::move(s));
    } catch (const std::exception& e) {
      return ctl->fail("fmi2DeSerializeFMUstate", e.what());
    }
    return fmi2OK;
  });
}

// --- what this FMU does not have: declared so in modelDescription.xml -----------

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference[], size_t,
                                        const fmi2ValueReference[], size_t, const fmi2Real[], fmi2Real[]) {
  return c ? static_cast<Controller*>(c)->fail("fmi2GetDirectionalDerivative", "not provided") : fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t, const fmi2Integer[],
                                        fmi2Real[]) {
  return c ? static_cast<Controller*>(c)->fail("fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder is 0")
           : fmi2Error;
}

// No Integer, Boolean or String variables: only empty calls succeed, where a
// call of that kind is allowed.
static fmi2Status noVariables(fmi2Component c, const char* function, size_t n, bool get) {
  return guarded(c, function, get ? kGet : kSet, [&](Controller* ctl) {
    return n == 0 ? fmi2OK : ctl->fail(function, "this FMU has Real variables only");
  });
}
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference[], size_t n, fmi2Integer[]) {
  return noVariables(c, "fmi2GetInteger", n, true);
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference[], size_t n, fmi2Boolean[]) {
  return noVariables(c, "fmi2GetBoolean", n, true);
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference[], size_t n, fmi2String[]) {
  return noVariables(c, "fmi2GetString", n, true);
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference[], size_t n, const fmi2Integer[]) {
  return noVariables(c, "fmi2SetInteger", n, false);
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference[], size_t n, const fmi2Boolean[]) {
  return noVariables(c, "fmi2SetBoolean", n, false);
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference[], size_t n, const fmi2String[]) {
  return noVariables(c, "fmi2SetString", n, false);
}

// --- status: every step completes at once ---------------------------------------

// Status functions: after a step (every step completes at once); fmi2GetStatus
// asks about asynchronous steps, which this FMU does not make.
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind, fmi2Status* value) {
  return statusCall(c, "fmi2GetStatus", value, [&](Controller* ctl) {
    return ctl->fail("fmi2GetStatus", "no asynchronous steps: no status to ask");
  });
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real* value) {
  return statusCall(c, "fmi2GetRealStatus", value, [&](Controller* ctl) {
    if (kind != fmi2LastSuccessfulTime) return ctl->fail("fmi2GetRealStatus", "expected fmi2LastSuccessfulTime");
    *value = ctl->state.time;
    return fmi2OK;
  });
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind, fmi2Integer*) {
  return c ? static_cast<Controller*>(c)->fail("fmi2GetIntegerStatus", "no integer status") : fmi2Error;
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean* value) {
  return statusCall(c, "fmi2GetBooleanStatus", value, [&](Controller* ctl) {
    if (kind != fmi2Terminated) return ctl->fail("fmi2GetBooleanStatus", "expected fmi2Terminated");
    *value = fmi2False;
    return fmi2OK;
  });
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind, fmi2String*) {
  return c ? static_cast<Controller*>(c)->fail("fmi2GetStringStatus", "no string status") : fmi2Error;
}

}  // extern "C"
