// Scene -> Model: order bodies along the spanning tree from ground, place
// every joint's markers from its design-configuration frame, and lay out the
// coordinates (scalars, stored rotations) and velocities.
#include <deque>
#include <map>

#include "coupling/joint_constraint.hpp"
#include "model/model.hpp"
#include "scene/joint_dofs.hpp"

namespace mfbd {

namespace {

// Frame of a joint in the design configuration: origin at its position, z
// along its axis.
struct WorldFrame {
  Vec3 origin;
  Mat3 orientation;
};

Marker markerOn(int body, const WorldFrame& bodyFrame, const WorldFrame& jointFrame) {
  Marker m;
  m.body = body;
  m.position = bodyFrame.orientation.transpose() * (jointFrame.origin - bodyFrame.origin);
  m.orientation = bodyFrame.orientation.transpose() * jointFrame.orientation;
  return m;
}

// Bodies in breadth-first order from ground along tree joints: parent < child.
std::vector<int> treeOrder(const Scene& scene, std::map<std::string, int>& sceneBodyIndex) {
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) sceneBodyIndex[scene.bodies[i].name] = int(i);
  std::vector<int> order;
  std::deque<std::string> open = {kGround};
  while (!open.empty()) {
    const std::string at = open.front();
    open.pop_front();
    for (const JointSpec& j : scene.joints) {
      if (j.cut || j.parent != at) continue;
      order.push_back(sceneBodyIndex.at(j.child));
      open.push_back(j.child);
    }
  }
  return order;
}

void layOutCoordinates(Model& model, Joint& joint, const JointSpec& spec) {
  const bool storedRotation = spec.type == JointType::Spherical || spec.type == JointType::Free;
  const int scalarCount = joint.dofs - (storedRotation ? 3 : 0);
  joint.velocityOffset = model.velocityCount;
  VectorXd& x = model.initialConfiguration.scalars;
  std::vector<double> q0 = spec.initialCoordinates;
  q0.resize(joint.dofs, 0.0);
  if (scalarCount > 0) {
    joint.scalarOffset = int(x.size());
    x.conservativeResize(x.size() + scalarCount);
    for (int i = 0; i < scalarCount; ++i) x[joint.scalarOffset + i] = q0[i];
    model.blocks.push_back({joint.velocityOffset, scalarCount, joint.scalarOffset, -1});
  }
  if (storedRotation) {
    // Initial rotation given as a rotation vector, the last three coordinates.
    joint.rotation = int(model.initialConfiguration.rotations.size());
    model.initialConfiguration.rotations.push_back(expSO3(Vec3(q0[scalarCount], q0[scalarCount + 1], q0[scalarCount + 2])));
    model.blocks.push_back({joint.velocityOffset + scalarCount, 3, -1, joint.rotation});
  }
  VectorXd& v = model.initialVelocity;
  v.conservativeResize(v.size() + joint.dofs);
  for (int i = 0; i < joint.dofs; ++i) v[joint.velocityOffset + i] = spec.initialRates.empty() ? 0.0 : spec.initialRates[i];
  model.velocityCount += joint.dofs;
  if (joint.actuated || spec.driveRateInput) {
    joint.inputOffset = model.jointInputCount;
    model.jointInputCount += spec.driveRateInput ? 1 : joint.dofs;
  }
}

// Where the bodies are while assembly places markers on them: model index
// by name and solver (centre-of-mass) frames in the design configuration.
struct Placement {
  std::map<std::string, int> bodyIndex;
  std::vector<WorldFrame> design;

  int indexOf(const std::string& name) const { return name == kGround ? kGroundIndex : bodyIndex.at(name); }
  WorldFrame frameOf(int body) const {
    return body == kGroundIndex ? WorldFrame{Vec3::Zero(), Mat3::Identity()} : design[body];
  }
  Marker marker(int body, const WorldFrame& frame) const { return markerOn(body, frameOf(body), frame); }
};

// The bodies in tree order (parent < child).
void addBodies(const Scene& scene, const std::vector<int>& order, Model& model, Placement& at) {
  for (int k = 0; k < int(order.size()); ++k) {
    const BodySpec& spec = scene.bodies[order[k]];
    Body b;
    b.name = spec.name;
    b.isVirtual = spec.isVirtual;
    b.mass = spec.mass;
    b.inertia = spec.inertia;
    b.centerOfMass = spec.centerOfMass;
    at.bodyIndex[spec.name] = k;
    at.design.push_back({spec.position + spec.orientation * spec.centerOfMass, spec.orientation});
    model.bodies.push_back(b);
  }
}

// A joint's markers: its design frame fixed in the parent and in the child.
Joint jointOf(const JointSpec& spec, const Placement& at) {
  Joint j;
  j.name = spec.name;
  j.type = spec.type;
  j.dofs = int(jointDofs(spec.type));
  j.cut = spec.cut;
  j.actuated = spec.torqueInput;
  j.keepRates = spec.keepRates;
  j.damping = spec.damping;
  const WorldFrame jointFrame{spec.position, spec.frame};
  j.parentMarker = at.marker(at.indexOf(spec.parent), jointFrame);
  j.childMarker = at.marker(at.indexOf(spec.child), jointFrame);
  return j;
}

// Tree joints in body order (so joint k's child is body k), cut joints after.
void addJoints(const Scene& scene, Model& model, const Placement& at) {
  std::vector<int> jointOrder(model.bodies.size(), -1);
  std::vector<int> cutJoints;
  for (int i = 0; i < int(scene.joints.size()); ++i) {
    if (scene.joints[i].cut) cutJoints.push_back(i);
    else jointOrder[at.bodyIndex.at(scene.joints[i].child)] = i;
  }
  for (int sceneIndex : jointOrder) {
    const JointSpec& spec = scene.joints[sceneIndex];
    Joint j = jointOf(spec, at);
    const int parent = j.parentMarker.body, child = j.childMarker.body;
    layOutCoordinates(model, j, spec);
    if (spec.driven) {
      j.driven = true;
      j.drive = spec.drive;
      j.driveRateInput = spec.driveRateInput;
      j.constraintOffset = model.constraintCount;
      model.constraintCount += 1;
    }
    model.bodies[child].parent = parent;
    model.bodies[child].inboardJoint = int(model.joints.size());
    model.joints.push_back(j);
  }
  // Cut joints close loops: constraint rows with Lagrange multipliers.
  for (int sceneIndex : cutJoints) {
    const JointSpec& spec = scene.joints[sceneIndex];
    Joint j = jointOf(spec, at);
    j.constraintOffset = model.constraintCount;
    model.constraintCount += constraintCount(spec.type);
    model.joints.push_back(j);
  }
}

// Force elements: their points become markers on the bodies; a rotational
// spring-damper sits on its joint.
void addForceElements(const Scene& scene, Model& model, const Placement& at) {
  for (const ForceSpec& f : scene.forces) {
    if (f.kind == ForceSpec::Kind::RotationalSpringDamper) {
      Joint& j = model.joints[findJoint(model, f.joint)];
      j.springStiffness = f.stiffness;
      j.springDamping = f.damping;
      j.springFreeCoordinate = f.freeLength;
      continue;
    }
    ForceElement e;
    e.name = f.name;
    const int b1 = at.indexOf(f.body1);
    const int b2 = f.kind == ForceSpec::Kind::AppliedForce ? kGroundIndex : at.indexOf(f.body2);
    e.marker1 = at.marker(b1, {f.point1, f.orientation});
    e.marker2 = at.marker(b2, {f.point2, f.orientation});
    switch (f.kind) {
      case ForceSpec::Kind::SpringDamper:
        e.kind = ForceElement::Kind::SpringDamper;
        e.stiffness = f.stiffness;
        e.damping = f.damping;
        e.freeLength = f.freeLength >= 0.0 ? f.freeLength : (f.point2 - f.point1).norm();
        if (f.actuated) e.inputOffset = model.forceInputCount++;
        break;
      case ForceSpec::Kind::Bushing:
        e.kind = ForceElement::Kind::Bushing;
        e.bushingStiffness = f.stiffness6;
        e.bushingDamping = f.damping6;
        break;
      default:
        e.kind = ForceElement::Kind::AppliedForce;
        e.bodyFrame = f.bodyFrame;
        e.force = f.force;
        e.torque = f.torque;
        e.scale = f.scale;
        if (!f.input) break;
        e.inputOffset = model.forceInputCount;
        model.forceInputCount += 6;
        break;
    }
    model.forces.push_back(e);
  }
}

// Flexible body joints: the virtual body's design frame, fixed in the node's.
void addFlexibleBodyJoints(const Scene& scene, Model& model, const Placement& at) {
  for (const FlexibleBodyJointSpec& spec : scene.flexibleBodyJoints) {
    FlexibleBodyJoint w;
    w.name = spec.name;
    w.virtualBody = at.bodyIndex.at(spec.virtualBody);
    w.node = model.flexible.bodies[spec.flexibleBody].firstNode + spec.node;
    const NodePose& node = model.flexible.nodes[w.node].reference;
    const WorldFrame& body = at.design[w.virtualBody];
    w.joint.type = JointType::Fixed;
    w.joint.parentMarker = {node.A.transpose() * (body.origin - node.r), node.A.transpose() * body.orientation};
    w.joint.childMarker = {Vec3::Zero(), Mat3::Identity()};
    w.constraintOffset = model.constraintCount;
    model.constraintCount += 6;
    model.flexibleBodyJoints.push_back(w);
  }
}

}  // namespace

Model assemble(const Scene& scene) {
  Model model;
  model.name = scene.name;
  model.gravity = scene.gravity;
  model.newtonMatrix = scene.solver.newtonMatrix;
  std::map<std::string, int> sceneBodyIndex;
  Placement at;
  addBodies(scene, treeOrder(scene, sceneBodyIndex), model, at);
  addJoints(scene, model, at);
  addForceElements(scene, model, at);
  model.rigidVelocityCount = model.velocityCount;
  model.analysis = scene.analysis;
  assembleFlexibleBodies(scene, model.flexible, model.blocks, model.initialConfiguration, model.initialVelocity,
                         model.velocityCount);
  addFlexibleBodyJoints(scene, model, at);
  return model;
}

int findBody(const Model& model, const std::string& name) {
  for (int i = 0; i < int(model.bodies.size()); ++i)
    if (model.bodies[i].name == name) return i;
  return -1;
}

int findJoint(const Model& model, const std::string& name) {
  for (int i = 0; i < int(model.joints.size()); ++i)
    if (model.joints[i].name == name) return i;
  return -1;
}

}  // namespace mfbd
