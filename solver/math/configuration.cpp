#include "math/configuration.hpp"

namespace mfbd {

namespace {
// Block b of q <- b o exp(dq), dq pointing at the block's own rates.
inline void retractAt(const CoordinateBlock& b, Configuration& q, const double* dq) {
  if (b.rotation >= 0) {
    Mat3& R = q.rotations[b.rotation];
    R = R * expSO3(Vec3(dq[0], dq[1], dq[2]));
  } else {
    double* x = q.scalars.data() + b.scalarOffset;
    for (int i = 0; i < b.size; ++i) x[i] += dq[i];
  }
}
}  // namespace

void retractBlock(const CoordinateBlock& b, Configuration& q, const Eigen::Ref<const VectorXd>& dq) {
  retractAt(b, q, dq.data());
}

void retract(const std::vector<CoordinateBlock>& blocks, Configuration& q, const VectorXd& dq) {
  for (const CoordinateBlock& b : blocks) retractAt(b, q, dq.data() + b.velocityOffset);
}

void chartRate(const std::vector<CoordinateBlock>& blocks, const VectorXd& delta, const VectorXd& v, VectorXd& rate) {
  rate = v;
  for (const CoordinateBlock& b : blocks) {
    if (b.rotation < 0) continue;
    const int k = b.velocityOffset;
    rate.segment<3>(k) = tangentSO3Inverse(delta.segment<3>(k)) * v.segment<3>(k);
  }
}

void restoreOrthogonality(Configuration& q) {
  for (Mat3& R : q.rotations) R = polarStep(R);
}

}  // namespace mfbd
