// Energies of a flexible body, for outputs (energy balance is how a user
// checks a conservative run): kinetic 1/2 v^T M v of its nodal inertia and
// consistent element mass (flex/consistent_mass.hpp), strain energy of its
// elements' local deformations (localStrainEnergy: the potential whose
// gradient is the elastic internal force), and the potential of gravity
// -m g . r of its nodal and element masses.
#pragma once
#include "flex/flexible_mesh.hpp"

namespace mfbd {

struct FlexibleEnergy {
  double kinetic = 0.0, strain = 0.0, gravity = 0.0;
};

FlexibleEnergy flexibleBodyEnergy(const FlexibleMesh& mesh, const FlexibleBody& body,
                                  const std::vector<NodeState>& nodes, const Vec3& gravity);

}  // namespace mfbd
