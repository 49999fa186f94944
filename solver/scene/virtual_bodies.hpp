// Virtual bodies (docs/design.md 3): the last step of parsing rewrites every
// joint or force-element end on a flexible node into a massless virtual body
// at that marker and a flexible body joint that holds it to the node, so
// that joints and force elements connect rigid bodies only.
#pragma once
#include "scene/scene.hpp"

namespace mfbd {

// Resolves each node reference (node index, or distance along the body) and
// adds the virtual bodies, their flexible body joints and, where nothing
// holds a virtual body in the tree, its free joint to ground; a note per
// virtual body. Throws SceneError naming the reference that matches no node.
void makeVirtualBodies(Scene& scene);

}  // namespace mfbd
