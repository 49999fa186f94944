// The recursive formulation's Newton matrix (System::recursiveTangent), the
// choice of that form, and the elimination order that keeps it free of
// fill (System::pivotOrder).
#include <algorithm>
#include <cmath>

#include "rigid/force_elements.hpp"
#include "rigid/joint_motion.hpp"
#include "rigid/recursive_dynamics.hpp"
#include "system.hpp"

namespace mfbd {

// The joint-space tangent costs a residual per rate and a factorization of
// its pattern: the recursive form pays off once that pattern holds about a
// dense block of kRecursiveNewtonMatrixRates rates (a chain of that length).
// Not automatically with cut joints: their multipliers couple every body
// between the loop's ends in the elimination (R3's 40 loops).
bool System::chooseRecursiveNewtonMatrix() const {
  using Form = SolverSection::NewtonMatrix;
  bool cutJoints = false;
  for (const Joint& j : model_.joints) cutJoints = cutJoints || j.cut;
  const int coupled = int(ratesCoupled_.count());
  const int dense = SolverSection::kRecursiveNewtonMatrixRates * SolverSection::kRecursiveNewtonMatrixRates;
  return model_.analysis == Analysis::Dynamic && !model_.bodies.empty() &&
         (model_.newtonMatrix == Form::Recursive ||
          (model_.newtonMatrix == Form::Automatic && !cutJoints && coupled >= dense));
}

int System::auxiliaryCount(double cM) const {
  return recursiveMatrix_ && cM != 0.0 ? 18 * int(model_.bodies.size()) : 0;
}

// Body by body from the leaves in, each body's acceleration and velocity
// variations pivoting on their recursion rows (unit pivots), its wrench on
// its balance row (unit),
// then its joint rates on their own rows (the articulated inertia S^T H S
// by then): the elimination of the articulated-body recursion, no fill
// beyond each body's parent. Multipliers and flexible DOFs follow.
std::vector<std::pair<int, int>> System::pivotOrder(double cM) const {
  std::vector<std::pair<int, int>> order;
  if (auxiliaryCount(cM) == 0) return order;
  for (int i = int(model_.bodies.size()) - 1; i >= 0; --i) {
    for (int d = 0; d < 6; ++d) order.emplace_back(accelerationUnknown(i) + d, accelerationUnknown(i) + d);
    for (int d = 0; d < 6; ++d) order.emplace_back(wrenchUnknown(i) + d, bodyUnknown(i) + d);
    for (int d = 0; d < 6; ++d) order.emplace_back(bodyUnknown(i) + d, wrenchUnknown(i) + d);
    const Joint& jt = model_.joints[model_.bodies[i].inboardJoint];
    for (int d = 0; d < jt.dofs; ++d) order.emplace_back(jt.velocityOffset + d, jt.velocityOffset + d);
  }
  return order;
}

// The recursive formulation's own Newton matrix, sparse and O(n) for a tree
// of n bodies where the joint-space B^T M B is dense (a chain). Besides the
// joint-rate corrections x it carries, per body, the variations y of its
// pose and velocity ([dr; dphi], world, centre of mass: velocity
// variations are cC y), w of its acceleration, and z of the wrench its
// inboard joint passes to its subtree:
//   x rows:  A x + S^T z                                   = r
//   y rows:  cM M w + H y - (I - P)^T z + Phi_Z^T dl        = 0  (wrench balance)
//   z rows:  S x - (I - P) y                               = 0  (y = T y_parent + S x)
//   w rows:  S x - (I - P) w + cC (D_p y_parent + D_x x)   = 0  (accelerations)
// with T the rigid transfer from the parent's centre of mass, A the joint
// springs and dampers, H = cC C + cK K of inertia (gyroscopic), force
// elements and cut joints at body level, and D the derivatives of the
// acceleration recursion's rate terms (Coriolis, centripetal) with respect
// to the parent's velocity and the joint rates, and the geometric stiffness
// of the transmitted wrenches z (joint axes turning, levers stretching).
// Eliminating y, w and z leaves the joint-space matrix: mass and damping
// exactly, stiffness exactly where nothing accelerates; left out is the
// turning of S and T acting on accelerations (relative size h^2 |a| / L):
// Newton converges linearly there, to the same answer (the residual is
// exact). Statics (cM = 0) uses the joint space (no auxiliary unknowns).
void System::recursiveTangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                              const VectorXd& lambda, double cM, double cC, double cK, Triplets& iteration,
                              Triplets& constraintJacobian) {
  // The residual's backward loop: the subtree wrenches z the geometric
  // terms act on (and the kinematics of q).
  VectorXd r, phi;
  rigidResidual(t, q, v, vdot, lambda, r, phi);
  Configuration moved = q;  // joint coordinates perturbed one block at a time
  for (int i = 0; i < int(model_.bodies.size()); ++i) {
    const BiasRateDerivatives D = biasRateDerivatives(model_, data_, q, v, i);
    bodyBlocks(i, D, cM, cC, cK, iteration);
    jointBlocks(i, D, v, cC, cK, moved, iteration);
  }
  forceElementTangent(t, cC, cK, iteration);
  constraintRows(true, constraintJacobian);
}

// Blocks are written with every entry that can be nonzero, zeros included,
// so that the pattern never changes: in full where they couple poses, by
// their structure where that is fixed (unit diagonals, the rigid transfer's
// lever arm, a body's mass and rotary inertia).
namespace {
void block(Triplets& iteration, int row, int col, const Mat6& M) {
  for (int k = 0; k < 6; ++k)
    for (int i = 0; i < 6; ++i) iteration.emplace_back(row + i, col + k, M(i, k));
}
void diagonal(Triplets& iteration, int row, int col, double value) {
  for (int i = 0; i < 6; ++i) iteration.emplace_back(row + i, col + i, value);
}
void corner(Triplets& iteration, int row, int col, const Mat3& M) {  // the 3 x 3 block at (row, col)
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) iteration.emplace_back(row + i, col + k, M(i, k));
}
}  // namespace

// Body i's inertia (wrench balance rows) and its recursion rows from its
// parent: y and w over the parent's through T and D_p.
void System::bodyBlocks(int i, const BiasRateDerivatives& D, double cM, double cC, double cK,
                        Triplets& iteration) const {
  const Body& b = model_.bodies[i];
  const BodyKinematics& k = data_.body[i];
  const Mat3 J = k.orientation * b.inertia * k.orientation.transpose();
  const Vec3& w = k.angularVelocity;
  const Mat3 gyroscopic = skew(w) * J - skew(J * w);  // d(w x J w)/dw
  // d(J alpha + w x J w)/dphi, J = A J0 A^T turned by dphi.
  const Mat3 turning =
      J * skew(k.angularAcceleration) - skew(J * k.angularAcceleration) + skew(w) * (J * skew(w) - skew(J * w));
  // cM M on the acceleration; cC gyroscopic + cK turning on the pose.
  for (int d = 0; d < 3; ++d) iteration.emplace_back(bodyUnknown(i) + d, accelerationUnknown(i) + d, cM * b.mass);
  corner(iteration, bodyUnknown(i) + 3, accelerationUnknown(i) + 3, cM * J);
  corner(iteration, bodyUnknown(i) + 3, bodyUnknown(i) + 3, cC * gyroscopic + cK * turning);
  diagonal(iteration, bodyUnknown(i), wrenchUnknown(i), -1.0);
  diagonal(iteration, wrenchUnknown(i), bodyUnknown(i), -1.0);
  diagonal(iteration, accelerationUnknown(i), accelerationUnknown(i), -1.0);
  if (b.parent == kGroundIndex) return;
  // T = [I, -skew(dr); 0, I]: v_i = v_p + w_p x dr, and so for accelerations.
  const Mat3 lever = -skew(k.position - data_.body[b.parent].position);
  diagonal(iteration, wrenchUnknown(i), bodyUnknown(b.parent), 1.0);
  corner(iteration, wrenchUnknown(i), bodyUnknown(b.parent) + 3, lever);
  diagonal(iteration, bodyUnknown(b.parent), wrenchUnknown(i), 1.0);
  corner(iteration, bodyUnknown(b.parent) + 3, wrenchUnknown(i), lever.transpose());
  diagonal(iteration, accelerationUnknown(i), accelerationUnknown(b.parent), 1.0);
  corner(iteration, accelerationUnknown(i), accelerationUnknown(b.parent) + 3, lever);
  block(iteration, accelerationUnknown(i), bodyUnknown(b.parent), cC * D.parent);
}

// d(S^T z)/dq of body i's inboard joint along its own coordinates at fixed
// parent pose (universal, spherical, free: the axes turn with them), by
// central differences along the retraction. Only this joint's coordinate
// block moves: perturbed in place in one copy of q (a copy per rate would
// make the tangent O(n^2)).
Eigen::MatrixXd System::ownAxesStiffness(int i, const VectorXd& v, Configuration& moved) const {
  const Body& b = model_.bodies[i];
  const Joint& jt = model_.joints[b.inboardJoint];
  const Vec3& F = data_.subtreeForce[i];
  const Vec3& N = data_.subtreeTorque[i];
  const Mat3 AP =
      (b.parent == kGroundIndex ? Mat3::Identity() : data_.body[b.parent].orientation) * jt.parentMarker.orientation;
  auto transmitted = [&](const Configuration& qj) {  // S(q)^T z at fixed parent pose
    const JointMotion m = jointMotion(jt, qj, v.segment(jt.velocityOffset, jt.dofs));
    const Mat3 AC = AP * m.rotation;
    const Vec3 pC = AC * jt.childMarker.orientation.transpose() * jt.childMarker.position;
    const Matrix3X Sw = AC * m.Hw;
    const Matrix3X Sv = AP * m.Hv + skew(pC) * Sw;
    return VectorXd(Sv.transpose() * F + Sw.transpose() * N);
  };
  Eigen::MatrixXd dOwn(jt.dofs, jt.dofs);
  const double eps = 1e-6;
  for (int d = 0; d < jt.dofs; ++d) {
    const CoordinateBlock& block = model_.blocks[blockOfRate_[jt.velocityOffset + d]];
    VectorXd column[2];
    for (int side = 0; side < 2; ++side) {
      const bool rotation = block.rotation >= 0;
      const Mat3 savedRotation = rotation ? moved.rotations[block.rotation] : Mat3::Identity();
      const VectorXd savedScalars = rotation ? VectorXd() : VectorXd(moved.scalars.segment(block.scalarOffset, block.size));
      retractBlock(block, moved,
                   VectorXd::Unit(block.size, jt.velocityOffset + d - block.velocityOffset) * (side ? -eps : eps));
      column[side] = transmitted(moved);
      if (rotation) moved.rotations[block.rotation] = savedRotation;
      else moved.scalars.segment(block.scalarOffset, block.size) = savedScalars;
    }
    dOwn.col(d) = (column[0] - column[1]) / (2.0 * eps);
  }
  return dOwn;
}

// The rows and columns of body i's inboard joint rates x: S x in the
// recursion rows, S^T z in their own rows, springs and dampers, and the
// geometric stiffness of the transmitted wrench z_i = [F; N]: the joint axes
// S turn rigidly with the parent, d(S^T z)/dphi_p = S_v^T skew(F) + S_w^T
// skew(N), and with the joint's own coordinates (ownAxesStiffness); the
// lever of T_i^T z_i in the parent's balance stretches with dr. A loaded
// chain's tension as a string's transverse stiffness.
void System::jointBlocks(int i, const BiasRateDerivatives& D, const VectorXd& v, double cC, double cK,
                         Configuration& moved, Triplets& iteration) const {
  const Body& b = model_.bodies[i];
  const Joint& jt = model_.joints[b.inboardJoint];
  const Matrix6X& S = data_.joint[b.inboardJoint].motionSubspace;
  const Vec3& F = data_.subtreeForce[i];
  const Vec3& N = data_.subtreeTorque[i];
  const Eigen::Matrix<double, Eigen::Dynamic, 3> dParent =
      S.topRows<3>().transpose() * skew(F) + S.bottomRows<3>().transpose() * skew(N);
  const Eigen::MatrixXd dOwn = ownAxesStiffness(i, v, moved);
  if (b.parent != kGroundIndex) {
    const Mat3 lever = cK * skew(F);  // d(dr x F) = -skew(F) (dr_i - dr_p)
    corner(iteration, bodyUnknown(b.parent) + 3, bodyUnknown(i), -lever);
    corner(iteration, bodyUnknown(b.parent) + 3, bodyUnknown(b.parent), lever);
  }
  for (int d = 0; d < jt.dofs; ++d)
    for (int e = 0; e < jt.dofs; ++e)
      iteration.emplace_back(jt.velocityOffset + d, jt.velocityOffset + e, cK * dOwn(d, e));
  for (int d = 0; d < jt.dofs; ++d) {
    const int x = jt.velocityOffset + d;
    if (b.parent != kGroundIndex)
      for (int c = 0; c < 3; ++c) iteration.emplace_back(x, bodyUnknown(b.parent) + 3 + c, cK * dParent(d, c));
    for (int r = 0; r < 6; ++r) {
      iteration.emplace_back(wrenchUnknown(i) + r, x, S(r, d));
      iteration.emplace_back(accelerationUnknown(i) + r, x, S(r, d) + cC * D.rates(r, d));
      iteration.emplace_back(x, wrenchUnknown(i) + r, S(r, d));
    }
    // Joint springs and dampers act on the joint's own rates.
    double a = cC * (jt.damping + jt.springDamping);
    if (d == 0) a += cK * jt.springStiffness;
    iteration.emplace_back(x, x, a);
  }
}

// Body-level stiffness and damping of the force elements, -dQ/d(pose) and
// -dQ/d(twist) of each element's wrenches, by finite differences of that
// element alone (6 evaluations per body it touches).
void System::forceElementTangent(double t, double cC, double cK, Triplets& iteration) {
  if (cC == 0.0 && cK == 0.0) return;
  const double eps = 1e-7;
  for (const ForceElement& e : model_.forces) {
    const int ends[2] = {e.marker1.body, e.kind == ForceElement::Kind::AppliedForce ? kGroundIndex : e.marker2.body};
    const ForceElementWrenches w0 = forceElementWrenches(e, forceSignals_.current(), t, data_);
    for (int side = 0; side < 2; ++side) {
      const int moved = ends[side];
      if (moved == kGroundIndex) continue;
      BodyKinematics& k = data_.body[moved];
      const BodyKinematics saved = k;
      for (int d = 0; d < 6; ++d) {
        // Pose by eps e_d and twist by (cC/cK) eps e_d: the difference
        // quotient is K e_d + (cC/cK) C e_d (the twist alone when cK = 0).
        const double twist = cK != 0.0 ? cC / cK * eps : eps;
        if (cK != 0.0) {
          if (d < 3) k.position[d] += eps;
          else k.orientation = expSO3(eps * Vec3::Unit(d - 3)) * k.orientation;
        }
        if (d < 3) k.velocity[d] += twist;
        else k.angularVelocity[d - 3] += twist;
        const ForceElementWrenches w1 = forceElementWrenches(e, forceSignals_.current(), t, data_);
        k = saved;
        const double factor = -(cK != 0.0 ? cK : cC) / eps;
        for (int on = 0; on < 2; ++on) {
          if (ends[on] == kGroundIndex) continue;
          const Vec6 dw = on == 0 ? Vec6(w1.onBody1 - w0.onBody1) : Vec6(w1.onBody2 - w0.onBody2);
          for (int i = 0; i < 6; ++i) iteration.emplace_back(bodyUnknown(ends[on]) + i, bodyUnknown(moved) + d, factor * dw[i]);
        }
      }
    }
  }
}

}  // namespace mfbd
