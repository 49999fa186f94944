// A multi-channel PID controller as a continuous-time law and its exact step
// for inputs held or ramped over a communication step. No FMI here.
//
// Per channel, with error e = r - y and derivative signal w = c r - y:
//   u     = clamp(Kp e + I + D, u_min, u_max)          (the command)
//   D     = Kd (w - x) / Tf,   x' = (w - x) / Tf        (derivative through a first-order filter)
//   I'    = Ki e, frozen while u is at a limit and Ki e pushes it further (clamping anti-windup)
// Over a step of length H the inputs are r + r' tau, y + y' tau (r', y' from
// fmi2SetRealInputDerivatives, else zero: a zero-order hold). The filter state
// and the integral are advanced by their exact solutions for those inputs;
// whether the integral is frozen is decided once, at the step start. So the
// step is exact for the continuous PID while the command stays off its limits,
// and converges to it as H -> 0 (at first order in the time a limit is hit).
#pragma once
#include <cstddef>
#include <string>
#include <vector>

namespace mfbd::pid {

// The variables of one channel, in the order of their value-reference blocks
// (value reference = kind * channels + channel index).
enum Kind : int { Setpoint, Measurement, Command, Kp, Ki, Kd, Tf, C, UMin, UMax, kKinds };

// Variable names, by kind; channel k (0-based) of kind K is "<name>[k+1]".
inline const char* const kKindNames[kKinds] = {"setpoint", "measurement", "command", "Kp", "Ki",
                                               "Kd",       "Tf",          "c",       "u_min", "u_max"};

struct Channel {
  double value[kKinds] = {0, 0, 0, 1, 0, 0, 0.01, 0, -1e20, 1e20};  // Command unused: computed
  double setpointRate = 0, measurementRate = 0;  // input derivatives for the next step
  double integral = 0, filter = 0;               // I and x
};

// Everything the next result depends on: the FMU state saved and restored as a whole.
struct State {
  double time = 0;
  std::vector<Channel> channels;
};

double unsaturatedCommand(const Channel& ch);
double command(const Channel& ch);
// Starts the derivative filter at rest on the present inputs (no kick at t0).
void initialize(Channel& ch);
// Advances one channel over [t, t + H]; the inputs end at their ramp's end value
// and the input derivatives are used up (zero again).
void step(Channel& ch, double H);

// Why a parameter value is refused ("" if it is accepted), given the channel
// the value would go into.
std::string refusal(const Channel& ch, Kind kind, double value);

// FMU state as bytes: a header naming the format and the channel count, then the doubles.
std::string serialize(const State& s);
// Throws std::runtime_error naming what is wrong (format, channel count, length).
State deserialize(const char* bytes, std::size_t size, std::size_t channels);

}  // namespace mfbd::pid
