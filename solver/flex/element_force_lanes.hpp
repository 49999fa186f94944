// The residual's element forces, four elements at a time in vector lanes
// (math/lanes.hpp): the internal force plus, for an element with mass > 0,
// its consistent inertia less weight, the kernel of flex/corotational_force.hpp
// compiled for T = Lanes, for the baseline x86-64 and for AVX2, the variant
// for this processor chosen at run time.
#pragma once
#include "flex/corotational_beam.hpp"

namespace mfbd {

constexpr int kForceLanes = 4;  // elements per call

struct ElementInputs {
  const CorotationalBeam* beam;
  double damping, mass;
  const NodePose *pose1, *pose2;
  const NodeVelocity *velocity1, *velocity2;
  const NodeAcceleration *acceleration1, *acceleration2;  // read only where mass > 0
};

// f[i] for count <= kForceLanes elements: internalForceVector's f plus, for
// mass > 0, consistentInertiaForce (flex/consistent_mass.hpp). False if any
// element's frame is undefined or a force not finite.
bool elementForceVectors(int count, const ElementInputs elements[], const Vec3& gravity, Vec12 f[]);

// For the test that both variants give the same numbers: the baseline
// variant itself, and whether elementForceVectors takes the AVX2 one.
bool elementForceVectorsBaseline(int count, const ElementInputs elements[], const Vec3& gravity, Vec12 f[]);
bool hasAvx2();

}  // namespace mfbd
