// A scene whose rigid tree has a motion that moves no mass and that no
// constraint holds cannot start: the mass matrix at the initial
// configuration is singular. Checked right after assembly, when a
// Simulation is built (it needs the tree's recursions, so not in
// assemble()); the packer, fmi2Instantiate and fmi2SetReal of a user
// parameter all build one, so they refuse such a scene with the joint's
// JSON path instead of failing at initialization.
#pragma once
#include "model/model.hpp"

namespace mfbd {

// Throws SceneError naming the joint (joints[i]) whose rates make such a
// motion and its child body. Dynamics only (statics has no mass matrix).
void checkMassMatrix(const Scene& scene, const Model& model);

}  // namespace mfbd
