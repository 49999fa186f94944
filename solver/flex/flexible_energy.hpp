// Energies of a flexible body, for outputs (energy balance is how a user
// checks a conservative run): kinetic 1/2 v^T M v of its nodal inertia and
// consistent element mass,
// strain 1/2 e_l^T K_l e_l of its elements' local deformations (the
// potential whose gradient is the elastic internal force), and the
// potential of gravity -m g . r of its nodal and element masses.
#pragma once
#include "flex/flexible_mesh.hpp"

namespace mfbd {

struct FlexibleEnergy {
  double kinetic = 0.0, strain = 0.0, gravity = 0.0;
};

FlexibleEnergy flexibleBodyEnergy(const FlexibleMesh& mesh, const FlexibleBody& body,
                                  const std::vector<NodeState>& nodes, const Vec3& gravity);

}  // namespace mfbd
