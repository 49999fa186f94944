// Cross-field checks of a parsed scene: unique names, resolved references,
// coordinate counts, and a spanning tree rooted at ground.
#include <map>
#include <set>
#include <vector>

#include "scene/joint_dofs.hpp"
#include "scene/scene.hpp"

namespace mfbd {

namespace {

std::string jointPath(std::size_t i) { return "joints[" + std::to_string(i) + "]"; }

void checkNames(const Scene& scene) {
  std::map<std::string, std::string> seen;  // name -> path of first use
  const std::set<std::string> reserved = {kGround, "gravity", "solver", "time"};
  auto claim = [&](const std::string& name, const std::string& path) {
    if (reserved.count(name)) throw SceneError(path, "\"" + name + "\" is a reserved name");
    const auto [it, fresh] = seen.emplace(name, path);
    if (!fresh) throw SceneError(path, "duplicate name \"" + name + "\" (already used at " + it->second + ")");
  };
  for (std::size_t i = 0; i < scene.parameters.size(); ++i)
    claim(scene.parameters[i].name, "parameters." + scene.parameters[i].name);
  for (std::size_t i = 0; i < scene.bodies.size(); ++i)
    claim(scene.bodies[i].name, "bodies[" + std::to_string(i) + "].name");
  for (std::size_t i = 0; i < scene.joints.size(); ++i) claim(scene.joints[i].name, jointPath(i) + ".name");
  for (std::size_t i = 0; i < scene.flexibleBodies.size(); ++i)
    claim(scene.flexibleBodies[i].name, "flexible_bodies[" + std::to_string(i) + "].name");
  for (std::size_t i = 0; i < scene.forces.size(); ++i) claim(scene.forces[i].name, "forces[" + std::to_string(i) + "].name");
}

void checkJoint(const Scene& scene, std::size_t i, const std::set<std::string>& bodies) {
  const JointSpec& j = scene.joints[i];
  const std::string path = jointPath(i);
  for (const auto* end : {&j.parent, &j.child}) {
    const char* key = end == &j.parent ? ".parent" : ".child";
    if (*end != kGround && !bodies.count(*end))
      throw SceneError(path + key, "joint '" + j.name + "' names unknown body \"" + *end + "\"");
  }
  if (j.child == kGround) throw SceneError(path + ".child", "ground cannot be a joint's child; swap parent and child");
  if (j.parent == j.child) throw SceneError(path + ".child", "joint '" + j.name + "' connects a body to itself");
  const std::size_t n = jointDofs(j.type);
  if (!j.initialCoordinates.empty() && j.initialCoordinates.size() != n)
    throw SceneError(path + ".initial.coordinates", "a " + std::string(jointTypeName(j.type)) + " joint has " +
                                                        std::to_string(n) + " coordinates, got " +
                                                        std::to_string(j.initialCoordinates.size()));
  if (!j.initialRates.empty() && j.initialRates.size() != n)
    throw SceneError(path + ".initial.rates", "a " + std::string(jointTypeName(j.type)) + " joint has " +
                                                  std::to_string(n) + " rates, got " +
                                                  std::to_string(j.initialRates.size()));
  if (j.torqueInput && n == 0)
    throw SceneError(path + ".actuated", "a fixed joint has no coordinate to actuate");
  if (j.driven && (n != 1 || j.cut))
    throw SceneError(path + ".drive", "joint '" + j.name + "': a drive prescribes the coordinate of a one-DOF tree "
                                          "joint (revolute or prismatic)");
  if (j.driven && j.torqueInput)
    throw SceneError(path + ".actuated", "joint '" + j.name + "' is driven: its force comes from the drive");
  if (j.cut && j.torqueInput)
    throw SceneError(path + ".actuated", "joint '" + j.name + "' is a cut joint: it has no coordinates to actuate");
  if (j.cut && j.damping != 0.0)
    throw SceneError(path + ".damping", "joint '" + j.name + "' is a cut joint: it has no coordinates to damp");
  if (j.cut && (!j.initialCoordinates.empty() || !j.initialRates.empty() || j.keepRates))
    throw SceneError(path + ".initial", "joint '" + j.name + "' is a cut joint: it has no coordinates of its own");
}

// Every body is the child of exactly one tree (non-cut) joint, and following
// parents from any body reaches ground.
void checkTree(const Scene& scene) {
  std::map<std::string, std::size_t> inboard;  // body -> index of its tree joint
  for (std::size_t i = 0; i < scene.joints.size(); ++i) {
    const JointSpec& j = scene.joints[i];
    if (j.cut) continue;
    const auto [it, fresh] = inboard.emplace(j.child, i);
    if (!fresh)
      throw SceneError(jointPath(i) + ".child",
                       "body '" + j.child + "' has two parent joints, '" + scene.joints[it->second].name +
                           "' and '" + j.name + "'; declare one of them \"cut\": true to close the loop");
  }
  for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
    const std::string& name = scene.bodies[b].name;
    if (!inboard.count(name))
      throw SceneError("bodies[" + std::to_string(b) + "]",
                       "body '" + name + "' has no joint to a parent; connect it (a \"free\" joint for a floating body)");
    std::string at = name;
    for (std::size_t steps = 0; at != kGround; ++steps) {
      if (steps > scene.bodies.size())
        throw SceneError("bodies[" + std::to_string(b) + "]",
                         "body '" + name + "' is on a loop of parent joints that never reaches ground");
      at = scene.joints[inboard.at(at)].parent;
    }
  }
}

void checkOutputs(const Scene& scene, const std::set<std::string>& bodies) {
  std::set<std::string> joints;
  for (const auto& j : scene.joints) joints.insert(j.name);
  for (std::size_t i = 0; i < scene.outputs.bodies.size(); ++i)
    if (!bodies.count(scene.outputs.bodies[i]))
      throw SceneError("outputs.bodies[" + std::to_string(i) + "]", "unknown body \"" + scene.outputs.bodies[i] + "\"");
  for (std::size_t i = 0; i < scene.outputs.joints.size(); ++i)
    if (!joints.count(scene.outputs.joints[i]))
      throw SceneError("outputs.joints[" + std::to_string(i) + "]", "unknown joint \"" + scene.outputs.joints[i] + "\"");
}

}  // namespace

// The spanning tree, where the scene does not declare every cut: breadth
// first from ground over the joints not declared cut, each body taking as
// its tree joint the first (in scene order) of the joints that reach it
// from the shallowest level. The shallowest tree moves each body by the
// fewest joint rates, which keeps the joint-space Newton matrix sparse (an
// N-four-bar: a band, where cutting the pivots makes an 81-deep chain and
// a dense matrix). The other joints are cut (a closed loop), noted for the
// log. Bodies that no joint reaches are left for validateScene to name.
void chooseCutJoints(Scene& scene) {
  std::set<std::string> reached = {kGround};
  std::vector<bool> tree(scene.joints.size(), false);
  for (std::set<std::string> level = {kGround}; !level.empty();) {
    std::set<std::string> next;
    for (std::size_t k = 0; k < scene.joints.size(); ++k) {
      const JointSpec& j = scene.joints[k];
      if (j.cut || !level.count(j.parent) || reached.count(j.child)) continue;
      tree[k] = true;
      reached.insert(j.child);
      next.insert(j.child);
    }
    level = std::move(next);
  }
  std::set<std::string> hasParent;  // joints from bodies no tree joint reaches: the first per child
  for (std::size_t k = 0; k < scene.joints.size(); ++k) {
    JointSpec& j = scene.joints[k];
    if (j.cut || tree[k]) continue;
    if (!reached.count(j.child) && hasParent.insert(j.child).second) continue;
    j.cut = true;
    scene.notes.push_back("joint '" + j.name + "' closes a loop at body '" + j.child + "': cut (Lagrange multipliers)");
  }
}

void checkForces(const Scene& scene, const std::set<std::string>& bodies) {
  for (std::size_t i = 0; i < scene.forces.size(); ++i) {
    const ForceSpec& f = scene.forces[i];
    const std::string path = "forces[" + std::to_string(i) + "]";
    if (f.kind == ForceSpec::Kind::RotationalSpringDamper) {
      const JointSpec* joint = nullptr;
      for (const JointSpec& j : scene.joints)
        if (j.name == f.joint) joint = &j;
      if (!joint) throw SceneError(path + ".joint", "force '" + f.name + "' names unknown joint \"" + f.joint + "\"");
      if (joint->cut || jointDofs(joint->type) != 1)
        throw SceneError(path + ".joint", "force '" + f.name + "': a rotational spring-damper acts on a one-DOF tree joint");
      continue;
    }
    const bool applied = f.kind == ForceSpec::Kind::AppliedForce;
    for (int k = 1; k <= (applied ? 1 : 2); ++k) {
      const std::string& b = k == 1 ? f.body1 : f.body2;
      if (b != kGround && !bodies.count(b))
        throw SceneError(path + (applied ? ".body" : ".body" + std::to_string(k)),
                         "force '" + f.name + "' names unknown body \"" + b + "\"");
    }
    if (applied && f.body1 == kGround) throw SceneError(path + ".body", "a force applied to ground does nothing");
    if (f.kind == ForceSpec::Kind::SpringDamper && f.freeLength < 0.0 && (f.point2 - f.point1).norm() < 1e-12)
      throw SceneError(path, "spring '" + f.name + "' has zero length; its direction is undefined");
  }
}

void validateScene(const Scene& scene) {
  if (scene.bodies.empty() && scene.flexibleBodies.empty())
    throw SceneError("bodies", "expected at least one body or flexible body");
  checkNames(scene);
  std::set<std::string> bodies;
  for (const auto& b : scene.bodies) bodies.insert(b.name);
  for (std::size_t i = 0; i < scene.joints.size(); ++i) checkJoint(scene, i, bodies);
  checkTree(scene);
  checkOutputs(scene, bodies);
  checkForces(scene, bodies);
}

}  // namespace mfbd
