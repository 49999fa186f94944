// The flexible body joint (docs/design.md 3): six rows that hold a virtual
// body to a flexible node, Phi^er = 0, written with the fixed joint of the
// joint library: the node is the parent (its marker: the virtual body's
// design frame, fixed in the node frame), the virtual body the child (its
// marker: its own frame). The multipliers are the force and torque passed
// between node and virtual body. The System treats it as one of its
// two-marker constraints (solver/two_marker_constraints.hpp), where a node
// side's variations are mapped.
#pragma once
#include <string>

#include "coupling/joint_constraint.hpp"

namespace mfbd {

struct FlexibleBodyJoint {
  std::string name;
  int virtualBody = -1;   // model body index
  int node = -1;          // mesh node index
  JointConstraint joint;  // fixed type, node -> virtual body
  int constraintOffset = -1;
};

}  // namespace mfbd
