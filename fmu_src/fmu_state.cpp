// FMU state save and restore (fmi2GetFMUstate ... fmi2DeSerializeFMUstate)
// and input derivatives (fmi2SetRealInputDerivatives).
//
// A state, in memory or serialized, is one byte string (native byte order):
//   "MFBDSTAT" | format version (u32) | GUID length (u32) | GUID |
//   payload length (u64) | payload | CRC-32 (u32) of every byte before it
// (the IEEE 802.3 CRC, the same as zlib's crc32). The payload holds the
// instance's own fields (InstanceFields) and, when it has one, its
// Simulation's state (Simulation::saveState). An fmi2FMUstate is the
// address of such a string owned by the instance (states_), so a pointer
// the instance did not make is refused, never dereferenced.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "call_guard.hpp"
#include "instance.hpp"
#include "math/number_text.hpp"

namespace mfbd {

namespace {

constexpr char kMagic[8] = {'M', 'F', 'B', 'D', 'S', 'T', 'A', 'T'};
// 2: the Dormand-Prince stepper saves its redundant constraint rows; 3: the
// steppers save a substep kept past the state's time (dense output); 4:
// generalized-alpha's Newton memory holds the error Newton left and the
// local discretisation error since the last communication point; 5: the
// system saves the redundant constraint rows it leaves out (for every
// stepper, in place of the Dormand-Prince stepper's own); 6:
// generalized-alpha saves the split of its error estimate (S_c, where it
// was made, the motion range); 7: and the sum of its slow errors carried
// along the motion.
constexpr std::uint32_t kFormatVersion = 7;
constexpr std::size_t kFrameBytes = sizeof kMagic + 4 + 4 + 8 + 4;  // the header and CRC around GUID and payload

// CRC-32 (reflected polynomial 0xEDB88320, initial and final XOR all ones):
// a checksum, not a protection against deliberate changes. No zlib here:
// the FMU binaries link nothing beyond the C and C++ runtimes.
std::uint32_t crc32(const unsigned char* p, std::size_t n) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < n; ++i) c = table[(c ^ p[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

template <class T>
void append(std::vector<unsigned char>& out, T x) {
  const auto* b = reinterpret_cast<const unsigned char*>(&x);
  out.insert(out.end(), b, b + sizeof x);
}

template <class T>
T readAt(const unsigned char* p) {
  T x;
  std::memcpy(&x, p, sizeof x);
  return x;
}

std::string hex(std::uint32_t x) {
  std::ostringstream s;
  s << "0x" << std::hex << x;
  return s.str();
}

}  // namespace

// The instance's own fields in a state: one line each in visitState.
struct InstanceFields {
  unsigned mode = 0;  // FmuState
  std::vector<double> values, derivative1, derivative2, builtWith;
  bool simulationStale = true, stopTimeDefined = false, terminatedBySlave = false, hasSimulation = false;
  double startTime = 0.0, stopTime = 0.0, lastSuccessfulTime = 0.0;
  double tolerance = 0.0;  // fmi2SetupExperiment's, the Simulation's error tolerance
  template <class Archive>
  void visitState(Archive& ar) {
    ar(mode, values, derivative1, derivative2, builtWith);
    ar(simulationStale, stopTimeDefined, terminatedBySlave, hasSimulation);
    ar(startTime, stopTime, lastSuccessfulTime, tolerance);
  }
};

std::vector<unsigned char> Instance::saveState() {
  std::vector<unsigned char> out(kMagic, kMagic + sizeof kMagic);
  append(out, kFormatVersion);
  append(out, std::uint32_t(guid_.size()));
  out.insert(out.end(), guid_.begin(), guid_.end());
  const std::size_t lengthAt = out.size();
  append(out, std::uint64_t(0));
  InstanceFields f{static_cast<unsigned>(state_), values_, derivative1_, derivative2_,
                   simulation_ ? builtWith_ : std::vector<double>(), simulationStale_, stopTimeDefined_,
                   terminatedBySlave_, simulation_ != nullptr, startTime_, stopTime_, lastSuccessfulTime_, tolerance_};
  StateWriter ar(out);
  ar(f);
  if (simulation_) simulation_->saveState(ar);
  const std::uint64_t payload = out.size() - lengthAt - 8;
  std::memcpy(out.data() + lengthAt, &payload, sizeof payload);
  append(out, crc32(out.data(), out.size()));
  return out;
}

namespace {

// The payload of a state of the FMU with `guid`, or why it is not one.
bool framePayload(const unsigned char* p, std::size_t size, const std::string& guid, std::size_t& payloadAt,
                  std::size_t& payloadSize, std::string& why) {
  if (size < kFrameBytes || std::memcmp(p, kMagic, sizeof kMagic) != 0) {
    why = "it is not an MFBD-FMU state (" + std::to_string(size) + " bytes without the MFBDSTAT header)";
    return false;
  }
  const auto version = readAt<std::uint32_t>(p + 8);
  if (version != kFormatVersion) {
    why = "its format version is " + std::to_string(version) + "; this binary reads version " +
          std::to_string(kFormatVersion);
    return false;
  }
  const std::size_t guidSize = readAt<std::uint32_t>(p + 12);
  if (guidSize > size - kFrameBytes) {
    why = "it is truncated (" + std::to_string(size) + " bytes, shorter than its header)";
    return false;
  }
  payloadAt = 16 + guidSize + 8;
  const std::uint64_t announced = readAt<std::uint64_t>(p + 16 + guidSize);
  if (announced != size - kFrameBytes - guidSize) {
    why = "it is " + std::string(announced > size - kFrameBytes - guidSize ? "truncated" : "followed by extra bytes") +
          " (" + std::to_string(size) + " bytes where its header announces " +
          std::to_string(kFrameBytes + guidSize + announced) + ")";
    return false;
  }
  payloadSize = std::size_t(announced);
  const std::uint32_t stored = readAt<std::uint32_t>(p + size - 4), computed = crc32(p, size - 4);
  if (stored != computed) {
    why = "it is corrupted (CRC-32 " + hex(stored) + " stored, " + hex(computed) + " computed)";
    return false;
  }
  const std::string theirs(reinterpret_cast<const char*>(p + 16), guidSize);
  if (theirs != guid) {
    why = "it belongs to another FMU (GUID \"" + theirs + "\"; this FMU's is \"" + guid + "\")";
    return false;
  }
  return true;
}

}  // namespace

bool Instance::sameFixedParameters(const std::vector<double>& a, const std::vector<double>& b) const {
  if (a.size() != table_.size() || b.size() != table_.size()) return false;
  for (std::size_t i = 0; i < table_.size(); ++i)
    if (table_[i].variability == Variability::Fixed && a[i] != b[i]) return false;
  return true;
}

// All or nothing: the fields are read first, the Simulation's state into
// the present Simulation (its own state kept to put back on failure) or
// into a new one built with the state's fixed parameters.
fmi2Status Instance::loadState(const char* function, const std::vector<unsigned char>& bytes) {
  std::size_t at = 0, size = 0;
  std::string why;
  if (!framePayload(bytes.data(), bytes.size(), guid_, at, size, why)) return fail(function, "state refused: " + why);
  InstanceFields f;
  std::unique_ptr<Simulation> fresh;
  try {
    StateReader ar(bytes.data() + at, size);
    ar(f);
    const std::size_t n = table_.size();
    const unsigned modes = static_cast<unsigned>(FmuState::Error) - 1u;  // every state below Error
    if (f.values.size() != n || f.derivative1.size() != n || f.derivative2.size() != n ||
        (f.hasSimulation && f.builtWith.size() != n) || !(f.mode & modes) || (f.mode & (f.mode - 1u)))
      throw StateError("its instance fields do not fit this FMU");
    const double horizon = errorHorizon(f.stopTimeDefined, f.startTime, f.stopTime);
    if (f.hasSimulation && simulation_ && sameFixedParameters(builtWith_, f.builtWith) && f.tolerance == tolerance_ &&
        horizon == errorHorizon(stopTimeDefined_, startTime_, stopTime_)) {
      std::vector<unsigned char> backup;
      StateWriter keep(backup);
      simulation_->saveState(keep);
      try {
        simulation_->loadState(ar);
        if (!ar.atEnd()) throw StateError("bytes are left after its last field");
      } catch (const StateError&) {
        StateReader back(backup.data(), backup.size());
        simulation_->loadState(back);
        throw;
      }
    } else if (f.hasSimulation) {
      fresh = makeSimulation(f.builtWith, f.tolerance, horizon);
      fresh->loadState(ar);
    }
    if (!ar.atEnd()) throw StateError("bytes are left after its last field");
  } catch (const StateError& e) {
    return fail(function, std::string("state refused (nothing changed): ") + e.what());
  } catch (const SceneError& e) {
    return fail(function, std::string("state refused (nothing changed): its parameters make the scene invalid: ") +
                              e.what());
  }
  if (fresh) simulation_ = std::move(fresh);
  if (!f.hasSimulation) simulation_.reset();
  if (f.hasSimulation) builtWith_ = std::move(f.builtWith);
  tolerance_ = f.tolerance;
  state_ = static_cast<FmuState>(f.mode);
  values_ = std::move(f.values);
  derivative1_ = std::move(f.derivative1);
  derivative2_ = std::move(f.derivative2);
  simulationStale_ = f.simulationStale;
  stopTimeDefined_ = f.stopTimeDefined;
  terminatedBySlave_ = f.terminatedBySlave;
  startTime_ = f.startTime;
  stopTime_ = f.stopTime;
  lastSuccessfulTime_ = f.lastSuccessfulTime;
  return fmi2OK;
}

std::vector<unsigned char>* Instance::ownedState(fmi2FMUstate state) const {
  const auto it = states_.find(state);
  return it == states_.end() ? nullptr : it->second.get();
}

namespace {
const char* kNotOurs =
    " is not a state of this instance (one made by its fmi2GetFMUstate or fmi2DeSerializeFMUstate and not yet "
    "freed); to move a state to another instance, serialize it";
}

fmi2Status Instance::getFMUstate(fmi2FMUstate* state) {
  if (!state) return fail("fmi2GetFMUstate", "null FMUstate argument");
  std::vector<unsigned char>* reused = nullptr;
  if (*state && !(reused = ownedState(*state))) return fail("fmi2GetFMUstate", std::string("*FMUstate") + kNotOurs);
  std::vector<unsigned char> bytes = saveState();
  if (reused) {
    *reused = std::move(bytes);
    return fmi2OK;
  }
  auto owned = std::make_unique<std::vector<unsigned char>>(std::move(bytes));
  *state = owned.get();
  states_[owned.get()] = std::move(owned);
  return fmi2OK;
}

fmi2Status Instance::setFMUstate(fmi2FMUstate state) {
  if (!state) return fail("fmi2SetFMUstate", "null FMUstate");
  const std::vector<unsigned char>* bytes = ownedState(state);
  if (!bytes) return fail("fmi2SetFMUstate", std::string("FMUstate") + kNotOurs);
  return loadState("fmi2SetFMUstate", *bytes);
}

fmi2Status Instance::freeFMUstate(fmi2FMUstate* state) {
  if (!state || !*state) return fmi2OK;
  if (!ownedState(*state)) return fail("fmi2FreeFMUstate", std::string("*FMUstate") + kNotOurs);
  states_.erase(*state);
  *state = nullptr;
  return fmi2OK;
}

fmi2Status Instance::serializedFMUstateSize(fmi2FMUstate state, std::size_t* size) {
  if (!size) return fail("fmi2SerializedFMUstateSize", "null size argument");
  const std::vector<unsigned char>* bytes = ownedState(state);
  if (!bytes) return fail("fmi2SerializedFMUstateSize", std::string("FMUstate") + kNotOurs);
  *size = bytes->size();
  return fmi2OK;
}

fmi2Status Instance::serializeFMUstate(fmi2FMUstate state, fmi2Byte out[], std::size_t size) {
  const std::vector<unsigned char>* bytes = ownedState(state);
  if (!bytes) return fail("fmi2SerializeFMUstate", std::string("FMUstate") + kNotOurs);
  if (!out) return fail("fmi2SerializeFMUstate", "null serializedState argument");
  if (size < bytes->size())
    return fail("fmi2SerializeFMUstate", "a buffer of " + std::to_string(size) + " bytes; the state has " +
                                             std::to_string(bytes->size()) + " (fmi2SerializedFMUstateSize)");
  std::memcpy(out, bytes->data(), bytes->size());
  return fmi2OK;
}

fmi2Status Instance::deSerializeFMUstate(const fmi2Byte in[], std::size_t size, fmi2FMUstate* state) {
  const char* function = "fmi2DeSerializeFMUstate";
  if (!state) return fail(function, "null FMUstate argument");
  if (!in || size == 0) return fail(function, "no serialized state (null pointer or size 0)");
  std::size_t at = 0, payload = 0;
  std::string why;
  const auto* p = reinterpret_cast<const unsigned char*>(in);
  if (!framePayload(p, size, guid_, at, payload, why)) return fail(function, "state refused: " + why);
  std::vector<unsigned char>* reused = nullptr;
  if (*state && !(reused = ownedState(*state))) return fail(function, std::string("*FMUstate") + kNotOurs);
  std::vector<unsigned char> bytes(p, p + size);
  if (reused) {
    *reused = std::move(bytes);
    return fmi2OK;
  }
  auto owned = std::make_unique<std::vector<unsigned char>>(std::move(bytes));
  *state = owned.get();
  states_[owned.get()] = std::move(owned);
  return fmi2OK;
}

fmi2Status Instance::setRealInputDerivatives(const fmi2ValueReference vr[], std::size_t n, const fmi2Integer order[],
                                             const fmi2Real value[]) {
  const char* function = "fmi2SetRealInputDerivatives";
  if (n > 0 && (!vr || !order || !value)) return fail(function, "null array argument");
  std::vector<std::size_t> index(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto it = byReference_.find(vr[i]);
    if (it == byReference_.end())
      return fail(function, "no Real variable with value reference " + std::to_string(vr[i]));
    const Variable& v = table_[it->second];
    if (v.causality != Causality::Input)
      return fail(function, "'" + v.name + "' is not an input; only inputs have derivatives to set");
    if (order[i] < 1 || order[i] > InputSignals::kMaxOrder)
      return fail(function, "'" + v.name + "': derivative order " + std::to_string(order[i]) +
                                " is not supported (1 to " + std::to_string(InputSignals::kMaxOrder) + ")");
    if (!std::isfinite(value[i]))
      return fail(function, "'" + v.name + "': derivative of order " + std::to_string(order[i]) + " = " +
                                numberText(value[i]) + ": expected a finite value");
    index[i] = it->second;
  }
  for (std::size_t i = 0; i < n; ++i) {
    (order[i] == 1 ? derivative1_ : derivative2_)[index[i]] = value[i];
    if (simulation_) simulation_->writeDerivative(table_[index[i]].quantity, order[i], value[i]);
  }
  return fmi2OK;
}

}  // namespace mfbd

using namespace mfbd;

namespace {
// Every state but Error (FMI 2.0: not after an error); freeing always.
constexpr unsigned kStates = kAny & ~kError;
}  // namespace

extern "C" {

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state) {
  return guarded(c, "fmi2GetFMUstate", kStates, [&](Instance* i) { return i->getFMUstate(state); });
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
  return guarded(c, "fmi2SetFMUstate", kStates, [&](Instance* i) { return i->setFMUstate(state); });
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state) {
  return guarded(c, "fmi2FreeFMUstate", kAny, [&](Instance* i) { return i->freeFMUstate(state); });
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size) {
  return guarded(c, "fmi2SerializedFMUstateSize", kStates,
                 [&](Instance* i) { return i->serializedFMUstateSize(state, size); });
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte serializedState[], size_t size) {
  return guarded(c, "fmi2SerializeFMUstate", kStates,
                 [&](Instance* i) { return i->serializeFMUstate(state, serializedState, size); });
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate* state) {
  return guarded(c, "fmi2DeSerializeFMUstate", kStates,
                 [&](Instance* i) { return i->deSerializeFMUstate(serializedState, size, state); });
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[]) {
  return guarded(c, "fmi2SetRealInputDerivatives", kSet,
                 [&](Instance* i) { return i->setRealInputDerivatives(vr, n, order, value); });
}

}  // extern "C"
