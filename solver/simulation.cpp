#include "simulation.hpp"

#include "rigid/recursive_dynamics.hpp"

namespace mfbd {

void setSceneParameter(Scene& scene, const Quantity& q, double value) {
  switch (q.kind) {
    case QuantityKind::UserParameter: scene.parameters[q.index].value = value; break;
    case QuantityKind::Gravity: scene.gravity[q.component] = value; break;
    case QuantityKind::StepSizeMax: scene.solver.hMax = value; break;
    case QuantityKind::SpectralRadius: scene.solver.rhoInf = value; break;
    case QuantityKind::JointDamping: scene.joints[q.index].damping = value; break;
    default: break;
  }
}

double sceneParameter(const Scene& scene, const Quantity& q) {
  switch (q.kind) {
    case QuantityKind::UserParameter: return scene.parameters[q.index].value;
    case QuantityKind::Gravity: return scene.gravity[q.component];
    case QuantityKind::StepSizeMax: return scene.solver.hMax;
    case QuantityKind::SpectralRadius: return scene.solver.rhoInf;
    case QuantityKind::JointDamping: return scene.joints[q.index].damping;
    default: return 0.0;
  }
}

Simulation::Simulation(const Scene& scene)
    : scene_(scene), system_(assemble(scene)), integrator_(scene.solver) {
  const Model& model = system_.model();
  for (const BodySpec& b : scene.bodies) bodyIndex_.push_back(findBody(model, b.name));
  for (const JointSpec& j : scene.joints) jointIndex_.push_back(findJoint(model, j.name));
  orientation_.assign(scene.bodies.size(), Quat::Identity());
  state_.q = model.initialConfiguration;
  state_.v = model.initialVelocity;
}

bool Simulation::initialize(double t0, std::string& message) {
  state_.t = t0;
  if (!integrator_.initialize(system_, state_, message)) return false;
  outputsCurrent_ = false;
  evaluateOutputs();
  for (std::size_t i = 0; i < orientation_.size(); ++i) {
    orientation_[i] = Quat(system_.data().body[bodyIndex_[i]].orientation);
    if (orientation_[i].w() < 0.0) orientation_[i].coeffs() *= -1.0;
  }
  return true;
}

AdvanceResult Simulation::doStep(double H) {
  IntegratorState start = state_;
  AdvanceResult result = integrator_.advance(system_, state_, state_.t + H);
  if (!result.ok) {
    state_ = std::move(start);
    outputsCurrent_ = false;  // the workspace holds the failed trial, not the restored state
    return result;
  }
  inputsChangedSinceStep_ = false;
  outputsCurrent_ = false;
  evaluateOutputs();
  // Quaternion sign continuous with the previous communication point.
  for (std::size_t i = 0; i < orientation_.size(); ++i) {
    Quat qn(system_.data().body[bodyIndex_[i]].orientation);
    if (qn.coeffs().dot(orientation_[i].coeffs()) < 0.0) qn.coeffs() *= -1.0;
    orientation_[i] = qn;
  }
  return result;
}

// Outputs of the state at the current time. When inputs changed after the
// step, accelerations (and so reactions) are those of the new inputs; the
// integrator's own history is left untouched.
void Simulation::evaluateOutputs() {
  if (outputsCurrent_) return;
  VectorXd vdot = state_.vdot;
  if (inputsChangedSinceStep_) {
    IntegratorState probe = state_;
    std::string message;
    if (integrator_.initialize(system_, probe, message)) vdot = probe.vdot;
  }
  system_.evaluate(state_.q, state_.v, vdot);
  outputsCurrent_ = true;
}

double Simulation::read(const Quantity& q) {
  const Model& model = system_.model();
  switch (q.kind) {
    case QuantityKind::UserParameter:
    case QuantityKind::Gravity:
    case QuantityKind::StepSizeMax:
    case QuantityKind::SpectralRadius: return sceneParameter(scene_, q);
    case QuantityKind::JointDamping: return model.joints[jointIndex_[q.index]].damping;
    case QuantityKind::JointForceInput: {
      const Joint& j = model.joints[jointIndex_[q.index]];
      return system_.jointInputs()[j.inputOffset + q.component];
    }
    default: break;
  }
  evaluateOutputs();
  const Data& data = system_.data();
  if (q.kind == QuantityKind::JointCoordinate || q.kind == QuantityKind::JointRate ||
      q.kind == QuantityKind::JointReactionForce || q.kind == QuantityKind::JointReactionTorque) {
    const int k = jointIndex_[q.index];
    const Joint& j = model.joints[k];
    if (q.kind == QuantityKind::JointRate) return state_.v[j.velocityOffset + q.component];
    if (q.kind == QuantityKind::JointCoordinate) {
      const int scalars = j.rotation >= 0 ? j.dofs - 3 : j.dofs;
      if (q.component < scalars) return state_.q.scalars[j.scalarOffset + q.component];
      return logSO3(state_.q.rotations[j.rotation])[q.component - scalars];
    }
    Vec3 force, torque;
    jointReaction(model, data, k, force, torque);
    return q.kind == QuantityKind::JointReactionForce ? force[q.component] : torque[q.component];
  }
  const int b = bodyIndex_[q.index];
  const BodyKinematics& k = data.body[b];
  const Vec3 comOffset = k.orientation * model.bodies[b].centerOfMass;  // frame origin -> centre of mass
  switch (q.kind) {
    case QuantityKind::BodyPosition: return (k.position - comOffset)[q.component];
    case QuantityKind::BodyVelocity: return (k.velocity - k.angularVelocity.cross(comOffset))[q.component];
    case QuantityKind::BodyAngularVelocity: return k.angularVelocity[q.component];
    case QuantityKind::BodyOrientation: {
      const Quat& o = orientation_[q.index];
      const double wxyz[4] = {o.w(), o.x(), o.y(), o.z()};
      return wxyz[q.component];
    }
    default: return 0.0;
  }
}

bool Simulation::write(const Quantity& q, double value) {
  Model& model = system_.tunableModel();
  switch (q.kind) {
    case QuantityKind::JointDamping:
      model.joints[jointIndex_[q.index]].damping = value;
      inputsChangedSinceStep_ = true;
      break;
    case QuantityKind::JointForceInput: {
      const Joint& j = model.joints[jointIndex_[q.index]];
      system_.jointInputs()[j.inputOffset + q.component] = value;
      inputsChangedSinceStep_ = true;
      break;
    }
    default: return false;
  }
  outputsCurrent_ = false;
  return true;
}

}  // namespace mfbd
