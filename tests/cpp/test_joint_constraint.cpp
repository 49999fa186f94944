// Joint constraints in absolute form (coupling/joint_constraint.hpp) against
// the relative-coordinate joint library (rigid/joint_motion.hpp) and against
// finite differences over the pose manifold (r + dr, expSO3(dphi) A).
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "coupling/joint_constraint.hpp"
#include "model/model.hpp"
#include "rigid/joint_motion.hpp"
#include "scene/joint_dofs.hpp"

using namespace mfbd;

namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using MatX12 = Eigen::Matrix<double, Eigen::Dynamic, 12>;

constexpr std::array<JointType, 8> kAllTypes = {JointType::Revolute,  JointType::Prismatic, JointType::Cylindrical,
                                                JointType::Universal, JointType::Spherical, JointType::Planar,
                                                JointType::Fixed,     JointType::Free};

const char* name(JointType type) {
  constexpr const char* names[] = {"revolute", "prismatic", "cylindrical", "universal",
                                   "spherical", "planar",   "fixed",       "free"};
  return names[static_cast<int>(type)];
}

Vec3 randomVector(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return Vec3(u(rng), u(rng), u(rng)) * scale;
}

// A rotation by up to `maxAngle` about a random axis.
Mat3 randomRotation(std::mt19937& rng, double maxAngle) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  return expSO3(randomVector(rng, 1.0).normalized() * maxAngle * u(rng));
}

Eigen::VectorXd randomVectorX(std::mt19937& rng, int size, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Eigen::VectorXd x(size);
  for (int i = 0; i < size; ++i) x[i] = u(rng);
  return x;
}

BodyPose moved(const BodyPose& b, const Vec6& dz) { return {b.r + dz.head<3>(), expSO3(dz.tail<3>()) * b.A}; }

// A joint with random markers, a parent in a random pose, the child placed by
// the joint library at random coordinates (|q| <= qScale), as the recursive
// kinematics does: A_C = A_P R(q), c = p + A_P d(q).
struct JointCase {
  JointConstraint joint;
  BodyPose parent, child;
  JointMotion motion;  // R, d, Hv (P frame), Hw (C frame) at q
};

JointCase onManifold(JointType type, std::mt19937& rng, double qScale, double markerOffset = 0.5,
                 bool groundParent = false) {
  JointCase s;
  s.joint.type = type;
  s.joint.parentMarker = {randomVector(rng, markerOffset), randomRotation(rng, 3.0)};
  s.joint.childMarker = {randomVector(rng, markerOffset), randomRotation(rng, 3.0)};
  if (!groundParent) s.parent = {randomVector(rng, 2.0), randomRotation(rng, 3.0)};
  Joint joint;
  joint.type = type;
  joint.dofs = static_cast<int>(jointDofs(type));
  joint.scalarOffset = 0;
  joint.rotation = 0;
  Configuration q;
  q.scalars = randomVectorX(rng, 6, qScale);
  q.rotations = {expSO3(randomVector(rng, qScale))};
  s.motion = jointMotion(joint, q, randomVectorX(rng, joint.dofs, 1.0));
  const Mat3 P = s.parent.A * s.joint.parentMarker.orientation;
  const Vec3 p = s.parent.r + s.parent.A * s.joint.parentMarker.position;
  const Mat3 Q = P * s.motion.rotation;
  const Vec3 c = p + P * s.motion.translation;
  s.child.A = Q * s.joint.childMarker.orientation.transpose();
  s.child.r = c - s.child.A * s.joint.childMarker.position;
  return s;
}

// Off the manifold: the child moved by a random relative motion.
void perturbChild(JointCase& s, std::mt19937& rng, double scale) {
  s.child.r += randomVector(rng, 0.3 * scale);
  s.child.A = randomRotation(rng, scale) * s.child.A;
}

MatX12 jacobian(const ConstraintEvaluation& ev) {
  MatX12 J(ev.phi.size(), 12);
  J << ev.jacobianParent, ev.jacobianChild;
  return J;
}

// d phi along each of the 12 pose variations, central differences.
MatX12 jacobianByDifferences(const JointCase& s, double h) {
  const int m = constraintCount(s.joint.type);
  MatX12 J(m, 12);
  for (int b = 0; b < 12; ++b) {
    const Vec6 d = Vec6::Unit(b % 6) * h;
    const bool child = b >= 6;
    const auto phi = [&](const Vec6& dz) {
      return evaluateJointConstraint(s.joint, child ? s.parent : moved(s.parent, dz),
                                     child ? moved(s.child, dz) : s.child).phi;
    };
    J.col(b) = (phi(d) - phi(-d)) / (2.0 * h);
  }
  return J;
}

// Singular values of an m x n matrix, m <= 6: those of J J^T are their squares.
Eigen::VectorXd singularValues(const Eigen::MatrixXd& J) {
  using Gram = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 6, 6>;
  const Gram JJt = J * J.transpose();
  return Eigen::JacobiSVD<Gram, Eigen::NoQRPreconditioner>(JJt).singularValues().cwiseSqrt();
}

std::string scientific(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2e", x);
  return text;
}

double relativeError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& reference) {
  if (reference.size() == 0) return 0.0;
  return (a - reference).cwiseAbs().maxCoeff() / std::max(1.0, reference.cwiseAbs().maxCoeff());
}

}  // namespace

TEST(JointConstraint, RowCountsAreSixMinusDofs) {
  for (JointType type : kAllTypes) {
    EXPECT_EQ(constraintCount(type), 6 - static_cast<int>(jointDofs(type))) << name(type);
  }
}

TEST(JointConstraint, JacobianMatchesFiniteDifferences) {
  std::mt19937 rng(11);
  for (JointType type : kAllTypes) {
    double worst = 0.0;
    for (int k = 0; k < 20; ++k) {
      JointCase s = onManifold(type, rng, 1.5);
      if (k % 2 == 1) perturbChild(s, rng, 0.6);  // half near, half on the manifold
      const MatX12 J = jacobian(evaluateJointConstraint(s.joint, s.parent, s.child));
      worst = std::max(worst, relativeError(J, jacobianByDifferences(s, 1e-6)));
    }
    EXPECT_LT(worst, 1e-7) << name(type);
    RecordProperty(std::string("jacobian_error_") + name(type), scientific(worst));
  }
}

TEST(JointConstraint, VanishesOnPermittedMotionOnly) {
  // Elementary relative motions in C's frame (translations, then rotations)
  // that each joint forbids at any coordinates (universal: about C's z, the
  // cross axis, moves -p_x.q_y by cos(b) >= 0.5 here).
  const auto forbidden = [](JointType type) -> std::vector<int> {
    switch (type) {
      case JointType::Revolute: return {0, 1, 2, 3, 4};
      case JointType::Prismatic: return {0, 1, 3, 4, 5};
      case JointType::Cylindrical: return {0, 1, 3, 4};
      case JointType::Universal: return {0, 1, 2, 5};
      case JointType::Spherical: return {0, 1, 2};
      case JointType::Planar: return {2, 3, 4};
      case JointType::Fixed: return {0, 1, 2, 3, 4, 5};
      case JointType::Free: return {};
    }
    return {};
  };
  std::mt19937 rng(12);
  const double step = 1e-3;
  for (JointType type : kAllTypes) {
    for (int k = 0; k < 20; ++k) {
      const JointCase s = onManifold(type, rng, 1.0);
      const auto phi = evaluateJointConstraint(s.joint, s.parent, s.child).phi;
      EXPECT_LT(phi.size() ? phi.cwiseAbs().maxCoeff() : 0.0, 1e-12) << name(type);
      const Mat3 Q = s.child.A * s.joint.childMarker.orientation;
      const Vec3 c = s.child.r + s.child.A * s.joint.childMarker.position;
      for (int motion : forbidden(type)) {
        BodyPose child = s.child;
        if (motion < 3) {
          child.r += Q.col(motion) * step;
        } else {  // turn about C's axis, C's origin kept
          child.A = expSO3(Q.col(motion - 3) * step) * child.A;
          child.r = c - child.A * s.joint.childMarker.position;
        }
        EXPECT_GT(evaluateJointConstraint(s.joint, s.parent, child).phi.norm(), 0.4 * step)
            << name(type) << " motion " << motion;
      }
    }
  }
}

TEST(JointConstraint, FullRowRankAtDesignConfiguration) {
  std::mt19937 rng(13);
  for (JointType type : kAllTypes) {
    if (constraintCount(type) == 0) continue;
    // Markers at the body origins: Phi_j's rows are orthonormal (singular
    // values all 1), the rows' scaling is consistent.
    const JointCase centred = onManifold(type, rng, 0.0, 0.0);
    const auto evCentred = evaluateJointConstraint(centred.joint, centred.parent, centred.child);
    EXPECT_LT((singularValues(evCentred.jacobianChild).array() - 1.0).abs().maxCoeff(), 1e-12) << name(type);
    // Offset markers: [Phi_i Phi_j] and Phi_j keep full row rank.
    double smallest = 1.0;
    for (int k = 0; k < 20; ++k) {
      const JointCase s = onManifold(type, rng, 0.0);
      const auto ev = evaluateJointConstraint(s.joint, s.parent, s.child);
      const double both = singularValues(jacobian(ev)).minCoeff();
      const double child = singularValues(ev.jacobianChild).minCoeff();
      EXPECT_GT(both, 1.0) << name(type);  // at least sqrt(2) x that of Phi_j
      EXPECT_GT(child, 0.4) << name(type);
      smallest = std::min(smallest, child);
    }
    RecordProperty(std::string("smallest_singular_value_") + name(type), scientific(smallest));
  }
}

TEST(JointConstraint, AnnihilatesTheJointsFreeDirections) {
  std::mt19937 rng(14);
  for (JointType type : kAllTypes) {
    if (constraintCount(type) == 0) continue;
    for (int k = 0; k < 20; ++k) {
      const JointCase s = onManifold(type, rng, 1.5);
      const auto ev = evaluateJointConstraint(s.joint, s.parent, s.child);
      const Mat3 P = s.parent.A * s.joint.parentMarker.orientation;
      const Mat3 Q = s.child.A * s.joint.childMarker.orientation;
      const Vec3 childArm = s.child.A * s.joint.childMarker.position;
      // Each joint rate, parent at rest: C's origin moves by P Hv, turns by Q Hw.
      for (int dof = 0; dof < s.motion.Hv.cols(); ++dof) {
        const Vec3 omega = Q * s.motion.Hw.col(dof);
        const Vec3 v = P * s.motion.Hv.col(dof) - omega.cross(childArm);
        Vec6 twist;
        twist << v, omega;
        EXPECT_LT((ev.jacobianChild * twist).cwiseAbs().maxCoeff(), 1e-12) << name(type) << " dof " << dof;
      }
      // A rigid motion of both bodies together leaves every row unchanged,
      // on the manifold or off it.
      JointCase off = s;
      perturbChild(off, rng, 0.5);
      const auto evOff = evaluateJointConstraint(off.joint, off.parent, off.child);
      const Vec3 V = randomVector(rng, 1.0), W = randomVector(rng, 1.0);
      Vec12 zdot;
      zdot << V + W.cross(off.parent.r), W, V + W.cross(off.child.r), W;
      EXPECT_LT((jacobian(evOff) * zdot).cwiseAbs().maxCoeff(), 1e-12) << name(type);
    }
  }
}

TEST(JointConstraint, AccelerationTermMatchesFiniteDifferences) {
  // Each body on r(t) = r0 + v0 t + a0 t^2/2, A(t) = expSO3(psi(t)) A0 with
  // psi = w0 t + alpha0 t^2/2; world omega = exp(psi) T(psi) psidot, so at
  // t = 0 the velocity is (v0, w0) and the acceleration (a0, alpha0).
  struct Trajectory {
    BodyPose start;
    Vec3 v0, a0, w0, alpha0;
    BodyPose pose(double t) const {
      return {start.r + v0 * t + 0.5 * a0 * t * t, expSO3(w0 * t + 0.5 * alpha0 * t * t) * start.A};
    }
    Vec6 twist(double t) const {
      const Vec3 psi = w0 * t + 0.5 * alpha0 * t * t, psidot = w0 + alpha0 * t;
      Vec6 z;
      z << v0 + a0 * t, expSO3(psi) * tangentSO3(psi) * psidot;
      return z;
    }
  };
  std::mt19937 rng(15);
  const double h = 1e-5;
  for (JointType type : kAllTypes) {
    if (constraintCount(type) == 0) continue;
    double worst = 0.0;
    for (int k = 0; k < 20; ++k) {
      JointCase s = onManifold(type, rng, 1.5);
      if (k % 2 == 1) perturbChild(s, rng, 0.5);
      const auto randomTrajectory = [&](const BodyPose& start) {
        return Trajectory{start, randomVector(rng, 1.0), randomVector(rng, 1.0), randomVector(rng, 2.0),
                          randomVector(rng, 2.0)};
      };
      const Trajectory parent = randomTrajectory(s.parent), child = randomTrajectory(s.child);
      const auto constraintVelocity = [&](double t) {
        const auto ev = evaluateJointConstraint(s.joint, parent.pose(t), child.pose(t));
        return ConstraintVector(ev.jacobianParent * parent.twist(t) + ev.jacobianChild * child.twist(t));
      };
      const ConstraintVector reference = (constraintVelocity(h) - constraintVelocity(-h)) / (2.0 * h);
      const auto ev = evaluateJointConstraint(s.joint, s.parent, s.child);
      Vec6 parentAcceleration, childAcceleration;
      parentAcceleration << parent.a0, parent.alpha0;
      childAcceleration << child.a0, child.alpha0;
      const ConstraintVector gamma = constraintAccelerationTerm(
          s.joint, s.parent, {parent.v0, parent.w0}, s.child, {child.v0, child.w0});
      const ConstraintVector predicted =
          ev.jacobianParent * parentAcceleration + ev.jacobianChild * childAcceleration + gamma;
      worst = std::max(worst, relativeError(predicted, reference));
    }
    EXPECT_LT(worst, 1e-7) << name(type);
    RecordProperty(std::string("gamma_error_") + name(type), scientific(worst));
  }
}

namespace {
// Phi_z^T lambda as a 12-vector.
Vec12 generalizedConstraintForce(const JointConstraint& joint, const BodyPose& parent, const BodyPose& child,
                                 const Eigen::VectorXd& lambda) {
  return jacobian(evaluateJointConstraint(joint, parent, child)).transpose() * lambda;
}

double stiffnessError(const JointCase& s, const Eigen::VectorXd& lambda, double h) {
  const GeometricStiffness K = constraintGeometricStiffness(s.joint, s.parent, s.child, lambda);
  GeometricStiffness reference;
  for (int b = 0; b < 12; ++b) {
    const Vec6 d = Vec6::Unit(b % 6) * h;
    const bool child = b >= 6;
    const auto force = [&](const Vec6& dz) {
      return generalizedConstraintForce(s.joint, child ? s.parent : moved(s.parent, dz),
                                        child ? moved(s.child, dz) : s.child, lambda);
    };
    reference.col(b) = (force(d) - force(-d)) / (2.0 * h);
  }
  return relativeError(K, reference);
}
}  // namespace

TEST(JointConstraint, GeometricStiffnessMatchesFiniteDifferences) {
  std::mt19937 rng(16);
  for (JointType type : kAllTypes) {
    double worst = 0.0;
    for (int k = 0; k < 20; ++k) {
      JointCase s = onManifold(type, rng, 1.5);
      if (k % 2 == 1) perturbChild(s, rng, 0.6);
      const Eigen::VectorXd lambda = randomVectorX(rng, constraintCount(type), 10.0);
      worst = std::max(worst, stiffnessError(s, lambda, 1e-6));
    }
    EXPECT_LT(worst, 1e-7) << name(type);
    RecordProperty(std::string("stiffness_error_") + name(type), scientific(worst));
  }
}

TEST(JointConstraint, RotationLockStiffnessAtEveryAngle) {
  // The log map's tangent switches from series to closed form at 0.3 rad.
  std::mt19937 rng(17);
  for (double angle : {0.0, 1e-8, 1e-3, 0.2999, 0.3001, 1.0, 2.5}) {
    JointCase s = onManifold(JointType::Fixed, rng, 0.0);
    const Vec3 axis = randomVector(rng, 1.0).normalized();
    const Vec3 c = s.child.r + s.child.A * s.joint.childMarker.position;
    s.child.A = expSO3(axis * angle) * s.child.A;  // turn about C's origin
    s.child.r = c - s.child.A * s.joint.childMarker.position;
    const auto ev = evaluateJointConstraint(s.joint, s.parent, s.child);
    EXPECT_NEAR(ev.phi.tail<3>().norm(), angle, 1e-12);
    const Eigen::VectorXd lambda = randomVectorX(rng, 6, 10.0);
    EXPECT_LT(stiffnessError(s, lambda, 1e-6), 1e-7) << "angle " << angle;
    EXPECT_LT(relativeError(jacobian(ev), jacobianByDifferences(s, 1e-6)), 1e-7) << "angle " << angle;
  }
}

TEST(JointConstraint, FixedJointCarriesTheWeight) {
  // A body of mass m, reference point at its centre of mass, welded to ground:
  // statics -Phi_j^T lambda + [m g; 0] = 0, so the joint pushes with -m g.
  std::mt19937 rng(18);
  const double mass = 2.5;
  const Vec3 gravity(0.0, 0.0, -9.81);
  for (int k = 0; k < 10; ++k) {
    const JointCase s = onManifold(JointType::Fixed, rng, 0.0, 1.0, /*groundParent=*/true);
    const auto ev = evaluateJointConstraint(s.joint, s.parent, s.child);
    Vec6 applied;
    applied << mass * gravity, Vec3::Zero();
    const Eigen::VectorXd lambda = Eigen::MatrixXd(ev.jacobianChild.transpose()).partialPivLu().solve(applied);
    const JointReaction reaction = constraintReaction(s.joint, s.parent, s.child, lambda);
    const Mat3 Q = s.child.A * s.joint.childMarker.orientation;
    const Vec3 childArm = s.child.A * s.joint.childMarker.position;
    EXPECT_LT((Q * reaction.force - Vec3(0.0, 0.0, mass * 9.81)).norm(), 1e-12);
    EXPECT_NEAR(reaction.force.norm(), mass * 9.81, 1e-12);
    // Moment about C's origin of the upward force acting at the centre of mass.
    EXPECT_LT((Q * reaction.torque - (-childArm).cross(-mass * gravity)).norm(), 1e-12);
  }
}

TEST(JointConstraint, ReactionDoesNoWorkOnPermittedMotion) {
  // Whatever lambda, a revolute passes no torque about its axis, a prismatic
  // no force along it, a spherical no torque about its centre (C's frame).
  std::mt19937 rng(19);
  for (int k = 0; k < 10; ++k) {
    const auto reaction = [&](JointType type) {
      const JointCase s = onManifold(type, rng, 1.5);
      const Eigen::VectorXd lambda = randomVectorX(rng, constraintCount(type), 100.0);
      return constraintReaction(s.joint, s.parent, s.child, lambda);
    };
    const JointReaction revolute = reaction(JointType::Revolute);
    EXPECT_GT(revolute.torque.head<2>().norm(), 1.0);
    EXPECT_LT(std::abs(revolute.torque.z()), 1e-12);
    const JointReaction prismatic = reaction(JointType::Prismatic);
    EXPECT_GT(prismatic.force.head<2>().norm(), 1.0);
    EXPECT_LT(std::abs(prismatic.force.z()), 1e-12);
    const JointReaction spherical = reaction(JointType::Spherical);
    EXPECT_GT(spherical.force.norm(), 1.0);
    EXPECT_LT(spherical.torque.norm(), 1e-12);
    const JointReaction free = reaction(JointType::Free);
    EXPECT_EQ(free.force.norm() + free.torque.norm(), 0.0);
  }
}

TEST(JointConstraint, WrongMultiplierCountIsRejected) {
  const JointConstraint joint{JointType::Revolute, {}, {}};
  EXPECT_THROW(constraintReaction(joint, {}, {}, Eigen::VectorXd::Zero(6)), std::invalid_argument);
  EXPECT_THROW(constraintGeometricStiffness(joint, {}, {}, Eigen::VectorXd::Zero(4)), std::invalid_argument);
}
