// System: the mechanical system as the integrator sees it (Dynamics), built
// from a Model: a rigid tree in joint coordinates (gravity, joint damping,
// joint-force inputs) and flexible bodies of corotational beams (supports,
// loads, drives). Velocities: joint rates first, then free node DOFs.
#pragma once
#include <Eigen/Cholesky>
#include <vector>

#include "flex/flexible_mesh.hpp"
#include "integrator/dynamics.hpp"
#include "math/input_signals.hpp"
#include "model/data.hpp"
#include "rigid/recursive_dynamics.hpp"
#include "two_marker_constraints.hpp"

namespace mfbd {

class System : public Dynamics {
 public:
  explicit System(Model model);

  const Model& model() const { return model_; }
  Model& tunableModel() { return model_; }  // for tunable parameters only
  const Data& data() const { return data_; }
  const std::vector<NodeState>& nodes() const { return nodes_; }

  // Inputs as set (values, and derivatives for interpolation in a step):
  // generalized joint forces along actuated DOFs and joint drive rates;
  // force-element inputs (spring actuator forces, applied forces and
  // torques); flexible-body inputs (six per input load, one per rate-driven
  // support).
  InputSignals& jointSignals() { return jointSignals_; }
  InputSignals& forceSignals() { return forceSignals_; }
  InputSignals& flexibleSignals() { return flexibleSignals_; }
  // Their values as set.
  VectorXd& jointInputs() { return jointSignals_.value; }
  const VectorXd& jointInputs() const { return jointSignals_.value; }
  VectorXd& forceInputs() { return forceSignals_.value; }
  const VectorXd& forceInputs() const { return forceSignals_.value; }
  VectorXd& flexibleInputs() { return flexibleSignals_.value; }
  const VectorXd& flexibleInputs() const { return flexibleSignals_.value; }
  // Force-element inputs at the time of the last evaluation (outputs).
  const VectorXd& forceInputsNow() const { return forceSignals_.current(); }
  // Rate-input drives integrate their angle; fold it in at each step end.
  const DriveState& driveState() const { return drives_; }
  void setDriveState(const DriveState& d) { drives_ = d; }
  void startDrives(double t0);  // the first step starts at t0 from the initial coordinates
  void endStep(double t);
  // The coordinate a joint drive prescribes at t: drive(t), or for a rate
  // input the coordinate at the step start plus rate (t - step start).
  double driveCoordinate(const Joint& joint, double t) const;

  int velocityCount() const override { return model_.velocityCount; }
  int constraintCount() const override { return model_.constraintCount; }
  void retract(Configuration& q, const VectorXd& dq) const override;
  void chartRate(const VectorXd& delta, const VectorXd& v, VectorXd& rate) const override {
    mfbd::chartRate(model_.blocks, delta, v, rate);
  }
  void residual(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot, const VectorXd& lambda,
                VectorXd& r, VectorXd& phi) override;
  void tangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot, const VectorXd& lambda,
               double cM, double cC, double cK, Triplets& iteration, Triplets& constraintJacobian) override;
  // Auxiliary unknowns of the recursive Newton matrix (see recursiveTangent):
  // 18 per body, in dynamics (cM != 0) when the model uses that form.
  int auxiliaryCount(double cM) const override;
  bool recursiveNewtonMatrix() const { return recursiveMatrix_; }
  std::vector<std::pair<int, int>> pivotOrder(double cM) const override;
  VectorXd constraintAccelerationTerm(double t, const Configuration& q, const VectorXd& v) override;
  bool unconstrainedAccelerations(double t, const Configuration& q, const VectorXd& v, VectorXd& vdot) override;
  // Phi_q over the joint rates and node DOFs (joint space, whatever form
  // the Newton matrix takes): for assembly and the constraints' rank.
  void constraintJacobian(double t, const Configuration& q, const VectorXd& v, Triplets& jacobian);
  // Phi_q v + Phi_t; Phi_t (drives) by central differences in time.
  VectorXd velocityConstraints(double t, const Configuration& q, const VectorXd& v) override;
  // Constraint rows that are combinations of the others along the motion
  // (Bricard's sixth joint condition; a planar loop's out-of-plane rows),
  // found at the start (Simulation::initialize), are left out of what the
  // integrator solves, as multibody codes leave out redundant constraints:
  // their rows of phi, gamma and Phi_q v + Phi_t read zero and the Newton
  // matrix gets no Jacobian row for them, so their multipliers stay zero.
  // Kept in, a regularised constraint block turns each row's round-off into
  // a multiplier along the null space of Phi_q^T, and the iterations add it
  // up without bound (docs/design.md, "Redundant constraints").
  // constraintJacobian keeps every row (outputs, assembly, rank).
  void setRedundantRows(std::vector<int> rows) { redundantRows_ = std::move(rows); }
  const std::vector<int>& redundantRows() const { return redundantRows_; }
  double redundantViolation() const override { return redundantViolation_; }
  bool readmitRedundantRows() override {
    const bool any = !redundantRows_.empty();
    redundantRows_.clear();
    return any;
  }
  double constraintLengthScale() const override { return constraintLengthScale_; }
  double tangentCost() const override;
  bool elasticCoordinates() const override;
  bool flexibleBodies() const override { return !model_.flexible.nodes.empty(); }
  void turnWithRotations(const Configuration& from, const Configuration& to, VectorXd& x,
                         bool transpose) const override;
  void turnOverStep(const Configuration& q, const VectorXd& v, double h, VectorXd& x) const override;

  // Force and torque a cut joint passes to its child (child marker frame,
  // about its origin), from the multipliers (after evaluate()).
  void cutJointReaction(int joint, const VectorXd& lambda, Vec3& force, Vec3& torque) const;
  // Force and torque flexible body joint k passes from the node to its
  // virtual body (virtual body frame, about its origin), and the largest
  // violation of its rows (m, rad), after evaluate().
  void flexibleBodyJointReaction(int k, const VectorXd& lambda, Vec3& force, Vec3& torque) const;
  double flexibleBodyJointViolation(int k) const;

  // Every member that carries over between evaluations (inputs, drives,
  // tunable damping); the rest is workspace or fixed by the model.
  template <class Archive>
  void visitState(Archive& ar) {
    ar(jointSignals_, forceSignals_, flexibleSignals_);
    ar(drives_.startAngle, drives_.stepStart, jointDriveStart_, jointDriveStepStart_, constraintLengthScale_);
    ar(redundantRows_);
    for (Joint& j : model_.joints) ar(j.damping);
    for (FlexElement& e : model_.flexible.elements) ar(e.damping);
    drives_.samples.clear();  // caches of time functions, recomputed alike
    driveSamples_.clear();
  }
  // The saved sizes match this model.
  bool stateFits() const;

  // Kinematics, joint reactions and node states of a state into data() and
  // nodes() (for outputs).
  void evaluate(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot, const VectorXd& lambda);
  // Kinematics and node states alone: what outputs of positions, velocities,
  // orientations, springs and flexible body joint violations read.
  void evaluateKinematics(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot);

 private:
  // The residual (system.cpp).
  void rigidResidual(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                     const VectorXd& lambda, VectorXd& r, VectorXd& phi, VectorXd* nodeRows = nullptr);
  void jointForces(const Configuration& q, const VectorXd& v, VectorXd& tau) const;
  // The joint-space tangent and its sparsity and colouring (joint_space_tangent.cpp).
  void jointSpaceSparsity();
  void colourRates();
  void rigidTangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot, const VectorXd& lambda,
                    double cM, double cC, double cK, Triplets& iteration, Triplets& constraintJacobian);
  // The recursive Newton matrix (recursive_newton_matrix.cpp).
  bool chooseRecursiveNewtonMatrix() const;
  void recursiveTangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot, const VectorXd& lambda,
                        double cM, double cC, double cK, Triplets& iteration, Triplets& constraintJacobian);
  void bodyBlocks(int i, const BiasRateDerivatives& D, double cM, double cC, double cK, Triplets& iteration) const;
  Eigen::MatrixXd ownAxesStiffness(int i, const VectorXd& v, Configuration& moved) const;
  void jointBlocks(int i, const BiasRateDerivatives& D, const VectorXd& v, double cC, double cK, Configuration& moved,
                   Triplets& iteration) const;
  void forceElementTangent(double t, double cC, double cK, Triplets& iteration);
  // Constraint rows: two-marker constraints and drives (constraint_rows.cpp).
  SideColumns columnsOf(const ConstraintSide& side, bool bodyColumns) const;
  Eigen::MatrixXd rowsOn(const ConstraintSide& side, const SideColumns& columns, const ConstraintJacobian& J,
                         bool bodyColumns) const;
  void twoMarkerRowsAndForces(const VectorXd& lambda, VectorXd& phi, VectorXd* nodeRows);
  void twoMarkerJacobian(bool bodyColumns, Triplets& constraintJacobian);
  void twoMarkerAccelerationTerms(VectorXd& gamma) const;
  void twoMarkerStiffness(const VectorXd& lambda, double cK, bool bodyColumns, Triplets& iteration);
  void driveRowsAndForces(double t, const Configuration& q, const VectorXd& lambda, VectorXd& phi, VectorXd& r);
  void driveJacobian(Triplets& constraintJacobian) const;
  // Phi_q: drives on their joint rates; two-marker constraints over the
  // joint rates that move their bodies (Phi_q = Phi_Z B: joint-space form)
  // or over the auxiliary body-level unknowns (bodyColumns: the recursive
  // form), and their nodes' free DOFs. After forwardKinematics, with nodes_
  // current.
  void constraintRows(bool bodyColumns, Triplets& constraintJacobian);
  const TwoMarkerConstraint& constraintAtRow(int firstRow) const;
  JointReaction reaction(const TwoMarkerConstraint& k, const VectorXd& lambda) const;
  // Indices of body i's variations among the Newton matrix's unknowns
  // (auxiliary, after the velocities): of its pose and velocity y_i, of
  // the wrench z_i its inboard joint passes, of its acceleration w_i.
  int bodyUnknown(int i) const { return model_.velocityCount + 6 * i; }
  int wrenchUnknown(int i) const { return model_.velocityCount + 6 * (int(model_.bodies.size()) + i); }
  int accelerationUnknown(int i) const { return model_.velocityCount + 6 * (2 * int(model_.bodies.size()) + i); }

  Model model_;
  Data data_;
  // Read through current(): the inputs at the time of the evaluation under
  // way (inputsAt).
  InputSignals jointSignals_, flexibleSignals_, forceSignals_;
  void inputsAt(double t);
  DriveState drives_;
  std::vector<double> jointDriveStart_;  // per joint: a rate-input drive's coordinate at the step start
  double jointDriveStepStart_ = 0.0;
  // Per joint: its drive law for the last time asked (TimeFunction::Sample).
  mutable std::vector<TimeFunction::Sample> driveSamples_;
  std::vector<NodeState> nodes_;
  VectorXd tau_, rigid_;
  Eigen::MatrixXd massMatrix_;  // joint-space, of rigidTangent and unconstrainedAccelerations
  VectorXd noAccelerations_, noMultipliers_, noConstraints_;  // unconstrainedAccelerations' workspace
  Eigen::LLT<Eigen::MatrixXd> massFactor_;
  double constraintLengthScale_ = 1.0;  // of the last residual
  std::vector<int> redundantRows_;     // see setRedundantRows
  double redundantViolation_ = 0.0;    // of the last residual
  // Zeroes the redundant rows of a constraint vector; the largest of them.
  double leaveOutRedundantRows(VectorXd& rows) const;
  bool recursiveMatrix_ = false;  // Newton matrix in the recursive form (dynamics)
  std::vector<int> blockOfRate_;  // model_.blocks index of each rate
  // Sparsity of the rigid tangent: the joint rates that move each body (its
  // path to ground), and which pairs of rates can couple at all
  // (jointSpaceSparsity). Fixed by the topology, so the pattern never changes.
  std::vector<std::vector<int>> supportColumns_;
  Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> ratesCoupled_;
  std::vector<std::vector<int>> tangentColours_;  // rates perturbed together (rigidTangent)
  std::vector<TwoMarkerConstraint> constraints_;  // cut joints, then flexible body joints
  // Three translation rates (from velocityOffset) that turn with a stored rotation.
  struct TurningBlock {
    int velocityOffset, rotation;
  };
  std::vector<TurningBlock> turningBlocks_;
};

}  // namespace mfbd
