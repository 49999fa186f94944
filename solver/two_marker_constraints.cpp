// The list of two-marker constraints of a Model (two_marker_constraints.hpp):
// cut joints, then flexible body joints, each with its two sides and rows.
// A new constraint kind between two markers enters the System here.
#include "two_marker_constraints.hpp"

namespace mfbd {

std::vector<TwoMarkerConstraint> twoMarkerConstraints(const Model& model) {
  std::vector<TwoMarkerConstraint> list;
  for (const Joint& j : model.joints) {
    if (!j.cut) continue;
    TwoMarkerConstraint c;
    c.joint = {j.type, {j.parentMarker.position, j.parentMarker.orientation},
               {j.childMarker.position, j.childMarker.orientation}};
    c.parent.body = j.parentMarker.body;
    c.child.body = j.childMarker.body;
    c.firstRow = j.constraintOffset;
    c.rows = constraintCount(j.type);
    list.push_back(c);
  }
  // The node is the parent side, the virtual body the child.
  for (const FlexibleBodyJoint& w : model.flexibleBodyJoints) {
    TwoMarkerConstraint c;
    c.joint = w.joint;
    c.parent.node = w.node;
    c.child.body = w.virtualBody;
    c.firstRow = w.constraintOffset;
    c.rows = constraintCount(w.joint.type);
    list.push_back(c);
  }
  return list;
}

}  // namespace mfbd
