// Loads an FMU binary with dlopen, initializes one instance and runs N
// cycles of fmi2GetFMUstate / fmi2SetFMUstate / fmi2FreeFMUstate, each with
// a serialize / deserialize round trip, and a step every 100 cycles, for
// leak checking under valgrind (tests/python/test_fmu_state.py).
// usage: fmu_state_cycles BINARY.so RESOURCE_URI GUID CYCLES
#include <vector>

#include "fmu_binary.hpp"

static void logger(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String message, ...) {
  std::fprintf(stderr, "%s\n", message);
}

int main(int argc, char** argv) {
  FmuBinary fmu;
  if (!fmu.open(argc, argv)) return 2;
  FMU_FUNCTION(fmu, fmi2DoStep);
  FMU_FUNCTION(fmu, fmi2GetFMUstate);
  FMU_FUNCTION(fmu, fmi2SetFMUstate);
  FMU_FUNCTION(fmu, fmi2FreeFMUstate);
  FMU_FUNCTION(fmu, fmi2SerializedFMUstateSize);
  FMU_FUNCTION(fmu, fmi2SerializeFMUstate);
  FMU_FUNCTION(fmu, fmi2DeSerializeFMUstate);
  FMU_FUNCTION(fmu, fmi2FreeInstance);
  const fmi2CallbackFunctions callbacks = {logger, nullptr, nullptr, nullptr, nullptr};
  const int cycles = fmu.cycles;
  fmi2Component c = fmu.instantiate(callbacks);
  if (!c || !fmu.initialize(c)) {
    std::fprintf(stderr, "initialization failed\n");
    return 1;
  }
  const double H = 0.001;
  double t = 0.0;
  std::vector<fmi2Byte> bytes;
  for (int i = 0; i < cycles; ++i) {
    fmi2FMUstate state = nullptr, copy = nullptr;
    std::size_t size = 0;
    bool ok = fmi2GetFMUstate(c, &state) == fmi2OK && fmi2SerializedFMUstateSize(c, state, &size) == fmi2OK;
    bytes.resize(size);
    ok = ok && fmi2SerializeFMUstate(c, state, bytes.data(), size) == fmi2OK &&
         fmi2DeSerializeFMUstate(c, bytes.data(), size, &copy) == fmi2OK;
    if (ok && i % 100 == 0) {  // a step, then back to the state before it
      ok = fmi2DoStep(c, t, H, fmi2False) == fmi2OK;
      ok = ok && fmi2SetFMUstate(c, i % 200 == 0 ? state : copy) == fmi2OK;
      ok = ok && fmi2DoStep(c, t, H, fmi2False) == fmi2OK;
      t += H;
    } else {
      ok = ok && fmi2SetFMUstate(c, state) == fmi2OK;
    }
    ok = ok && fmi2FreeFMUstate(c, &state) == fmi2OK && fmi2FreeFMUstate(c, &copy) == fmi2OK && !state && !copy;
    if (!ok) {
      std::fprintf(stderr, "cycle %d failed\n", i);
      return 1;
    }
  }
  // States left unfreed are the instance's to free with it.
  fmi2FMUstate left = nullptr;
  if (fmi2GetFMUstate(c, &left) != fmi2OK) return 1;
  fmi2FreeInstance(c);
  std::printf("%d cycles\n", cycles);
  return 0;
}
