// Derivatives the FMI layer offers a master: time derivatives of outputs
// (fmi2GetRealOutputDerivatives) and partial derivatives of outputs with
// respect to inputs (fmi2GetDirectionalDerivative), both at the present
// state and without touching the integrator's history.
#include <cmath>
#include <limits>

#include "rigid/force_elements.hpp"
#include "simulation.hpp"

namespace mfbd {

namespace {

// Puts a state into the Simulation for the duration of a scope and takes
// it back (also when a read throws), so the outputs of the present state
// are evaluated again at the next read.
class StateSwap {
 public:
  StateSwap(IntegratorState& held, IntegratorState& other, bool& outputsCurrent)
      : held_(held), other_(other), outputsCurrent_(outputsCurrent) {
    std::swap(held_, other_);
    outputsCurrent_ = false;
  }
  ~StateSwap() {
    std::swap(held_, other_);
    outputsCurrent_ = false;
  }

 private:
  IntegratorState &held_, &other_;
  bool& outputsCurrent_;
};

Quat rateOf(const Quat& q, const Vec3& omegaWorld) { return Quat(0.0, omegaWorld.x(), omegaWorld.y(), omegaWorld.z()) * q; }

double component(const Quat& q, int c) {
  const double wxyz[4] = {q.w(), q.x(), q.y(), q.z()};
  return wxyz[c];
}

}  // namespace

bool Simulation::consistentAccelerations(IntegratorState& s) {
  std::string message;
  if (stepper_->initialize(system_, s, message)) return true;
  s.vdot.setConstant(std::numeric_limits<double>::quiet_NaN());
  return false;
}

// The state at time x.t + eps along the motion through x, from its
// velocities and accelerations (and the jerk, when given): q o exp(eps v +
// eps^2/2 vdot), v + eps vdot (+ eps^2/2 jerk), with consistent
// accelerations there. The terms left out are odd in eps or of higher
// order, so central differences over +-eps keep their O(eps^2) error.
IntegratorState Simulation::alongMotion(const IntegratorState& x, double eps, const VectorXd* jerk) {
  IntegratorState s = x;
  s.t = x.t + eps;
  system_.retract(s.q, eps * x.v + 0.5 * eps * eps * x.vdot);
  s.v = x.v + eps * x.vdot;
  if (jerk) s.v += 0.5 * eps * eps * *jerk;
  consistentAccelerations(s);
  return s;
}

// Outputs (order 0) or their exact derivatives of that order at state s,
// the inputs as they are.
std::vector<double> Simulation::valuesAt(IntegratorState& s, const std::vector<Quantity>& outputs, int order) {
  StateSwap swap(state_, s, outputsCurrent_);
  std::vector<double> y;
  for (const Quantity& q : outputs) y.push_back(order == 0 ? read(q) : exactDerivative(q, order));
  return y;
}

// The highest order of derivative that the state and its accelerations give
// exactly: 2 for positions and orientations, 1 for rates, rotation-vector
// coordinates and spring lengths, 0 for the rest (forces, energies).
int Simulation::exactDerivativeOrder(const Quantity& q) const {
  switch (q.kind) {
    case QuantityKind::JointCoordinate: {
      const Joint& j = system_.model().joints[jointIndex_[q.index]];
      return q.component < (j.rotation >= 0 ? j.dofs - 3 : j.dofs) ? 2 : 1;
    }
    case QuantityKind::BodyPosition:
    case QuantityKind::BodyOrientation:
    case QuantityKind::NodePosition:
    case QuantityKind::NodeOrientation: return 2;
    case QuantityKind::JointRate:
    case QuantityKind::BodyVelocity:
    case QuantityKind::BodyAngularVelocity:
    case QuantityKind::NodeVelocity:
    case QuantityKind::NodeAngularVelocity: return 1;
    case QuantityKind::SpringLength: return q.component == 0 ? 1 : 0;
    default: return 0;
  }
}

// Second derivatives of positions and orientations: the rates of their
// velocities; a quaternion's is 1/2 (0, alpha) q + 1/2 (0, omega) qdot.
double Simulation::exactDerivative(const Quantity& q, int order) {
  if (order == 1) return rateFromState(q);
  switch (q.kind) {
    case QuantityKind::JointCoordinate: return rateFromState({QuantityKind::JointRate, q.index, q.component});
    case QuantityKind::BodyPosition: return rateFromState({QuantityKind::BodyVelocity, q.index, q.component});
    case QuantityKind::NodePosition: return rateFromState({QuantityKind::NodeVelocity, q.index, q.component});
    default: break;
  }
  evaluateOutputs(false);
  Quat o;
  Vec3 omega, alpha;
  if (q.kind == QuantityKind::NodeOrientation) {
    const NodeState& n = system_.nodes()[q.index];
    o = outputQuaternion(bodyIndex_.size() + q.index, n.pose.A);
    omega = n.pose.A * n.velocity.omega;
    alpha = n.pose.A * n.acceleration.omegaDot;
  } else {
    const BodyKinematics& k = system_.data().body[bodyIndex_[q.index]];
    o = outputQuaternion(q.index, k.orientation);
    omega = k.angularVelocity;
    alpha = k.angularAcceleration;
  }
  const Quat rate = rateOf(o, 0.5 * omega);
  return component(rateOf(o, 0.5 * alpha), q.component) + component(rateOf(rate, 0.5 * omega), q.component);
}

// The quaternion an orientation output gives for A: the sign of the one
// last output (tracked), else w >= 0.
Quat Simulation::outputQuaternion(std::size_t i, const Mat3& A) const {
  Quat o(A);
  const double reference = orientationTracked_[i] ? o.coeffs().dot(orientation_[i].coeffs()) : o.w();
  if (reference < 0.0) o.coeffs() *= -1.0;
  return o;
}

// d/dt of a kinematic output from the state and its accelerations (state_.vdot,
// consistent): a coordinate's rate (a rotation vector's through the inverse
// tangent of the exponential map), a rate's acceleration, a position's
// velocity, a quaternion's rate (1/2 (0, omega) q, omega in the world frame).
double Simulation::rateFromState(const Quantity& q) {
  evaluateOutputs(false);
  const Model& model = system_.model();
  const Data& data = system_.data();
  if (q.kind == QuantityKind::JointCoordinate || q.kind == QuantityKind::JointRate) {
    const Joint& j = model.joints[jointIndex_[q.index]];
    if (q.kind == QuantityKind::JointRate) return state_.vdot[j.velocityOffset + q.component];
    const int scalars = j.rotation >= 0 ? j.dofs - 3 : j.dofs;
    if (q.component < scalars) return state_.v[j.velocityOffset + q.component];
    const Vec3 theta = logSO3(state_.q.rotations[j.rotation]);
    const Vec3 omega = state_.v.segment<3>(j.velocityOffset + scalars);
    return (tangentSO3Inverse(theta) * omega)[q.component - scalars];
  }
  if (q.kind == QuantityKind::SpringLength) return springState(model.forces[q.index], system_.forceInputs(), data).rate;
  if (q.kind >= QuantityKind::NodePosition) {
    const NodeState& n = system_.nodes()[q.index];
    switch (q.kind) {
      case QuantityKind::NodePosition: return n.velocity.v[q.component];
      case QuantityKind::NodeVelocity: return n.acceleration.a[q.component];
      case QuantityKind::NodeAngularVelocity: return (n.pose.A * n.acceleration.omegaDot)[q.component];
      default: {
        const Quat o = outputQuaternion(bodyIndex_.size() + q.index, n.pose.A);
        return 0.5 * component(rateOf(o, n.pose.A * n.velocity.omega), q.component);
      }
    }
  }
  const int b = bodyIndex_[q.index];
  const BodyKinematics& k = data.body[b];
  const Vec3 c = k.orientation * model.bodies[b].centerOfMass;  // frame origin -> centre of mass
  const Vec3& w = k.angularVelocity;
  switch (q.kind) {
    case QuantityKind::BodyPosition: return (k.velocity - w.cross(c))[q.component];
    case QuantityKind::BodyVelocity:
      return (k.acceleration - k.angularAcceleration.cross(c) - w.cross(w.cross(c)))[q.component];
    case QuantityKind::BodyAngularVelocity: return k.angularAcceleration[q.component];
    default: return 0.5 * component(rateOf(outputQuaternion(q.index, k.orientation), w), q.component);
  }
}

// Positions and orientations (to order 2), rates and rotation-vector
// coordinates (order 1) exactly from the state and its consistent
// accelerations. The rest by central differences along the motion: order 1
// of forces (reactions, drive forces, tensions, section forces, energies)
// over +-eps1, O(eps1^2); order 2 of rates as the difference of their exact
// rates over +-eps2, of forces as a second difference over +-eps2 along the
// motion continued with the jerk (the difference of the consistent
// accelerations), both O(eps2^2). eps1 is 1e-2 h_max, the time the user
// resolves the motion in, eps2 1e-1 h_max; for the second difference at
// least 1e-4 s: the consistent solves carry round-off of ~1e-12 of the
// forces, which it divides by eps2^2 (slider_crank: 40 N/s^2 of 4920 at
// eps2 = 1e-5 s). Inputs follow their signals (System::inputsAt): held, or
// along the derivatives fmi2SetRealInputDerivatives gave.
std::vector<double> Simulation::outputDerivatives(const std::vector<Quantity>& outputs, const std::vector<int>& orders) {
  // 0: difference of order 1; 1: difference of exact rates, order 2; 2: second
  // difference; 3, 4: exact of order 1, 2
  std::vector<Quantity> groups[5];
  std::vector<std::pair<int, std::size_t>> place;  // group and index in it, per output
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const int exact = exactDerivativeOrder(outputs[i]);
    const int g = orders[i] <= exact ? 2 + orders[i] : orders[i] == 1 ? 0 : exact == 1 ? 1 : 2;
    place.emplace_back(g, groups[g].size());
    groups[g].push_back(outputs[i]);
  }
  IntegratorState x0 = state_;
  consistentAccelerations(x0);
  const double eps1 = 1e-2 * scene_.solver.hMax, eps2 = 1e-1 * scene_.solver.hMax, epsForces2 = std::max(eps2, 1e-4);
  std::vector<double> values[5];
  for (int order = 1; order <= 2; ++order)
    if (!groups[2 + order].empty()) values[2 + order] = valuesAt(x0, groups[2 + order], order);
  if (!groups[0].empty()) {
    IntegratorState ahead = alongMotion(x0, eps1, nullptr), behind = alongMotion(x0, -eps1, nullptr);
    const std::vector<double> plus = valuesAt(ahead, groups[0], 0), minus = valuesAt(behind, groups[0], 0);
    for (std::size_t i = 0; i < plus.size(); ++i) values[0].push_back((plus[i] - minus[i]) / (2.0 * eps1));
  }
  if (!groups[1].empty()) {
    IntegratorState ahead = alongMotion(x0, eps2, nullptr), behind = alongMotion(x0, -eps2, nullptr);
    const std::vector<double> plus = valuesAt(ahead, groups[1], 1), minus = valuesAt(behind, groups[1], 1);
    for (std::size_t i = 0; i < plus.size(); ++i) values[1].push_back((plus[i] - minus[i]) / (2.0 * eps2));
  }
  if (!groups[2].empty()) {
    const double e = epsForces2;
    const IntegratorState ahead = alongMotion(x0, e, nullptr), behind = alongMotion(x0, -e, nullptr);
    const VectorXd jerk = (ahead.vdot - behind.vdot) / (2.0 * e);
    IntegratorState ahead2 = alongMotion(x0, e, &jerk), behind2 = alongMotion(x0, -e, &jerk);
    const std::vector<double> plus = valuesAt(ahead2, groups[2], 0), minus = valuesAt(behind2, groups[2], 0),
                              now = valuesAt(x0, groups[2], 0);
    for (std::size_t i = 0; i < plus.size(); ++i) values[2].push_back((plus[i] - 2.0 * now[i] + minus[i]) / (e * e));
  }
  std::vector<double> result;
  for (const auto& [g, k] : place) result.push_back(values[g][k]);
  return result;
}

// At a fixed state (q, v, t) the consistent accelerations and multipliers
// solve one linear system, [M Phi_q^T; Phi_q 0] [vdot; lambda] = [Q(u); -gamma],
// whose right-hand side is affine in the force inputs u; the outputs are
// affine in (vdot, lambda, u) (quadratic at most in a rate-driven support's
// rate, through its node's velocity). So the central difference of the
// outputs over u +- s seed is the exact partial, up to round-off: the same
// solve with the input direction as right-hand side. s scales the seed to
// the size of the inputs (at least 1), so that round-off stays relative to
// the outputs. Evaluated as fmi2GetReal would after fmi2SetReal of those
// inputs, and everything is put back.
std::vector<double> Simulation::inputDirectionalDerivative(const std::vector<Quantity>& outputs,
                                                           const std::vector<Quantity>& inputs,
                                                           const std::vector<double>& seed) {
  std::vector<double> result(outputs.size(), 0.0);
  double seedSize = 0.0, inputSize = 1.0;
  std::vector<double*> slots;
  for (std::size_t j = 0; j < inputs.size(); ++j) {
    slots.push_back(&inputSlot(inputs[j]));
    seedSize = std::max(seedSize, std::abs(seed[j]));
    inputSize = std::max(inputSize, std::abs(*slots.back()));
  }
  if (seedSize == 0.0 || outputs.empty()) return result;
  const double s = inputSize / seedSize;
  std::vector<double> saved;
  for (double* slot : slots) saved.push_back(*slot);
  const bool changed = inputsChangedSinceStep_;
  auto restore = [&] {
    for (std::size_t j = 0; j < slots.size(); ++j) *slots[j] = saved[j];
    inputsChangedSinceStep_ = changed;
    outputsCurrent_ = false;
  };
  auto outputsWith = [&](double sign) {
    restore();
    for (std::size_t j = 0; j < slots.size(); ++j) *slots[j] += sign * s * seed[j];
    inputsChangedSinceStep_ = true;  // the accelerations are solved for these inputs
    std::vector<double> y;
    for (const Quantity& q : outputs) y.push_back(read(q));
    return y;
  };
  try {
    const std::vector<double> plus = outputsWith(1.0), minus = outputsWith(-1.0);
    for (std::size_t i = 0; i < outputs.size(); ++i) result[i] = (plus[i] - minus[i]) / (2.0 * s);
  } catch (...) {
    restore();
    throw;
  }
  restore();
  return result;
}

}  // namespace mfbd
