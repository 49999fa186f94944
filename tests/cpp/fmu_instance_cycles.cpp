// Loads an FMU binary with dlopen and runs N instantiate / initialize / step /
// free cycles, for leak checking under valgrind (tests/python/test_memory.py).
// usage: fmu_instance_cycles BINARY.so RESOURCE_URI GUID CYCLES
#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...) {}

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s BINARY.so RESOURCE_URI GUID CYCLES\n", argv[0]);
    return 2;
  }
  void* lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
  if (!lib) {
    std::fprintf(stderr, "dlopen: %s\n", dlerror());
    return 2;
  }
#define LOAD(name) auto name = reinterpret_cast<name##TYPE*>(dlsym(lib, #name))
  LOAD(fmi2Instantiate);
  LOAD(fmi2SetupExperiment);
  LOAD(fmi2EnterInitializationMode);
  LOAD(fmi2ExitInitializationMode);
  LOAD(fmi2DoStep);
  LOAD(fmi2Terminate);
  LOAD(fmi2FreeInstance);
#undef LOAD
  const fmi2CallbackFunctions callbacks = {logger, nullptr, nullptr, nullptr, nullptr};
  const int cycles = std::atoi(argv[4]);
  for (int i = 0; i < cycles; ++i) {
    fmi2Component c = fmi2Instantiate("cycle", fmi2CoSimulation, argv[3], argv[2], &callbacks, fmi2False, fmi2False);
    if (!c) {
      std::fprintf(stderr, "instantiate failed in cycle %d\n", i);
      return 1;
    }
    // Every fourth cycle is freed right after instantiation, the rest after a run.
    if (i % 4 != 0) {
      if (fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
          fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK ||
          fmi2DoStep(c, 0.0, 0.01, fmi2True) != fmi2OK || fmi2Terminate(c) != fmi2OK) {
        std::fprintf(stderr, "run failed in cycle %d\n", i);
        return 1;
      }
    }
    fmi2FreeInstance(c);
  }
  dlclose(lib);
  std::printf("%d cycles\n", cycles);
  return 0;
}
