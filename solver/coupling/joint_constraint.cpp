#include "coupling/joint_constraint.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mfbd {

namespace {

// Column offsets of z = [dr_i; dphi_i; dr_j; dphi_j].
constexpr int kRi = 0, kPhiI = 3, kRj = 6, kPhiJ = 9;

// The three kinds of rows every joint type is built from (header table).
enum class RowKind {
  Translation,   // p_k . (c - p): displacement along parent marker axis k
  Alignment,     // sign * p_a . q_b: two marker axes kept perpendicular
  RotationLock,  // logSO3(P^T Q): three rows, no relative rotation
};

struct RowBlock {
  RowKind kind = RowKind::Translation;
  int parentAxis = 0;  // k for Translation, a for Alignment
  int childAxis = 0;   // b for Alignment
  double sign = 1.0;
};

int rowsOf(const RowBlock& block) { return block.kind == RowKind::RotationLock ? 3 : 1; }

struct RowLayout {
  std::array<RowBlock, 5> blocks;
  int count = 0;
};

RowLayout rowLayout(JointType type) {
  const RowBlock dx{RowKind::Translation, 0}, dy{RowKind::Translation, 1}, dz{RowKind::Translation, 2};
  // Signed so that each is the small relative rotation about P's x, y, z.
  const RowBlock aboutX{RowKind::Alignment, 1, 2, -1.0};  // -p_y . q_z
  const RowBlock aboutY{RowKind::Alignment, 0, 2, 1.0};   //  p_x . q_z
  const RowBlock aboutZ{RowKind::Alignment, 0, 1, -1.0};  // -p_x . q_y
  const RowBlock lock{RowKind::RotationLock};
  switch (type) {
    case JointType::Revolute: return {{dx, dy, dz, aboutX, aboutY}, 5};
    case JointType::Prismatic: return {{dx, dy, lock}, 3};
    case JointType::Cylindrical: return {{dx, dy, aboutX, aboutY}, 4};
    case JointType::Universal: return {{dx, dy, dz, aboutZ}, 4};
    case JointType::Spherical: return {{dx, dy, dz}, 3};
    case JointType::Planar: return {{dz, aboutX, aboutY}, 3};
    case JointType::Fixed: return {{dx, dy, dz, lock}, 4};
    case JointType::Free: return {{}, 0};
  }
  return {{}, 0};
}

// Both marker frames in world, and the lever arms the Jacobians need.
struct MarkerFrames {
  Vec3 p, c;        // marker origins
  Mat3 P, Q;        // marker orientations
  Vec3 parentArm;   // A_i s_P = p - r_i
  Vec3 childArm;    // A_j s_C = c - r_j
  Vec3 parentBody;  // r_i
};

MarkerFrames markerFrames(const JointConstraint& joint, const BodyPose& parent, const BodyPose& child) {
  MarkerFrames f;
  f.parentArm = parent.A * joint.parentMarker.position;
  f.childArm = child.A * joint.childMarker.position;
  f.p = parent.r + f.parentArm;
  f.c = child.r + f.childArm;
  f.P = parent.A * joint.parentMarker.orientation;
  f.Q = child.A * joint.childMarker.orientation;
  f.parentBody = parent.r;
  return f;
}

void evaluateBlock(const RowBlock& block, const MarkerFrames& f, int row, ConstraintEvaluation& out) {
  auto Ji = out.jacobianParent.middleRows(row, rowsOf(block));
  auto Jj = out.jacobianChild.middleRows(row, rowsOf(block));
  switch (block.kind) {
    case RowKind::Translation: {
      // d(p_k.(c-p)) with dp_k = dphi_i x p_k, dp = dr_i + dphi_i x (p - r_i).
      const Vec3 e = f.P.col(block.parentAxis);
      out.phi[row] = e.dot(f.c - f.p);
      Ji.leftCols<3>() = -e.transpose();
      Ji.rightCols<3>() = e.cross(f.c - f.parentBody).transpose();
      Jj.leftCols<3>() = e.transpose();
      Jj.rightCols<3>() = f.childArm.cross(e).transpose();
      break;
    }
    case RowKind::Alignment: {
      const Vec3 a = f.P.col(block.parentAxis), b = f.Q.col(block.childAxis);
      out.phi[row] = block.sign * a.dot(b);
      Ji.rightCols<3>() = block.sign * a.cross(b).transpose();
      Jj.rightCols<3>() = block.sign * b.cross(a).transpose();
      break;
    }
    case RowKind::RotationLock: {
      // P^T exp(dphi_j) Q = (P^T Q) exp(Q^T dphi_j), and exp(-dphi_i) likewise:
      // dtheta = T^-1(theta) Q^T (dphi_j - dphi_i) (right-trivialised tangent).
      const Vec3 theta = logSO3(f.P.transpose() * f.Q);
      const Mat3 dTheta = tangentSO3Inverse(theta) * f.Q.transpose();
      out.phi.segment<3>(row) = theta;
      Ji.rightCols<3>() = -dTheta;
      Jj.rightCols<3>() = dTheta;
      break;
    }
  }
}

// Adds d(Phi_block,z^T lambda)/dz: the derivatives of the Jacobian rows above
// along each pose variation (da = dphi x a for every world vector a fixed in
// a body), weighted by the block's multipliers.
void addBlockStiffness(const RowBlock& block, const MarkerFrames& f, const Eigen::Ref<const Eigen::VectorXd>& lambda,
                       GeometricStiffness& K) {
  switch (block.kind) {
    case RowKind::Translation: {
      const double l = lambda[0];
      const Vec3 e = f.P.col(block.parentAxis);
      const Mat3 E = skew(e), U = skew(f.childArm), W = skew(f.c - f.parentBody);
      // rows dr_i: -e;  dr_j: e
      K.block<3, 3>(kRi, kPhiI) += l * E;
      K.block<3, 3>(kRj, kPhiI) -= l * E;
      // rows dphi_i: e x (c - r_i)
      K.block<3, 3>(kPhiI, kRi) -= l * E;
      K.block<3, 3>(kPhiI, kPhiI) += l * W * E;
      K.block<3, 3>(kPhiI, kRj) += l * E;
      K.block<3, 3>(kPhiI, kPhiJ) -= l * E * U;
      // rows dphi_j: (c - r_j) x e
      K.block<3, 3>(kPhiJ, kPhiI) -= l * U * E;
      K.block<3, 3>(kPhiJ, kPhiJ) += l * E * U;
      break;
    }
    case RowKind::Alignment: {
      // rows dphi_i: s a x b;  dphi_j: -s a x b;
      // d(a x b) = (a b^T - (a.b) I) dphi_i + ((a.b) I - b a^T) dphi_j.
      const double l = block.sign * lambda[0];
      const Vec3 a = f.P.col(block.parentAxis), b = f.Q.col(block.childAxis);
      const Mat3 byParent = a * b.transpose() - a.dot(b) * Mat3::Identity();
      const Mat3 byChild = a.dot(b) * Mat3::Identity() - b * a.transpose();
      K.block<3, 3>(kPhiI, kPhiI) += l * byParent;
      K.block<3, 3>(kPhiI, kPhiJ) += l * byChild;
      K.block<3, 3>(kPhiJ, kPhiI) -= l * byParent;
      K.block<3, 3>(kPhiJ, kPhiJ) -= l * byChild;
      break;
    }
    case RowKind::RotationLock: {
      // rows dphi_j: tau = Q T^-T(theta) mu;  dphi_i: -tau.
      // dtau = dphi_j x tau + Q D dtheta, D = d(T^-T mu)/dtheta.
      const Vec3 mu = lambda.head<3>();
      const Vec3 theta = logSO3(f.P.transpose() * f.Q);
      const Mat3 Tinv = tangentSO3Inverse(theta);
      const Vec3 tau = f.Q * (Tinv.transpose() * mu);
      const Mat3 E = f.Q * tangentSO3InverseDerivative(theta, mu, true) * Tinv * f.Q.transpose();
      K.block<3, 3>(kPhiJ, kPhiJ) += E - skew(tau);
      K.block<3, 3>(kPhiJ, kPhiI) -= E;
      K.block<3, 3>(kPhiI, kPhiJ) += skew(tau) - E;
      K.block<3, 3>(kPhiI, kPhiI) += E;
      break;
    }
  }
}

void requireMultipliers(JointType type, Eigen::Index size) {
  if (size != constraintCount(type)) {
    throw std::invalid_argument("joint constraint: expected " + std::to_string(constraintCount(type)) +
                                " multipliers (one per row), got " + std::to_string(size));
  }
}

}  // namespace

int constraintCount(JointType type) {
  const RowLayout layout = rowLayout(type);
  int m = 0;
  for (int b = 0; b < layout.count; ++b) m += rowsOf(layout.blocks[b]);
  return m;
}

ConstraintEvaluation evaluateJointConstraint(const JointConstraint& joint, const BodyPose& parent,
                                             const BodyPose& child) {
  const int m = constraintCount(joint.type);
  ConstraintEvaluation out;
  out.phi = ConstraintVector::Zero(m);
  out.jacobianParent = ConstraintJacobian::Zero(m, 6);
  out.jacobianChild = ConstraintJacobian::Zero(m, 6);
  const MarkerFrames f = markerFrames(joint, parent, child);
  const RowLayout layout = rowLayout(joint.type);
  for (int b = 0, row = 0; b < layout.count; row += rowsOf(layout.blocks[b]), ++b) {
    evaluateBlock(layout.blocks[b], f, row, out);
  }
  return out;
}

GeometricStiffness constraintGeometricStiffness(const JointConstraint& joint, const BodyPose& parent,
                                                const BodyPose& child,
                                                const Eigen::Ref<const Eigen::VectorXd>& lambda) {
  requireMultipliers(joint.type, lambda.size());
  GeometricStiffness K = GeometricStiffness::Zero();
  const MarkerFrames f = markerFrames(joint, parent, child);
  const RowLayout layout = rowLayout(joint.type);
  for (int b = 0, row = 0; b < layout.count; row += rowsOf(layout.blocks[b]), ++b) {
    addBlockStiffness(layout.blocks[b], f, lambda.segment(row, rowsOf(layout.blocks[b])), K);
  }
  return K;
}

ConstraintVector constraintAccelerationTerm(const JointConstraint& joint, const BodyPose& parent,
                                            const BodyTwist& parentTwist, const BodyPose& child,
                                            const BodyTwist& childTwist) {
  // d/dt (Phi_z zdot) = Phi_z zddot + (dPhi_z/dz zdot) zdot, and row k of the
  // last term is zdot^T K(e_k) zdot (K with unit multiplier k).
  Eigen::Matrix<double, 12, 1> zdot;
  zdot << parentTwist.v, parentTwist.omega, childTwist.v, childTwist.omega;
  const int m = constraintCount(joint.type);
  ConstraintVector gamma = ConstraintVector::Zero(m);
  const MarkerFrames f = markerFrames(joint, parent, child);
  const RowLayout layout = rowLayout(joint.type);
  for (int b = 0, row = 0; b < layout.count; row += rowsOf(layout.blocks[b]), ++b) {
    const int rows = rowsOf(layout.blocks[b]);
    for (int k = 0; k < rows; ++k) {
      GeometricStiffness K = GeometricStiffness::Zero();
      addBlockStiffness(layout.blocks[b], f, Eigen::VectorXd::Unit(rows, k), K);
      gamma[row + k] = zdot.dot(K * zdot);
    }
  }
  return gamma;
}

JointReaction constraintReaction(const JointConstraint& joint, const BodyPose& parent, const BodyPose& child,
                                 const Eigen::Ref<const Eigen::VectorXd>& lambda) {
  requireMultipliers(joint.type, lambda.size());
  JointReaction reaction;
  if (lambda.size() == 0) return reaction;
  const ConstraintEvaluation ev = evaluateJointConstraint(joint, parent, child);
  const Eigen::Matrix<double, 6, 1> onChild = -ev.jacobianChild.transpose() * lambda;
  const Vec3 force = onChild.head<3>();
  const Vec3 childArm = child.A * joint.childMarker.position;
  // Moment about c = r_j + childArm: N_c = N_rj - childArm x F.
  const Vec3 torque = onChild.tail<3>() - childArm.cross(force);
  const Mat3 Q = child.A * joint.childMarker.orientation;
  reaction.force = Q.transpose() * force;
  reaction.torque = Q.transpose() * torque;
  return reaction;
}

}  // namespace mfbd
