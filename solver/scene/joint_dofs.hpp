#pragma once
#include <cstddef>

#include "scene/scene.hpp"

namespace mfbd {

// Degrees of freedom a joint leaves between its two bodies.
constexpr std::size_t jointDofs(JointType type) {
  switch (type) {
    case JointType::Revolute:
    case JointType::Prismatic: return 1;
    case JointType::Cylindrical:
    case JointType::Universal: return 2;
    case JointType::Spherical:
    case JointType::Planar: return 3;
    case JointType::Fixed: return 0;
    case JointType::Free: return 6;
  }
  return 0;
}

}  // namespace mfbd
