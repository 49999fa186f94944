// What is provably singular, and only that: a motion x of the joint rates
// that moves no mass (x^T M x = 0 for the joint-space mass matrix
// M = B^T M_body B, positive semi-definite, so M x = 0), moves no body that
// a cut joint or a flexible body joint holds, and no driven coordinate.
// Then [x; 0] is a null vector of [M Phi_q^T; Phi_q 0], the matrix the
// integrator factors at the start: every constraint row reads only the
// motion of the bodies it holds (or a driven rate), and flexible nodes do
// not move in x (their own mass is not checked here). A massless motion
// that a constraint touches is left to the solver, since the constraint may
// hold it: the massless slider of flexible_slider_crank is legitimate.
#include "rigid/mass_check.hpp"

#include <algorithm>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "math/number_text.hpp"
#include "model/data.hpp"
#include "rigid/recursive_dynamics.hpp"

namespace mfbd {

namespace {

// Motions the constraints see: rows of B for the velocity and angular
// velocity of every body a cut joint or flexible body joint holds, and a
// unit row per driven rate.
Eigen::MatrixXd heldMotions(const Model& model, const Data& data) {
  std::vector<int> bodies;
  for (const Joint& j : model.joints)
    if (j.cut) bodies.insert(bodies.end(), {j.parentMarker.body, j.childMarker.body});
  for (const FlexibleBodyJoint& w : model.flexibleBodyJoints) bodies.push_back(w.virtualBody);
  bodies.erase(std::remove(bodies.begin(), bodies.end(), kGroundIndex), bodies.end());
  int drives = 0;
  for (const Joint& j : model.joints) drives += j.driven;
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(6 * bodies.size() + drives, model.rigidVelocityCount);
  int row = 0;
  for (int b : bodies) {
    C.middleRows<6>(row) = data.velocityTransformation.middleRows<6>(6 * b);
    row += 6;
  }
  for (const Joint& j : model.joints)
    if (j.driven) C(row++, j.velocityOffset) = 1.0;
  return C;
}

// A motion in null(M) and null(C), in rates scaled by their own mass (so
// that kg and kg m^2 compare): empty if there is none. G = D M D + Cn^T Cn
// (Cn: the rows of C D, each of unit length) is positive semi-definite, and
// its null space is null(D M D) and null(C D) together. Cholesky from the
// last rate to the first (leaves before their parents, as the articulated-
// body recursion goes) makes each pivot the mass a joint's motion moves
// with the joints outboard of it free, against its diagonal entry (the mass
// it moves with them locked): a null space leaves a pivot of round-off size
// (1e-16), while legitimate trees stay far above 1e-12: the examples at
// 0.13 and more; the first joint of an n-link chain of bars at 1.9/n^3
// (1.9e-9 for 1000 links, 7e-11 for 3000). The eigenvector of G's smallest
// eigenvalue is the motion.
VectorXd masslessFreeMotion(const Eigen::MatrixXd& M, const Eigen::MatrixXd& C) {
  const int n = int(M.rows());
  VectorXd d(n);
  for (int k = 0; k < n; ++k) d[k] = M(k, k) > 0.0 ? 1.0 / std::sqrt(M(k, k)) : 1.0;
  Eigen::MatrixXd G = d.asDiagonal() * M * d.asDiagonal();
  Eigen::MatrixXd Cn = C * d.asDiagonal();
  for (int r = 0; r < Cn.rows(); ++r)
    if (const double norm = Cn.row(r).norm(); norm > 0.0) Cn.row(r) /= norm;
  G.noalias() += Cn.transpose() * Cn;
  const Eigen::MatrixXd leavesFirst = G.reverse();
  const Eigen::LLT<Eigen::MatrixXd> cholesky(leavesFirst);
  const VectorXd pivots = cholesky.matrixLLT().diagonal().array().square();
  if (cholesky.info() == Eigen::Success && (pivots.array() > 1e-12 * leavesFirst.diagonal().array()).all())
    return VectorXd();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(G);
  return d.asDiagonal() * eigen.eigenvectors().col(0);
}

// The error for motion x: the joint nearest ground among those whose rates
// take part (the others named beside it), its child body and what that
// body carries.
SceneError singularMotion(const Scene& scene, const Model& model, const Data& data, const VectorXd& x) {
  std::vector<int> children;  // bodies in tree order (parent first) whose inboard joint takes part
  for (int i = 0; i < int(model.bodies.size()); ++i) {
    const Joint& j = model.joints[model.bodies[i].inboardJoint];
    if (j.dofs > 0 && x.segment(j.velocityOffset, j.dofs).cwiseAbs().maxCoeff() > 0.1 * x.cwiseAbs().maxCoeff())
      children.push_back(i);
  }
  const int child = children.front();
  const int joint = model.bodies[child].inboardJoint;
  std::string others;
  for (std::size_t k = 1; k < std::min<std::size_t>(children.size(), 4); ++k)
    others += std::string(k == 1 ? " (together with " : ", ") + "'" +
              model.joints[model.bodies[children[k]].inboardJoint].name + "'";
  if (children.size() > 4) others += " and " + std::to_string(children.size() - 4) + " more";
  if (!others.empty()) others += ")";
  std::string jointPath = "joints", bodyPath = "bodies";
  for (std::size_t i = 0; i < scene.joints.size(); ++i)
    if (scene.joints[i].name == model.joints[joint].name) jointPath = "joints[" + std::to_string(i) + "]";
  for (std::size_t i = 0; i < scene.bodies.size(); ++i)
    if (scene.bodies[i].name == model.bodies[child].name) bodyPath = "bodies[" + std::to_string(i) + "]";
  const Body& body = model.bodies[child];
  const Vec3 moments = Eigen::SelfAdjointEigenSolver<Mat3>(body.inertia, Eigen::EigenvaluesOnly).eigenvalues();
  const double reach = data.joint[joint].childMarkerOffset.norm();
  return SceneError(jointPath, "the mass matrix is singular at the initial configuration: joint '" +
                                   model.joints[joint].name + "'" + others +
                                   " can move with no mass or rotary inertia moving; its child '" + body.name +
                                   "' (" + bodyPath + ") has mass " + numberText(body.mass) +
                                   ", principal moments " + vectorText(moments) + " and its centre of mass " +
                                   numberText(reach) + " m from the joint; expected mass or inertia that the "
                                   "joint's motion moves, or a drive or cut joint that holds it");
}

}  // namespace

void checkMassMatrix(const Scene& scene, const Model& model) {
  if (model.analysis == Analysis::Static || model.rigidVelocityCount == 0) return;
  Data data(model);
  const VectorXd rest = VectorXd::Zero(model.velocityCount);
  forwardKinematics(model, data, model.initialConfiguration, rest, rest);
  computeVelocityTransformation(model, data);
  Eigen::MatrixXd mass;
  jointSpaceMassMatrix(model, data, mass);
  const VectorXd x = masslessFreeMotion(mass, heldMotions(model, data));
  if (x.size() > 0) throw singularMotion(scene, model, data, x);
}

}  // namespace mfbd
