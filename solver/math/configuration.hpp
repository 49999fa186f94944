// The configuration manifold the integrator works on: a vector of scalar
// coordinates (joint angles and slides, node positions) and a list of stored
// rotations (spherical/free joints, flexible nodes). Velocities live in the
// tangent space; a rotation's velocity is its body-frame angular velocity.
#pragma once
#include <vector>

#include <Eigen/Core>

#include "math/rotation.hpp"

namespace mfbd {

using Eigen::VectorXd;

struct Configuration {
  VectorXd scalars;
  std::vector<Mat3> rotations;
  template <class Archive>
  void visitState(Archive& ar) {
    ar(scalars, rotations);
  }
};

// Where the velocity coordinates v[offset .. offset+size) act: on scalars
// (added) or on one stored rotation (R <- R expSO3(dv), size 3).
struct CoordinateBlock {
  int velocityOffset = 0;
  int size = 0;
  int scalarOffset = -1;  // scalar block
  int rotation = -1;      // rotation block
};

// q <- q o exp(dq): the exact exponential map on each rotation block.
// Newton iterates are retracted many times per step; the polar correction
// of round-off is left to restoreOrthogonality, once per accepted step.
void retract(const std::vector<CoordinateBlock>& blocks, Configuration& q, const VectorXd& dq);
// delta' along q0 o exp(delta(t)) with velocity v: T^-1(delta_b) v_b on
// each rotation block b (math/rotation.hpp: tangentSO3Inverse), v_b on
// scalar blocks.
void chartRate(const std::vector<CoordinateBlock>& blocks, const VectorXd& delta, const VectorXd& v, VectorXd& rate);
// One block of it: q's block b <- b o exp(dq), dq the block's own rates.
void retractBlock(const CoordinateBlock& b, Configuration& q, const Eigen::Ref<const VectorXd>& dq);
// Every stored rotation <- polarStep(rotation): keeps them orthogonal to
// round-off over any number of steps.
void restoreOrthogonality(Configuration& q);

}  // namespace mfbd
