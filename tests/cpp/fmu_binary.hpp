// What the leak-check drivers (fmu_instance_cycles.cpp, fmu_state_cycles.cpp)
// share: their command line BINARY.so RESOURCE_URI GUID CYCLES, the FMU
// binary opened with dlopen, its functions looked up by name, and an
// instance brought through initialization at t = 0.
#pragma once
#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>

#include "fmi2Functions.h"

class FmuBinary {
 public:
  // Opens the binary argv[1]; false (with a message) on a wrong command
  // line or a failed dlopen.
  bool open(int argc, char** argv) {
    if (argc != 5) {
      std::fprintf(stderr, "usage: %s BINARY.so RESOURCE_URI GUID CYCLES\n", argv[0]);
      return false;
    }
    library_ = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!library_) {
      std::fprintf(stderr, "dlopen: %s\n", dlerror());
      return false;
    }
    resourceUri_ = argv[2];
    guid_ = argv[3];
    cycles = std::atoi(argv[4]);
    instantiate_ = function<fmi2InstantiateTYPE>("fmi2Instantiate");
    setupExperiment_ = function<fmi2SetupExperimentTYPE>("fmi2SetupExperiment");
    enterInitialization_ = function<fmi2EnterInitializationModeTYPE>("fmi2EnterInitializationMode");
    exitInitialization_ = function<fmi2ExitInitializationModeTYPE>("fmi2ExitInitializationMode");
    return true;
  }
  ~FmuBinary() {
    if (library_) dlclose(library_);
  }

  template <class Type>
  Type* function(const char* name) const {
    return reinterpret_cast<Type*>(dlsym(library_, name));
  }

  // A new instance of the FMU (null if fmi2Instantiate refused).
  fmi2Component instantiate(const fmi2CallbackFunctions& callbacks) const {
    return instantiate_("cycle", fmi2CoSimulation, guid_, resourceUri_, &callbacks, fmi2False, fmi2False);
  }
  // Setup, enter and exit initialization mode at t = 0.
  bool initialize(fmi2Component c) const {
    return setupExperiment_(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK &&
           enterInitialization_(c) == fmi2OK && exitInitialization_(c) == fmi2OK;
  }

  int cycles = 0;

 private:
  void* library_ = nullptr;
  const char* resourceUri_ = nullptr;
  const char* guid_ = nullptr;
  fmi2InstantiateTYPE* instantiate_ = nullptr;
  fmi2SetupExperimentTYPE* setupExperiment_ = nullptr;
  fmi2EnterInitializationModeTYPE* enterInitialization_ = nullptr;
  fmi2ExitInitializationModeTYPE* exitInitialization_ = nullptr;
};

// `auto fmi2DoStep = ...` from the binary, by its standard name and type.
#define FMU_FUNCTION(binary, name) auto name = (binary).function<name##TYPE>(#name)
