// What the fmi2* entry points of this project's two FMUs (the plant,
// fmu_src/; the PID controller, controller/: a binary of its own) share:
// messages as the logger's format, fmi2Instantiate's argument checks, and
// for the other functions the call-sequence check (FMI 2.0 section 4.2.4)
// with no exception crossing the C boundary. Header only, so each binary
// compiles its own copy.
#pragma once
#include <exception>
#include <new>
#include <string>

#include "fmi2Functions.h"

namespace mfbd {

// A message as the logger's printf format ('%' doubled): importers that
// format print it as it is, and those that do not still read it.
inline std::string loggerFormat(const std::string& message) {
  std::string escaped;
  for (char c : message) escaped += c == '%' ? std::string("%%") : std::string(1, c);
  return escaped;
}

// The arguments of fmi2Instantiate that no FMU here accepts: what is
// wrong, or nullptr.
inline const char* instantiateArgumentError(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                            fmi2String fmuResourceLocation) {
  if (!instanceName || !*instanceName) return "instanceName must be a non-empty string";
  if (fmuType != fmi2CoSimulation) return "this FMU supports Co-Simulation only (fmuType must be fmi2CoSimulation)";
  if (!fmuGUID || !fmuResourceLocation) return "fmuGUID and fmuResourceLocation must not be null";
  return nullptr;
}

// A refused fmi2Instantiate, logged through the master's callbacks (there is
// no instance to log through).
inline void reportInstantiateError(const fmi2CallbackFunctions* functions, fmi2String instanceName,
                                   const char* message) {
  if (functions && functions->logger)
    functions->logger(functions->componentEnvironment, instanceName ? instanceName : "", fmi2Error,
                      "logStatusError", loggerFormat(std::string("fmi2Instantiate: ") + message).c_str());
}

// Runs `body` on the component when its state allows `function` (`mask`:
// the states that do); maps exceptions to fmi2Error. Component has
// allow(function, mask) (false: refused, logged) and fail(function, why).
template <class Component, class Body>
fmi2Status guardedCall(fmi2Component c, const char* function, unsigned mask, Body body) {
  if (!c) return fmi2Error;
  Component* component = static_cast<Component*>(c);
  if (!component->allow(function, mask)) return fmi2Error;
  try {
    return body(component);
  } catch (const std::bad_alloc&) {
    return component->fail(function, "out of memory");
  } catch (const std::exception& e) {
    return component->fail(function, std::string("internal error: ") + e.what());
  }
}

}  // namespace mfbd
