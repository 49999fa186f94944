// Simulation: the solver's facade for the FMU layer. One scene, its System,
// the integrator and its state; quantities read and written by kind, so the
// FMU layer needs no mechanics beyond this API and the variable table.
#pragma once
#include <memory>
#include <string>

#include "integrator/constraint_rank.hpp"
#include "integrator/time_stepper.hpp"
#include "model/model_numbering.hpp"
#include "system.hpp"

namespace mfbd {

enum class QuantityKind {
  UserParameter,    // index: parameter                          (fixed)
  Gravity,          // component 0..2                            (fixed)
  StepSizeMax,      //                                           (fixed)
  SpectralRadius,   //                                           (fixed)
  NewtonTolerance,  // position error left by Newton (m, rad)     (fixed)
  MaxSubsteps,      // substeps per communication step at most    (fixed)
  JointDamping,     // index: joint                              (tunable)
  JointForceInput,  // index: joint, component: DOF              (input)
  JointDriveRate,   // index: joint; rate of a rate-input drive  (input)
  JointCoordinate,  // index: joint, component: DOF              (output)
  JointRate,
  JointReactionForce,   // component 0..2, child marker frame
  JointReactionTorque,  // about the child marker origin
  JointDriveForce,      // generalized force of a drive along its coordinate
  FlexibleBodyJointForce,      // index: flexible body joint; node on virtual body, virtual body frame
  FlexibleBodyJointTorque,     // about the virtual body's origin
  FlexibleBodyJointViolation,  // largest |Phi| of its six rows (m, rad)
  ForceInput,           // index: offset into the force-element inputs             (input)
  SpringLength,         // index: force element; length, rate (component 1), tension (component 2)
  BodyPosition,         // user body frame origin, world
  BodyOrientation,      // quaternion w, x, y, z (body -> world)
  BodyVelocity,
  BodyAngularVelocity,
  NodePosition,         // index: mesh node; world
  NodeOrientation,      // quaternion w, x, y, z (node -> world)
  NodeVelocity,
  NodeAngularVelocity,  // world
  ElementSectionForce,  // index: mesh element; component 0..5 end 1 (N, Vy, Vz, T, My, Mz), 6..11 end 2
  FlexibleEnergy,       // index: flexible body; component 0 kinetic, 1 strain, 2 gravity potential
  FlexibleInput,        // index: offset into the flexible inputs (load components, drive rates)
  FlexibleDamping,      // index: flexible body (scene order)                       (tunable)
};

struct Quantity {
  QuantityKind kind;
  int index = 0;      // parameter, joint or body (model numbering for joints/bodies: by name at build)
  int component = 0;
};

// A fixed parameter's value written into a scene before assembly.
void setSceneParameter(Scene& scene, const Quantity& q, double value);
double sceneParameter(const Scene& scene, const Quantity& q);

class Simulation {
 public:
  // errorTolerance: the FMI tolerance (fmi2SetupExperiment), 0: no error
  // control; errorHorizon: the duration it holds over (stopTime - startTime),
  // 0: the scene's experiment. Throws SceneError.
  explicit Simulation(const Scene& scene, double errorTolerance = 0.0, double errorHorizon = 0.0);

  // Assembles closed loops and drives at time t0 (positions, then
  // velocities, projected onto the constraints by least change), then
  // consistent initial accelerations. False with a message naming the joint
  // whose constraint cannot be met; `notes` says what assembly moved.
  bool initialize(double t0, std::string& message, std::vector<std::string>* notes = nullptr);
  // With the scene's solver.initial_equilibrium (dynamics): moves the state
  // to the static equilibrium under gravity and loads at the current time,
  // at rest, and restarts the integrator there; `notes` gets a line with
  // the iterations and how far nodes moved. Otherwise nothing. Call after
  // initialize and after setting the inputs (fmi2ExitInitializationMode).
  bool startFromEquilibrium(std::string& message, std::vector<std::string>* notes = nullptr);
  // Advances by H from the master's time t (time() to round-off): the
  // substeps integrate exactly H, and time() is then t + H as the master
  // computes it, however large t is. On failure keeps the state of the
  // step start.
  AdvanceResult doStep(double t, double H);
  AdvanceResult doStep(double H) { return doStep(state_.t, H); }

  // What the initialization changed of what the scene asked for (given
  // initial rates the assembly adjusted): for the log at warning level.
  const std::vector<std::string>& warnings() const { return warnings_; }

  double time() const { return state_.t; }
  const IntegratorState& state() const { return state_; }
  const System& system() const { return system_; }
  // The numbers assembly gave (inputs, nodes, elements): what the variable
  // table reads of the assembled model.
  ModelNumbering numbering() const { return ModelNumbering(system_.model()); }

  double read(const Quantity& q);
  // Inputs and tunable parameters; false if q is neither. An input's value
  // restarts its derivatives at zero.
  bool write(const Quantity& q, double value);
  // Derivative of order 1 or 2 of an input at the present time: within the
  // next steps the input follows its Taylor polynomial (InputSignals).
  // False if q is not an input.
  bool writeDerivative(const Quantity& q, int order, double value);

  // Everything that influences the next results (integrator history and
  // its kept Newton matrix, inputs with their derivatives, drives, tunable
  // parameters, quaternion signs, pending input changes), as bytes. A
  // Simulation of the same scene and fixed parameters that loads them
  // continues bit for bit. loadState throws StateError on a blob that does
  // not fit, and may then have changed part of the state.
  void saveState(StateWriter& ar);
  void loadState(StateReader& ar);

  // Time derivatives of order 1 or 2 of outputs at the present state, the
  // inputs held (solver/output_derivatives.cpp): kinematic ones from the
  // state and its consistent accelerations, the rest by central
  // differences along the motion. Dynamics only.
  std::vector<double> outputDerivatives(const std::vector<Quantity>& outputs, const std::vector<int>& orders);
  // Sum over j of d outputs[i] / d inputs[j] * seed[j] at the present
  // state (q, v, t), as fmi2GetDirectionalDerivative. Dynamics only.
  std::vector<double> inputDirectionalDerivative(const std::vector<Quantity>& outputs,
                                                 const std::vector<Quantity>& inputs, const std::vector<double>& seed);

 private:
  // The integrator's consistent start (accelerations, multipliers) at the
  // present state, and the outputs of that state.
  bool startIntegrator(std::string& message);
  void evaluateOutputs(bool reactions);
  void minimumNormMultipliers(const VectorXd& vdot, VectorXd& lambda);

  void updateQuaternions(bool reset);
  double quaternion(std::size_t i, const Mat3& A, int component) const;
  bool assembleConstraints(std::string& message, std::vector<std::string>* notes);
  void warnGivenRatesChanged(const VectorXd& dv);
  void carryFlexibleBodies();
  bool carryOneFlexibleBody(const std::vector<BodyKinematics>& before, std::vector<bool>& carried);
  std::string constraintOwner(int row) const;
  std::string constraintOwners(const std::vector<int>& rows) const;
  Eigen::MatrixXd constraintJacobian(const Configuration& q, const VectorXd& v);
  std::string redundantConstraints(const ConstraintRank& rank, bool vanishing);
  double readFlexible(const Quantity& q);
  void setInput(InputSignals& signals, int i, double value);
  InputSignals* inputSignal(const Quantity& q, int& index);
  template <class Archive>
  void visitState(Archive& ar) {
    ar(state_, orientation_, inputsChangedSinceStep_, driveRateChanged_, system_);
  }
  double& inputSlot(const Quantity& q);  // the value of an input quantity

  // Output derivatives (output_derivatives.cpp).
  bool consistentAccelerations(IntegratorState& s);
  IntegratorState alongMotion(const IntegratorState& x, double eps, const VectorXd* jerk);
  std::vector<double> valuesAt(IntegratorState& s, const std::vector<Quantity>& outputs, int order);
  int exactDerivativeOrder(const Quantity& q) const;
  double exactDerivative(const Quantity& q, int order);
  double rateFromState(const Quantity& q);
  Quat outputQuaternion(std::size_t i, const Mat3& A) const;

  const Scene scene_;
  std::vector<std::string> warnings_;
  System system_;
  std::unique_ptr<TimeStepper> stepper_;
  std::string integratorNote_;  // which integrator, and why (logged at initialization)
  IntegratorState state_;
  std::vector<int> trackedOrientations_;  // indices into orientation_ of the exposed bodies and nodes
  std::vector<bool> orientationTracked_;  // the same as flags over orientation_
  IntegratorState stepStart_;  // of the communication step under way: restored if it fails
  std::vector<int> bodyIndex_, jointIndex_;  // scene order -> model order
  std::vector<Quat> orientation_;            // sign-continuous across steps: scene bodies, then mesh nodes
  VectorXd outputLambda_;  // multipliers of the evaluated outputs
  VectorXd outputVdot_;    // accelerations of the evaluated outputs
  bool outputsCurrent_ = false;
  bool reactionsCurrent_ = false;  // the evaluated outputs include consistent reactions
  bool inputsChangedSinceStep_ = false;
  bool driveRateChanged_ = false;  // a rate-input drive's rate, since the last step
};

}  // namespace mfbd
