#include "pid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>

namespace mfbd::pid {

namespace {

double derivativeSignal(const Channel& ch) { return ch.value[C] * ch.value[Setpoint] - ch.value[Measurement]; }

constexpr char kMagic[8] = {'M', 'F', 'B', 'D', 'P', 'I', 'D', '1'};
constexpr std::size_t kDoublesPerChannel = kKinds + 4;

}  // namespace

double unsaturatedCommand(const Channel& ch) {
  const double e = ch.value[Setpoint] - ch.value[Measurement];
  const double d = ch.value[Kd] * (derivativeSignal(ch) - ch.filter) / ch.value[Tf];
  return ch.value[Kp] * e + ch.integral + d;
}

double command(const Channel& ch) {
  return std::min(std::max(unsaturatedCommand(ch), ch.value[UMin]), ch.value[UMax]);
}

void initialize(Channel& ch) { ch.filter = derivativeSignal(ch); }

void step(Channel& ch, double H) {
  const double c = ch.value[C], tf = ch.value[Tf], ki = ch.value[Ki];
  const double e0 = ch.value[Setpoint] - ch.value[Measurement], e1 = ch.setpointRate - ch.measurementRate;
  const double w0 = derivativeSignal(ch), w1 = c * ch.setpointRate - ch.measurementRate;
  const double u = unsaturatedCommand(ch);
  const bool frozen = (u >= ch.value[UMax] && ki * e0 > 0) || (u <= ch.value[UMin] && ki * e0 < 0);
  if (!frozen) ch.integral += ki * (e0 * H + 0.5 * e1 * H * H);
  // x' = (w0 + w1 tau - x) / Tf: x follows the ramp w1 Tf behind it, and the
  // offset from that decays as exp(-tau / Tf).
  ch.filter = w0 + w1 * (H - tf) + (ch.filter - w0 + w1 * tf) * std::exp(-H / tf);
  ch.value[Setpoint] += ch.setpointRate * H;
  ch.value[Measurement] += ch.measurementRate * H;
  ch.setpointRate = ch.measurementRate = 0;
}

std::string refusal(const Channel& ch, Kind kind, double value) {
  if (!std::isfinite(value)) return "expected a finite number";
  if (kind == Tf && !(value > 0)) return "expected a filter time constant > 0 s";
  if (kind == UMin && value > ch.value[UMax]) return "expected u_min <= u_max of the channel";
  if (kind == UMax && value < ch.value[UMin]) return "expected u_max >= u_min of the channel";
  return "";
}

std::string serialize(const State& s) {
  std::vector<double> d{s.time};
  for (const Channel& ch : s.channels) {
    d.insert(d.end(), ch.value, ch.value + kKinds);
    d.insert(d.end(), {ch.setpointRate, ch.measurementRate, ch.integral, ch.filter});
  }
  const std::uint64_t n = s.channels.size();
  std::string bytes(kMagic, sizeof kMagic);
  bytes.append(reinterpret_cast<const char*>(&n), sizeof n);
  bytes.append(reinterpret_cast<const char*>(d.data()), d.size() * sizeof(double));
  return bytes;
}

State deserialize(const char* bytes, std::size_t size, std::size_t channels) {
  const std::size_t header = sizeof kMagic + sizeof(std::uint64_t);
  if (!bytes || size < header || std::memcmp(bytes, kMagic, sizeof kMagic) != 0)
    throw std::runtime_error("not a state of this PID controller (format MFBDPID1 expected)");
  std::uint64_t n = 0;
  std::memcpy(&n, bytes + sizeof kMagic, sizeof n);
  if (n != channels)
    throw std::runtime_error("the state has " + std::to_string(n) + " channels, this controller " +
                             std::to_string(channels));
  const std::size_t expected = header + (1 + channels * kDoublesPerChannel) * sizeof(double);
  if (size != expected)
    throw std::runtime_error("the state has " + std::to_string(size) + " bytes, expected " + std::to_string(expected));
  std::vector<double> d(1 + channels * kDoublesPerChannel);
  std::memcpy(d.data(), bytes + header, d.size() * sizeof(double));
  for (double v : d)
    if (!std::isfinite(v)) throw std::runtime_error("the state holds a number that is not finite");
  State s;
  s.time = d[0];
  s.channels.resize(channels);
  const double* p = d.data() + 1;
  for (Channel& ch : s.channels) {
    std::copy(p, p + kKinds, ch.value);
    ch.setpointRate = p[kKinds];
    ch.measurementRate = p[kKinds + 1];
    ch.integral = p[kKinds + 2];
    ch.filter = p[kKinds + 3];
    p += kDoublesPerChannel;
    for (int k = Kp; k < kKinds; ++k)
      if (!refusal(ch, Kind(k), ch.value[k]).empty()) throw std::runtime_error("the state holds a bad parameter");
  }
  return s;
}

}  // namespace mfbd::pid
