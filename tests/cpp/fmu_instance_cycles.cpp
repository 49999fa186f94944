// Loads an FMU binary with dlopen and runs N instantiate / initialize / step /
// free cycles, for leak checking under valgrind (tests/python/test_memory.py).
// usage: fmu_instance_cycles BINARY.so RESOURCE_URI GUID CYCLES
#include "fmu_binary.hpp"

static void logger(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...) {}

int main(int argc, char** argv) {
  FmuBinary fmu;
  if (!fmu.open(argc, argv)) return 2;
  FMU_FUNCTION(fmu, fmi2DoStep);
  FMU_FUNCTION(fmu, fmi2Terminate);
  FMU_FUNCTION(fmu, fmi2FreeInstance);
  const fmi2CallbackFunctions callbacks = {logger, nullptr, nullptr, nullptr, nullptr};
  for (int i = 0; i < fmu.cycles; ++i) {
    fmi2Component c = fmu.instantiate(callbacks);
    if (!c) {
      std::fprintf(stderr, "instantiate failed in cycle %d\n", i);
      return 1;
    }
    // Every fourth cycle is freed right after instantiation, the rest after a run.
    if (i % 4 != 0) {
      if (!fmu.initialize(c) || fmi2DoStep(c, 0.0, 0.01, fmi2True) != fmi2OK || fmi2Terminate(c) != fmi2OK) {
        std::fprintf(stderr, "run failed in cycle %d\n", i);
        return 1;
      }
    }
    fmi2FreeInstance(c);
  }
  std::printf("%d cycles\n", fmu.cycles);
  return 0;
}
