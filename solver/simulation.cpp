#include "simulation.hpp"

#include <algorithm>
#include <limits>

#include <Eigen/QR>

#include "coupling/joint_constraint.hpp"
#include "flex/flexible_energy.hpp"
#include "integrator/constraint_rank.hpp"
#include "initial_equilibrium.hpp"
#include "integrator_choice.hpp"
#include "rigid/force_elements.hpp"
#include "rigid/mass_check.hpp"
#include "rigid/recursive_dynamics.hpp"
#include "math/number_text.hpp"

namespace mfbd {

void setSceneParameter(Scene& scene, const Quantity& q, double value) {
  switch (q.kind) {
    case QuantityKind::UserParameter: scene.parameters[q.index].value = value; break;
    case QuantityKind::Gravity: scene.gravity[q.component] = value; break;
    case QuantityKind::StepSizeMax: scene.solver.hMax = value; break;
    case QuantityKind::SpectralRadius: scene.solver.rhoInf = value; break;
    case QuantityKind::NewtonTolerance:
      // The parameter always carries a value (its start is the scene's):
      // another one is the user's choice.
      if (value != scene.solver.tolerance) scene.solver.toleranceGiven = true;
      scene.solver.tolerance = value;
      break;
    case QuantityKind::MaxSubsteps: scene.solver.maxSubsteps = value; break;
    case QuantityKind::JointDamping: scene.joints[q.index].damping = value; break;
    case QuantityKind::FlexibleDamping: scene.flexibleBodies[q.index].damping = value; break;
    default: break;
  }
}

double sceneParameter(const Scene& scene, const Quantity& q) {
  switch (q.kind) {
    case QuantityKind::UserParameter: return scene.parameters[q.index].value;
    case QuantityKind::Gravity: return scene.gravity[q.component];
    case QuantityKind::StepSizeMax: return scene.solver.hMax;
    case QuantityKind::SpectralRadius: return scene.solver.rhoInf;
    case QuantityKind::NewtonTolerance: return scene.solver.tolerance;
    case QuantityKind::MaxSubsteps: return scene.solver.maxSubsteps;
    case QuantityKind::JointDamping: return scene.joints[q.index].damping;
    case QuantityKind::FlexibleDamping: return scene.flexibleBodies[q.index].damping;
    default: return 0.0;
  }
}

namespace {
// The scene's length scale for the error tolerance (README, "Error
// control"): the extent of its design configuration (body origins, the
// nodes of flexible bodies and the world origin) or, if larger, a body's
// radius of gyration; at least 1 mm.
double lengthScale(const Scene& scene) {
  Vec3 low = Vec3::Zero(), high = Vec3::Zero();
  double gyration = 0.0;
  auto include = [&](const Vec3& p) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  };
  for (const BodySpec& b : scene.bodies) {
    include(b.position);
    if (b.mass > 0.0) gyration = std::max(gyration, std::sqrt(b.inertia.trace() / b.mass));
  }
  for (const FlexibleBodySpec& f : scene.flexibleBodies)
    for (const Vec3& p : f.nodes) include(p);
  return std::max({1e-3, (high - low).norm(), gyration});
}

// The integrator's options: the scene's solver section, the FMI tolerance
// and the scene's length scale as the error's scale, the experiment's
// duration (fmi2SetupExperiment's, else the scene's) as its horizon.
SolverOptions solverOptions(const Scene& scene, double errorTolerance, double errorHorizon) {
  const SolverSection& s = scene.solver;
  SolverOptions options;
  options.hMax = s.hMax;
  options.hMin = s.hMin;
  options.rhoInf = s.rhoInf;
  options.maxSubsteps = s.maxSubsteps;
  options.tolerance = s.tolerance;
  options.maxIterations = s.maxIterations;
  options.errorTolerance = errorTolerance;
  options.errorScale = lengthScale(scene);
  const double duration = scene.experiment.stopTime - scene.experiment.startTime;
  options.errorHorizon = errorHorizon > 0.0 ? errorHorizon : duration > 0.0 ? duration : 1.0;
  options.newtonFollowsError = !s.toleranceGiven;
  return options;
}

// The Model, refused (SceneError) when its rigid tree has a motion that
// moves no mass and that nothing holds (rigid/mass_check.hpp).
Model assembleChecked(const Scene& scene) {
  Model model = assemble(scene);
  checkMassMatrix(scene, model);
  return model;
}
}  // namespace

Simulation::Simulation(const Scene& scene, double errorTolerance, double errorHorizon)
    : scene_(scene), system_(assembleChecked(scene)) {
  IntegratorChoice choice = chooseIntegrator(scene, system_, solverOptions(scene, errorTolerance, errorHorizon));
  stepper_ = std::move(choice.stepper);
  integratorNote_ = choice.note;
  const Model& model = system_.model();
  for (const BodySpec& b : scene.bodies) bodyIndex_.push_back(findBody(model, b.name));
  for (const JointSpec& j : scene.joints) jointIndex_.push_back(findJoint(model, j.name));
  orientation_.assign(scene.bodies.size() + model.flexible.nodes.size(), Quat::Identity());
  // Quaternions are kept sign-continuous only for what the outputs expose: a
  // 1000-element beam that lists two nodes converts two matrices per step.
  for (int b = 0; b < int(scene.bodies.size()); ++b)
    if (!scene.bodies[b].isVirtual && scene.outputs.exposesBody(scene.bodies[b].name)) trackedOrientations_.push_back(b);
  for (std::size_t f = 0; f < scene.flexibleBodies.size(); ++f)
    for (int i : scene.flexibleBodies[f].exposedNodes())
      trackedOrientations_.push_back(int(scene.bodies.size()) + model.flexible.bodies[f].firstNode + i);
  orientationTracked_.assign(orientation_.size(), false);
  for (const int i : trackedOrientations_) orientationTracked_[i] = true;
  state_.q = model.initialConfiguration;
  state_.v = model.initialVelocity;
}

bool Simulation::initialize(double t0, std::string& message, std::vector<std::string>* notes) {
  state_.t = t0;
  warnings_.clear();
  // Inputs and derivatives set before the start hold from the start time.
  for (InputSignals* s : {&system_.jointSignals(), &system_.forceSignals(), &system_.flexibleSignals()})
    s->anchor.setConstant(t0);
  system_.startDrives(t0);
  carryFlexibleBodies();
  system_.setRedundantRows({});
  if (!assembleConstraints(message, notes)) return false;
  if (notes && !integratorNote_.empty()) notes->push_back(integratorNote_);
  if (system_.constraintCount() > 0) {
    const ConstraintRank rank = constraintRank(constraintJacobian(state_.q, state_.v));
    system_.setRedundantRows(rank.redundantRows());
    const std::string redundant = redundantConstraints(rank, true);
    if (notes && !redundant.empty())
      notes->push_back("redundant constraints at the start (left out of the solve): " + redundant);
  }
  if (notes && system_.recursiveNewtonMatrix())
    notes->push_back("Newton matrix in the recursive form: " + std::to_string(system_.model().bodies.size()) +
                     " bodies, " + std::to_string(system_.auxiliaryCount(1.0)) +
                     " body-level unknowns (solver.newton_matrix)");
  return startIntegrator(message);
}

bool Simulation::startFromEquilibrium(std::string& message, std::vector<std::string>* notes) {
  if (!scene_.solver.initialEquilibrium || scene_.analysis != Analysis::Dynamic) return true;
  InitialEquilibriumReport report;
  if (!solveInitialEquilibrium(system_, state_, stepper_->options(), report, message)) return false;
  if (notes) notes->push_back(report.describe(system_));
  return startIntegrator(message);
}

bool Simulation::startIntegrator(std::string& message) {
  if (!stepper_->initialize(system_, state_, message)) return false;
  outputsCurrent_ = false;
  evaluateOutputs(false);
  updateQuaternions(true);
  return true;
}

// Quaternions of bodies and nodes, each sign-continuous with the previous
// communication point (w >= 0 at the start).
void Simulation::updateQuaternions(bool reset) {
  const std::size_t nb = bodyIndex_.size();
  for (const int k : trackedOrientations_) {
    const std::size_t i = std::size_t(k);
    const Mat3& A = i < nb ? system_.data().body[bodyIndex_[i]].orientation : system_.nodes()[i - nb].pose.A;
    Quat q(A);
    const double reference = reset ? q.w() : q.coeffs().dot(orientation_[i].coeffs());
    if (reference < 0.0) q.coeffs() *= -1.0;
    orientation_[i] = q;
  }
}

// Component (w, x, y, z) of orientation i (scene bodies, then mesh nodes):
// the sign-continuous one where the outputs expose it, else A's with w >= 0.
double Simulation::quaternion(std::size_t i, const Mat3& A, int component) const {
  Quat o = orientation_[i];
  if (!orientationTracked_[i]) {
    o = Quat(A);
    if (o.w() < 0.0) o.coeffs() *= -1.0;
  }
  const double wxyz[4] = {o.w(), o.x(), o.y(), o.z()};
  return wxyz[component];
}

AdvanceResult Simulation::doStep(double t, double H) {
  // The state to come back to if the step fails: before any restart, so a
  // retried step restarts from the same state again.
  // Statics: an input that jumped breaks the load path the predictor follows.
  if (inputsChangedSinceStep_) state_.pathRate.resize(0);
  stepStart_ = state_;  // assigned into kept buffers: no allocation per step
  state_.t = t;  // the master's clock: drives and loads see its times
  // An input that jumped at this communication point is a discontinuity:
  // restart generalized-alpha there, or its algorithmic acceleration would
  // carry the old input into the step (an O(h) error that does not go away).
  if (inputsChangedSinceStep_ && scene_.analysis == Analysis::Dynamic) {
    // A drive's rate input that jumped makes the velocities jump, by the
    // impulse that meets the velocity constraints again. (Only then: index-3
    // generalized-alpha meets them only to O(h^2), and a projection at every
    // change of a force input would alter the motion.)
    if (driveRateChanged_) {
      const VectorXd violation = system_.velocityConstraints(state_.t, state_.q, state_.v);
      if (violation.cwiseAbs().maxCoeff() > scene_.solver.tolerance)
        TimeStepper::jumpVelocities(system_, state_, violation);
    }
    std::string message;
    stepper_->inputsJumped(system_, state_, message);
  }
  // Held inputs let an explicit stepper step past t + H (and answer there
  // from its dense output); one that moves would be extrapolated. Not in a
  // step whose inputs just jumped either: a master that sets new inputs at
  // every point (a controller) would restart from an answer each time, the
  // dense output's error (of the order of the substep's estimate) added at
  // every point, where a landing substep's is an order smaller.
  const bool inputsHeld = scene_.analysis == Analysis::Dynamic && !inputsChangedSinceStep_ &&
                          !system_.jointSignals().moving && !system_.forceSignals().moving &&
                          !system_.flexibleSignals().moving;
  AdvanceResult result = stepper_->advance(system_, state_, H, inputsHeld);
  if (!result.ok) {
    // Where the substeps gave up, say which constraints were redundant:
    // rows that the motion cannot meet together are the usual cause.
    if (system_.constraintCount() > 0) {
      const std::string redundant = redundantConstraints(constraintRank(constraintJacobian(state_.q, state_.v)), false);
      if (!redundant.empty()) result.message += "; redundant constraints there: " + redundant;
    }
    std::swap(state_, stepStart_);
    outputsCurrent_ = false;  // the workspace holds the failed trial, not the restored state
    return result;
  }
  state_.t = t + H;  // exactly the master's next communication point
  system_.endStep(state_.t);
  inputsChangedSinceStep_ = false;
  driveRateChanged_ = false;
  outputsCurrent_ = false;
  evaluateOutputs(false);
  updateQuaternions(false);
  return result;
}

// Outputs of the state at the current time. Positions and velocities need
// only the kinematics. Accelerations and multipliers, so the reactions and
// drive forces, are solved consistently for the state (q, v) when one of
// those is read and there are constraints (index-3 generalized-alpha
// satisfies them only at position level) or inputs changed after the step;
// the integrator's own history is left untouched. That solve is a
// factorization of its own: a master that reads no reactions skips it.
void Simulation::evaluateOutputs(bool reactions) {
  if (outputsCurrent_ && (reactionsCurrent_ || !reactions)) return;
  outputsCurrent_ = true;
  reactionsCurrent_ = reactions;
  // The kinematics alone: what doStep evaluates for the quaternions' signs.
  if (!reactions) {
    system_.evaluateKinematics(state_.t, state_.q, state_.v, state_.vdot);
    outputVdot_ = state_.vdot;
    return;
  }
  VectorXd vdot = state_.vdot, lambda = state_.lambda;
  const bool consistentSolve = (inputsChangedSinceStep_ || system_.constraintCount() > 0) &&
                               scene_.analysis == Analysis::Dynamic;
  if (consistentSolve) {
    IntegratorState probe = state_;
    std::string message;
    if (stepper_->initialize(system_, probe, message)) {
      vdot = probe.vdot;
      lambda = probe.lambda;
    }
  }
  if (consistentSolve && system_.constraintCount() > 0) minimumNormMultipliers(vdot, lambda);
  system_.evaluate(state_.t, state_.q, state_.v, vdot, lambda);
  outputLambda_ = lambda;
  outputVdot_ = vdot;
}

// Redundant constraints (Bricard) leave the multipliers free along the
// null space of Phi_q^T: the generalized constraint force f = Phi_q^T
// lambda is unique, its split over the rows is whatever round-off picked
// (reaction torques 1.6 % of their range apart between a step H and
// nextafter(H)). The outputs take the minimum-norm lambda with that f, by
// a complete orthogonal decomposition of Phi_q^T; f is taken from the
// equations of motion, f = Q - M vdot (the residual with lambda = 0).
// Singular values below 1e-10 of the largest count as zero: a row that is
// a combination of others to round-off.
void Simulation::minimumNormMultipliers(const VectorXd& vdot, VectorXd& lambda) {
  const int n = system_.velocityCount(), m = system_.constraintCount();
  VectorXd r, phi;
  system_.residual(state_.t, state_.q, state_.v, vdot, VectorXd::Zero(m), r, phi);
  const Eigen::MatrixXd Jt = constraintJacobian(state_.q, state_.v).transpose();
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
  cod.setThreshold(1e-10);
  cod.compute(Jt);
  const VectorXd minimum = cod.solve(VectorXd(-r));
  if (minimum.allFinite() && n > 0) lambda = minimum;
}

double Simulation::read(const Quantity& q) {
  const Model& model = system_.model();
  switch (q.kind) {
    case QuantityKind::UserParameter:
    case QuantityKind::Gravity:
    case QuantityKind::StepSizeMax:
    case QuantityKind::SpectralRadius:
    case QuantityKind::NewtonTolerance:
    case QuantityKind::MaxSubsteps: return sceneParameter(scene_, q);
    case QuantityKind::JointDamping: return model.joints[jointIndex_[q.index]].damping;
    case QuantityKind::JointForceInput:
    case QuantityKind::JointDriveRate: {
      const Joint& j = model.joints[jointIndex_[q.index]];
      return system_.jointInputs()[j.inputOffset + q.component];
    }
    case QuantityKind::FlexibleInput: return system_.flexibleInputs()[q.index];
    case QuantityKind::ForceInput: return system_.forceInputs()[q.index];
    case QuantityKind::FlexibleDamping: {
      const FlexibleBody& b = model.flexible.bodies[q.index];
      return b.elementCount > 0 ? model.flexible.elements[b.firstElement].damping : 0.0;
    }
    default: break;
  }
  // Quantities of the multipliers or accelerations (with consistent element
  // mass, section forces include the element's inertia).
  evaluateOutputs(q.kind == QuantityKind::JointReactionForce || q.kind == QuantityKind::JointReactionTorque ||
                  q.kind == QuantityKind::JointDriveForce || q.kind == QuantityKind::FlexibleBodyJointForce ||
                  q.kind == QuantityKind::FlexibleBodyJointTorque || q.kind == QuantityKind::ElementSectionForce);
  if (q.kind >= QuantityKind::NodePosition) return readFlexible(q);
  const Data& data = system_.data();
  if (q.kind == QuantityKind::SpringLength) {
    const SpringState s = springState(model.forces[q.index], system_.forceInputsNow(), data);
    return q.component == 0 ? s.length : q.component == 1 ? s.rate : s.force;
  }
  if (q.kind == QuantityKind::FlexibleBodyJointViolation) return system_.flexibleBodyJointViolation(q.index);
  if (q.kind == QuantityKind::FlexibleBodyJointForce || q.kind == QuantityKind::FlexibleBodyJointTorque) {
    Vec3 force, torque;
    system_.flexibleBodyJointReaction(q.index, outputLambda_, force, torque);
    return q.kind == QuantityKind::FlexibleBodyJointForce ? force[q.component] : torque[q.component];
  }
  if (q.kind == QuantityKind::JointDriveForce)
    return -outputLambda_[model.joints[jointIndex_[q.index]].constraintOffset];
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
    if (j.cut) system_.cutJointReaction(k, outputLambda_, force, torque);
    else jointReaction(model, data, k, force, torque);
    return q.kind == QuantityKind::JointReactionForce ? force[q.component] : torque[q.component];
  }
  const int b = bodyIndex_[q.index];
  const BodyKinematics& k = data.body[b];
  const Vec3 comOffset = k.orientation * model.bodies[b].centerOfMass;  // frame origin -> centre of mass
  switch (q.kind) {
    case QuantityKind::BodyPosition: return (k.position - comOffset)[q.component];
    case QuantityKind::BodyVelocity: return (k.velocity - k.angularVelocity.cross(comOffset))[q.component];
    case QuantityKind::BodyAngularVelocity: return k.angularVelocity[q.component];
    case QuantityKind::BodyOrientation: return quaternion(q.index, k.orientation, q.component);
    default: return 0.0;
  }
}

double Simulation::readFlexible(const Quantity& q) {
  const FlexibleMesh& mesh = system_.model().flexible;
  if (q.kind == QuantityKind::FlexibleEnergy) {
    const FlexibleEnergy e =
        flexibleBodyEnergy(mesh, mesh.bodies[q.index], system_.nodes(), system_.model().gravity);
    return q.component == 0 ? e.kinetic : q.component == 1 ? e.strain : e.gravity;
  }
  if (q.kind == QuantityKind::ElementSectionForce) {
    const FlexElement& e = mesh.elements[q.index];
    const NodeState &a = system_.nodes()[e.node1], &b = system_.nodes()[e.node2];
    Vec12 f;
    if (!elementForce(e, a, b, system_.model().gravity, scene_.analysis == Analysis::Dynamic, f)) f.setZero();
    const SectionForces s = sectionForces(e.beam, a.pose, b.pose, f);
    const Vec3* parts[4] = {&s.force1, &s.moment1, &s.force2, &s.moment2};
    return (*parts[q.component / 3])[q.component % 3];
  }
  const NodeState& n = system_.nodes()[q.index];
  switch (q.kind) {
    case QuantityKind::NodePosition: return n.pose.r[q.component];
    case QuantityKind::NodeVelocity: return n.velocity.v[q.component];
    case QuantityKind::NodeAngularVelocity: return (n.pose.A * n.velocity.omega)[q.component];
    case QuantityKind::NodeOrientation: return quaternion(bodyIndex_.size() + q.index, n.pose.A, q.component);
    default: return 0.0;
  }
}

// Only a jump of the input's value at this time restarts the integrator
// (doStep): a master may set every input at every communication point, and
// an interpolating master sets the value its polynomial reached.
void Simulation::setInput(InputSignals& signals, int i, double value) {
  if (signals.at(i, state_.t) != value) inputsChangedSinceStep_ = true;
  signals.setValue(i, value, state_.t);
}

InputSignals* Simulation::inputSignal(const Quantity& q, int& index) {
  switch (q.kind) {
    case QuantityKind::JointForceInput:
    case QuantityKind::JointDriveRate:
      index = system_.model().joints[jointIndex_[q.index]].inputOffset + q.component;
      return &system_.jointSignals();
    case QuantityKind::ForceInput: index = q.index; return &system_.forceSignals();
    case QuantityKind::FlexibleInput: index = q.index; return &system_.flexibleSignals();
    default: return nullptr;
  }
}

bool Simulation::writeDerivative(const Quantity& q, int order, double value) {
  int i = 0;
  InputSignals* signals = inputSignal(q, i);
  if (!signals || order < 1 || order > InputSignals::kMaxOrder) return false;
  const double before = signals->at(i, state_.t);
  if ((order == 1 ? signals->d1 : signals->d2)[i] == value && signals->anchor[i] == state_.t) return true;
  signals->setDerivative(i, order, value, state_.t);
  // The input's value at this time moves to the one set when the anchor
  // moves: a drive rate that jumps makes the velocities jump (doStep).
  if (signals->at(i, state_.t) != before) {
    inputsChangedSinceStep_ = true;
    if (q.kind == QuantityKind::JointDriveRate) driveRateChanged_ = true;
  }
  outputsCurrent_ = false;
  return true;
}

void Simulation::saveState(StateWriter& ar) {
  visitState(ar);
  stepper_->saveState(ar);
}

void Simulation::loadState(StateReader& ar) {
  visitState(ar);
  stepper_->loadState(ar);
  const Model& model = system_.model();
  const int n = system_.velocityCount();
  const auto sized = [n](const VectorXd& x) { return x.size() == 0 || x.size() == n; };
  if (state_.q.scalars.size() != model.initialConfiguration.scalars.size() ||
      state_.q.rotations.size() != model.initialConfiguration.rotations.size() || state_.v.size() != n ||
      !sized(state_.vdot) || !sized(state_.a) || !sized(state_.pathRate) || !sized(state_.vdotBefore) ||
      (state_.lambdaBefore.size() != 0 && state_.lambdaBefore.size() != system_.constraintCount()) ||
      (state_.lambda.size() != 0 && state_.lambda.size() != system_.constraintCount()) ||
      orientation_.size() != orientationTracked_.size() || !system_.stateFits() || !stepper_->fits(state_))
    throw StateError("its sizes do not fit this scene's model");
  outputsCurrent_ = false;
  reactionsCurrent_ = false;
}

double& Simulation::inputSlot(const Quantity& q) {
  if (q.kind == QuantityKind::ForceInput) return system_.forceInputs()[q.index];
  if (q.kind == QuantityKind::FlexibleInput) return system_.flexibleInputs()[q.index];
  const Joint& j = system_.model().joints[jointIndex_[q.index]];
  return system_.jointInputs()[j.inputOffset + q.component];
}

bool Simulation::write(const Quantity& q, double value) {
  Model& model = system_.tunableModel();
  int i = 0;
  if (InputSignals* signals = inputSignal(q, i)) {
    if (q.kind == QuantityKind::JointDriveRate && signals->at(i, state_.t) != value) driveRateChanged_ = true;
    setInput(*signals, i, value);
    outputsCurrent_ = false;
    return true;
  }
  switch (q.kind) {
    case QuantityKind::JointDamping:
      model.joints[jointIndex_[q.index]].damping = value;
      inputsChangedSinceStep_ = true;
      break;
    case QuantityKind::FlexibleDamping: {
      const FlexibleBody& b = model.flexible.bodies[q.index];
      for (int e = 0; e < b.elementCount; ++e) model.flexible.elements[b.firstElement + e].damping = value;
      inputsChangedSinceStep_ = true;
      break;
    }
    default: return false;
  }
  outputsCurrent_ = false;
  return true;
}

}  // namespace mfbd
