// One FMU instance: the FMI 2.0 Co-Simulation state machine (checked in one
// place, `allow`), the variable table, start values, and the Simulation.
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "fmi2Functions.h"
#include "variable_table.hpp"

namespace mfbd {

enum class FmuState : unsigned {
  Instantiated = 1u << 0,
  InitializationMode = 1u << 1,
  StepComplete = 1u << 2,
  StepFailed = 1u << 3,
  Terminated = 1u << 4,
  Error = 1u << 5,
};

class Instance {
 public:
  // Largest solver.max_substeps accepted: beyond it the bound bounds nothing.
  static constexpr double kMaxSubstepsLimit = 1e9;

  // Returns nullptr (after logging why) when the scene or GUID is bad.
  static Instance* create(const std::string& name, const std::string& guid, const std::string& resourceUri,
                          const fmi2CallbackFunctions* callbacks, bool loggingOn);

  // Call-sequence check: logs and returns false if `function` may not be
  // called in the current state. Masks are FmuState bits.
  bool allow(const char* function, unsigned mask);

  fmi2Status setDebugLogging(bool on, std::size_t n, const fmi2String categories[]);
  fmi2Status setupExperiment(bool toleranceDefined, double tolerance, double startTime, bool stopTimeDefined,
                             double stopTime);
  fmi2Status enterInitializationMode();
  fmi2Status exitInitializationMode();
  fmi2Status terminate();
  fmi2Status reset();
  fmi2Status getReal(const fmi2ValueReference vr[], std::size_t n, fmi2Real value[]);
  fmi2Status setReal(const fmi2ValueReference vr[], std::size_t n, const fmi2Real value[]);
  // Integer/Boolean/String: the scene has none of these; any reference is unknown.
  fmi2Status noVariablesOfType(const char* function, const char* type, std::size_t n, const fmi2ValueReference vr[]);
  fmi2Status doStep(double currentCommunicationPoint, double communicationStepSize);
  fmi2Status getRealStatus(int kind, fmi2Real* value);
  fmi2Status getBooleanStatus(int kind, fmi2Boolean* value);
  fmi2Status unsupported(const char* function, const char* why);
  // fmi2GetRealOutputDerivatives and fmi2GetDirectionalDerivative (derivatives.cpp).
  fmi2Status getRealOutputDerivatives(const fmi2ValueReference vr[], std::size_t n, const fmi2Integer order[],
                                      fmi2Real value[]);
  fmi2Status getDirectionalDerivative(const fmi2ValueReference unknown[], std::size_t nUnknown,
                                      const fmi2ValueReference known[], std::size_t nKnown, const fmi2Real dvKnown[],
                                      fmi2Real dvUnknown[]);

  // FMU state and input derivatives (fmu_state.cpp). A state is the bytes
  // of a serialized state (header, payload, CRC-32), owned by this
  // instance until freed.
  fmi2Status getFMUstate(fmi2FMUstate* state);
  fmi2Status setFMUstate(fmi2FMUstate state);
  fmi2Status freeFMUstate(fmi2FMUstate* state);
  fmi2Status serializedFMUstateSize(fmi2FMUstate state, std::size_t* size);
  fmi2Status serializeFMUstate(fmi2FMUstate state, fmi2Byte bytes[], std::size_t size);
  fmi2Status deSerializeFMUstate(const fmi2Byte bytes[], std::size_t size, fmi2FMUstate* state);
  fmi2Status setRealInputDerivatives(const fmi2ValueReference vr[], std::size_t n, const fmi2Integer order[],
                                     const fmi2Real value[]);

  void log(fmi2Status status, const char* category, const std::string& message) const;
  // Whether a message of this status and category reaches the logger (so
  // that per-step messages are composed only when they will be read).
  bool logs(fmi2Status status, const char* category) const;
  fmi2Status fail(const char* function, const std::string& message);  // logs, returns fmi2Error

 private:
  Instance() = default;
  bool buildSimulation(const char* function);
  // A Simulation of the scene with the fixed parameters of `values` (by
  // table index), not yet initialized. Throws SceneError.
  std::unique_ptr<Simulation> makeSimulation(const std::vector<double>& values, double tolerance,
                                             double horizon) const;
  // The duration the error tolerance holds over: stopTime - startTime when
  // fmi2SetupExperiment defined it, else 0 (the scene's experiment).
  static double errorHorizon(bool stopTimeDefined, double startTime, double stopTime) {
    return stopTimeDefined ? stopTime - startTime : 0.0;
  }
  // State bytes of the present instance, and their restore (all or nothing).
  std::vector<unsigned char> saveState();
  fmi2Status loadState(const char* function, const std::vector<unsigned char>& bytes);
  std::vector<unsigned char>* ownedState(fmi2FMUstate state) const;
  bool sameFixedParameters(const std::vector<double>& a, const std::vector<double>& b) const;
  // One value of a parameter or input on its own (user parameters: checkScene).
  bool checkValue(const Variable& v, double value, std::string& why) const;
  // The scene stays valid with these user parameter values.
  // The user parameters' present values, by name (what parseScene takes).
  std::map<std::string, double> userParameterValues() const;
  bool checkScene(const std::map<std::string, double>& userValues, std::string& why) const;
  double timeRoundOff(double t, double now) const;
  // The variables of references of one causality, checked (derivatives.cpp).
  bool variablesOf(const char* function, const fmi2ValueReference vr[], std::size_t n, Causality causality,
                   std::vector<Quantity>& quantities);
  double currentTime() const;
  // Substeps, Newton iterations, factorizations and rejected substeps so far.
  std::string solverStatistics() const;

  std::string name_;
  fmi2CallbackFunctions callbacks_{};
  bool loggingOn_ = false;
  std::set<std::string, std::less<>> categories_;  // transparent: looked up by const char*
  FmuState state_ = FmuState::Instantiated;

  std::string sceneText_;
  Scene scene_;  // parsed with the default parameter values
  std::vector<Variable> table_;
  std::unordered_map<fmi2ValueReference, std::size_t> byReference_;
  std::vector<double> values_;  // parameters and inputs, by table index
  // Inputs' first and second derivatives (fmi2SetRealInputDerivatives), by table index.
  std::vector<double> derivative1_, derivative2_;
  std::vector<double> builtWith_;  // values_ when simulation_ was built (its fixed parameters)
  std::string guid_;
  std::map<const void*, std::unique_ptr<std::vector<unsigned char>>> states_;  // fmi2GetFMUstate's

  std::unique_ptr<Simulation> simulation_;
  bool simulationStale_ = true;  // a fixed parameter changed since it was built
  double startTime_ = 0.0;
  bool stopTimeDefined_ = false;
  double stopTime_ = 0.0;
  double tolerance_ = 0.0;  // fmi2SetupExperiment's relative tolerance; 0: not defined
  double lastSuccessfulTime_ = 0.0;
  bool terminatedBySlave_ = false;
};

}  // namespace mfbd
