// The FMI 2.0 Co-Simulation functions: thin wrappers over Instance. Each one
// checks the call sequence (allowed states per the standard's table, FMI 2.0
// section 4.2.4), and no exception ever crosses the C boundary.
#include <cstring>
#include <exception>

#include "fmi2Functions.h"
#include "call_guard.hpp"
#include "instance.hpp"

using mfbd::FmuState;
using mfbd::Instance;

using namespace mfbd;  // masks and guarded (call_guard.hpp)

extern "C" {

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions,
                              fmi2Boolean /*visible*/, fmi2Boolean loggingOn) {
  if (const char* why = instantiateArgumentError(instanceName, fmuType, fmuGUID, fmuResourceLocation)) {
    reportInstantiateError(functions, instanceName, why);
    return nullptr;
  }
  try {
    return Instance::create(instanceName, fmuGUID, fmuResourceLocation, functions, loggingOn);
  } catch (const std::exception& e) {
    reportInstantiateError(functions, instanceName, e.what());
    return nullptr;
  }
}

void fmi2FreeInstance(fmi2Component c) { delete static_cast<Instance*>(c); }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t n, const fmi2String categories[]) {
  return guarded(c, "fmi2SetDebugLogging", kAny,
                 [&](Instance* i) { return i->setDebugLogging(loggingOn, n, categories); });
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
  return guarded(c, "fmi2SetupExperiment", kInstantiated, [&](Instance* i) {
    return i->setupExperiment(toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime);
  });
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
  return guarded(c, "fmi2EnterInitializationMode", kInstantiated,
                 [](Instance* i) { return i->enterInitializationMode(); });
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
  return guarded(c, "fmi2ExitInitializationMode", kInit, [](Instance* i) { return i->exitInitializationMode(); });
}

fmi2Status fmi2Terminate(fmi2Component c) {
  return guarded(c, "fmi2Terminate", kStepComplete | kStepFailed, [](Instance* i) { return i->terminate(); });
}

fmi2Status fmi2Reset(fmi2Component c) {
  return guarded(c, "fmi2Reset", kAny, [](Instance* i) { return i->reset(); });
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[]) {
  return guarded(c, "fmi2GetReal", kGet, [&](Instance* i) { return i->getReal(vr, n, value); });
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer[]) {
  return guarded(c, "fmi2GetInteger", kGet,
                 [&](Instance* i) { return i->noVariablesOfType("fmi2GetInteger", "Integer", n, vr); });
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean[]) {
  return guarded(c, "fmi2GetBoolean", kGet,
                 [&](Instance* i) { return i->noVariablesOfType("fmi2GetBoolean", "Boolean", n, vr); });
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String[]) {
  return guarded(c, "fmi2GetString", kGet,
                 [&](Instance* i) { return i->noVariablesOfType("fmi2GetString", "String", n, vr); });
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[]) {
  return guarded(c, "fmi2SetReal", kSet, [&](Instance* i) { return i->setReal(vr, n, value); });
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer[]) {
  return guarded(c, "fmi2SetInteger", kSet,
                 [&](Instance* i) { return i->noVariablesOfType("fmi2SetInteger", "Integer", n, vr); });
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean[]) {
  return guarded(c, "fmi2SetBoolean", kSet,
                 [&](Instance* i) { return i->noVariablesOfType("fmi2SetBoolean", "Boolean", n, vr); });
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String[]) {
  return guarded(c, "fmi2SetString", kSet,
                 [&](Instance* i) { return i->noVariablesOfType("fmi2SetString", "String", n, vr); });
}

// FMU state (fmi2GetFMUstate ... fmi2DeSerializeFMUstate) and
// fmi2SetRealInputDerivatives: fmu_state.cpp.

// Output and directional derivatives: Instance (derivatives.cpp).
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown[], size_t nUnknown,
                                        const fmi2ValueReference vKnown[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
  return guarded(c, "fmi2GetDirectionalDerivative", kGet, [&](Instance* i) {
    return i->getDirectionalDerivative(vUnknown, nUnknown, vKnown, nKnown, dvKnown, dvUnknown);
  });
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[]) {
  return guarded(c, "fmi2GetRealOutputDerivatives", kStepComplete | kStepFailed | kTerminated | kError,
                 [&](Instance* i) { return i->getRealOutputDerivatives(vr, n, order, value); });
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean /*noSetFMUStatePriorToCurrentPoint*/) {
  return guarded(c, "fmi2DoStep", kStepComplete,
                 [&](Instance* i) { return i->doStep(currentCommunicationPoint, communicationStepSize); });
}

fmi2Status fmi2CancelStep(fmi2Component c) {
  return guarded(c, "fmi2CancelStep", kAny, [](Instance* i) {
    return i->unsupported("fmi2CancelStep", "steps are synchronous; there is nothing to cancel");
  });
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind, fmi2Status*) {
  return guarded(c, "fmi2GetStatus", kStatus, [](Instance* i) {
    return i->unsupported("fmi2GetStatus", "steps are synchronous; no fmi2Status kind is available");
  });
}

// A C master may pass any int as the kind: read it as one (loading an
// out-of-range value as the C++ enum is undefined).
int kindOf(const fmi2StatusKind& s) {
  int kind;
  std::memcpy(&kind, &s, sizeof kind);
  return kind;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
  return guarded(c, "fmi2GetRealStatus", kStatus, [&](Instance* i) { return i->getRealStatus(kindOf(s), value); });
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind, fmi2Integer*) {
  return guarded(c, "fmi2GetIntegerStatus", kStatus, [](Instance* i) {
    return i->unsupported("fmi2GetIntegerStatus", "no Integer status kind is available");
  });
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
  return guarded(c, "fmi2GetBooleanStatus", kStatus, [&](Instance* i) { return i->getBooleanStatus(kindOf(s), value); });
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind, fmi2String*) {
  return guarded(c, "fmi2GetStringStatus", kStatus, [](Instance* i) {
    return i->unsupported("fmi2GetStringStatus", "no String status kind is available (steps are synchronous)");
  });
}

}  // extern "C"
