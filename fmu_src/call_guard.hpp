// The call-sequence check and exception guard every fmi2* entry point of
// the plant goes through (FMI 2.0 section 4.2.4: allowed states per
// function, as masks of FmuState).
#pragma once
#include "fmi2Functions.h"
#include "entry_point.hpp"
#include "instance.hpp"

namespace mfbd {

inline constexpr unsigned bit(FmuState s) { return static_cast<unsigned>(s); }
inline constexpr unsigned kInstantiated = bit(FmuState::Instantiated);
inline constexpr unsigned kInit = bit(FmuState::InitializationMode);
inline constexpr unsigned kStepComplete = bit(FmuState::StepComplete);
inline constexpr unsigned kStepFailed = bit(FmuState::StepFailed);
inline constexpr unsigned kTerminated = bit(FmuState::Terminated);
inline constexpr unsigned kError = bit(FmuState::Error);
inline constexpr unsigned kAny = kInstantiated | kInit | kStepComplete | kStepFailed | kTerminated | kError;
inline constexpr unsigned kGet = kInit | kStepComplete | kStepFailed | kTerminated | kError;
inline constexpr unsigned kSet = kInstantiated | kInit | kStepComplete;
inline constexpr unsigned kStatus = kStepComplete | kStepFailed | kTerminated;

// Runs `body` on a checked instance; maps exceptions to fmi2Error.
template <class Body>
fmi2Status guarded(fmi2Component c, const char* function, unsigned mask, Body body) {
  return guardedCall<Instance>(c, function, mask, body);
}

}  // namespace mfbd
