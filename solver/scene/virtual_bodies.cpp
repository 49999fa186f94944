// Virtual bodies (docs/design.md 3): wherever a joint or force element names a
// flexible node, parsing puts a massless rigid body at that marker and
// holds it to the node with a flexible body joint. The joint or force element
// then connects rigid bodies only, so it is written once, against markers,
// and works unchanged on rigid-rigid, rigid-flex and flex-flex pairs.
//
// A virtual body is the child of the joint that touches the node when the
// node is the joint's child end. Otherwise (the node is the parent end, the
// joint is cut, or a force element touches the node) nothing holds the body
// in the tree, and it gets a free joint to ground: its six massless DOFs are
// fixed by the six rows of its flexible body joint.
#include <sstream>

#include "scene/virtual_bodies.hpp"

namespace mfbd {

namespace {

struct ResolvedNode {
  int flexibleBody = 0;
  int node = 0;
  Vec3 position;
  Mat3 orientation;
};

ResolvedNode resolve(const Scene& scene, const NodeReference& ref) {
  for (int b = 0; b < int(scene.flexibleBodies.size()); ++b) {
    const FlexibleBodySpec& body = scene.flexibleBodies[b];
    if (body.name != ref.flexibleBody) continue;
    const int count = int(body.nodes.size());
    int node = ref.node;
    if (ref.at >= 0.0) {
      // The point at distance `at` along the line from node 0 to the last node.
      const Vec3 chord = body.nodes.back() - body.nodes.front();
      const double length = chord.norm(), tol = 1e-9 * std::max(1.0, length);
      const Vec3 point = body.nodes.front() + chord.normalized() * ref.at;
      node = -1;
      for (int i = 0; i < count && node < 0; ++i)
        if ((body.nodes[i] - point).norm() <= tol) node = i;
      if (ref.at > length + tol || node < 0) {
        std::ostringstream s;
        s << "no node of '" << body.name << "' lies at " << ref.at << " m from node 0 (length " << length
          << " m); choose an element count that puts a node there, or name a node";
        throw SceneError(ref.path + ".at", s.str());
      }
    }
    if (node >= count)
      throw SceneError(ref.path + ".node", "expected a node index in 0.." + std::to_string(count - 1) + " of '" +
                                               body.name + "', got " + std::to_string(node));
    return {b, node, body.nodes[node], body.nodeOrientations[node]};
  }
  throw SceneError(ref.path + ".flexible", "unknown flexible body \"" + ref.flexibleBody + "\"");
}

class VirtualBodyMaker {
 public:
  explicit VirtualBodyMaker(Scene& scene) : scene_(scene) {}

  // Makes the virtual body of `owner`'s end `end` at the given frame and
  // its flexible body joint; returns the body's name.
  std::string make(const std::string& owner, const std::string& end, const ResolvedNode& at, const Vec3& position,
                   const Mat3& orientation, bool needsFreeJoint) {
    BodySpec body;
    body.name = owner + "." + end + "_virtual_body";
    body.isVirtual = true;
    body.position = position;
    body.orientation = orientation;
    scene_.bodies.push_back(body);
    FlexibleBodyJointSpec joint;
    joint.name = owner + "." + end + "_flexible_body_joint";
    joint.virtualBody = body.name;
    joint.flexibleBody = at.flexibleBody;
    joint.node = at.node;
    scene_.flexibleBodyJoints.push_back(joint);
    if (needsFreeJoint) {
      JointSpec free;
      free.name = body.name + "_joint";
      free.type = JointType::Free;
      free.parent = kGround;
      free.child = body.name;
      free.position = position;
      free.isVirtual = true;
      scene_.joints.push_back(free);
    }
    std::ostringstream note;
    note << "virtual body '" << body.name << "' at node " << at.node << " of '"
         << scene_.flexibleBodies[at.flexibleBody].name << "', welded by flexible body joint '" << joint.name << "'";
    if ((position - at.position).norm() > 0.0) note << " (offset " << (position - at.position).norm() << " m)";
    scene_.notes.push_back(note.str());
    return body.name;
  }

 private:
  Scene& scene_;
};

}  // namespace

void makeVirtualBodies(Scene& scene) {
  VirtualBodyMaker maker(scene);
  const std::size_t userJoints = scene.joints.size();
  for (std::size_t i = 0; i < userJoints; ++i) {
    // Copy what is needed: make() may grow scene.joints.
    JointSpec j = scene.joints[i];
    if (!j.parentNode && !j.childNode) continue;
    std::optional<ResolvedNode> parent, child;
    if (j.parentNode) parent = resolve(scene, *j.parentNode);
    if (j.childNode) child = resolve(scene, *j.childNode);
    if (!j.positionGiven) j.position = parent ? parent->position : child->position;
    const Mat3& frame = j.frame;
    if (parent) j.parent = maker.make(j.name, "parent", *parent, j.position, frame, true);
    if (child) j.child = maker.make(j.name, "child", *child, j.position, frame, j.cut);
    j.parentNode.reset();
    j.childNode.reset();
    scene.joints[i] = j;
  }
  for (ForceSpec& f : scene.forces) {
    // A force element's virtual body takes the node's orientation, so that
    // "body frame" components on a node are in the node's frame.
    if (f.node1) {
      const ResolvedNode n = resolve(scene, *f.node1);
      const std::string end = f.kind == ForceSpec::Kind::AppliedForce ? "" : "1";
      f.body1 = maker.make(f.name, end.empty() ? "node" : end, n, f.point1, n.orientation, true);
      f.node1.reset();
    }
    if (f.node2) {
      const ResolvedNode n = resolve(scene, *f.node2);
      f.body2 = maker.make(f.name, "2", n, f.point2, n.orientation, true);
      f.node2.reset();
    }
  }
}

}  // namespace mfbd
