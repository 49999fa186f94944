#include "model/configuration.hpp"

namespace mfbd {

void retractBlock(const CoordinateBlock& b, Configuration& q, const Eigen::Ref<const VectorXd>& dq) {
  if (b.rotation >= 0) {
    Mat3& R = q.rotations[b.rotation];
    R = R * expSO3(dq.head<3>());
  } else {
    q.scalars.segment(b.scalarOffset, b.size) += dq;
  }
}

void retract(const std::vector<CoordinateBlock>& blocks, Configuration& q, const VectorXd& dq) {
  for (const CoordinateBlock& b : blocks) retractBlock(b, q, dq.segment(b.velocityOffset, b.size));
}

void restoreOrthogonality(Configuration& q) {
  for (Mat3& R : q.rotations) R = polarStep(R);
}

}  // namespace mfbd
