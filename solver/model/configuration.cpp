#include "model/configuration.hpp"

namespace mfbd {

void retract(const std::vector<CoordinateBlock>& blocks, Configuration& q, const VectorXd& dq) {
  for (const CoordinateBlock& b : blocks) {
    if (b.rotation >= 0) {
      Mat3& R = q.rotations[b.rotation];
      R = rotateIncrementally(R, dq.segment<3>(b.velocityOffset));
    } else {
      q.scalars.segment(b.scalarOffset, b.size) += dq.segment(b.velocityOffset, b.size);
    }
  }
}

}  // namespace mfbd
