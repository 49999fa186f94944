#include "variable_table.hpp"

#include <cstdint>
#include <cstdio>

#include "scene/joint_dofs.hpp"

namespace mfbd {

namespace {

const char* kAxes[3] = {"x", "y", "z"};
const char* kQuaternion[4] = {"w", "x", "y", "z"};

bool isAngle(const std::string& coordinate) {
  return coordinate == "angle" || coordinate == "angle1" || coordinate == "angle2" ||
         coordinate.rfind("rotation", 0) == 0;
}

class TableBuilder {
 public:
  void add(std::string name, Causality c, Variability v, std::string unit, std::string description, Quantity q,
           double start = 0.0) {
    Variable var;
    var.name = std::move(name);
    var.valueReference = unsigned(table.size());
    var.causality = c;
    var.variability = v;
    var.unit = std::move(unit);
    var.description = std::move(description);
    var.quantity = q;
    var.start = start;
    table.push_back(std::move(var));
  }
  void output(const std::string& name, const std::string& unit, const std::string& description, Quantity q) {
    add(name, Causality::Output, Variability::Continuous, unit, description, q);
  }
  std::vector<Variable> table;
};

}  // namespace

std::vector<std::string> jointCoordinateNames(JointType type) {
  switch (type) {
    case JointType::Revolute: return {"angle"};
    case JointType::Prismatic: return {"position"};
    case JointType::Cylindrical: return {"angle", "position"};
    case JointType::Universal: return {"angle1", "angle2"};
    case JointType::Spherical: return {"rotation_x", "rotation_y", "rotation_z"};
    case JointType::Planar: return {"x", "y", "angle"};
    case JointType::Fixed: return {};
    case JointType::Free: return {"x", "y", "z", "rotation_x", "rotation_y", "rotation_z"};
  }
  return {};
}

std::vector<Variable> variableTable(const Scene& scene) {
  TableBuilder t;
  using QK = QuantityKind;
  const Causality P = Causality::Parameter;
  const Variability F = Variability::Fixed;

  // Parameters.
  for (int i = 0; i < int(scene.parameters.size()); ++i) {
    const ParameterSpec& p = scene.parameters[i];
    t.add(p.name, P, F, p.unit, p.description, {QK::UserParameter, i}, p.value);
  }
  for (int c = 0; c < 3; ++c)
    t.add(std::string("gravity.") + kAxes[c], P, F, "m/s2", "gravitational acceleration, world",
          {QK::Gravity, 0, c}, scene.gravity[c]);
  t.add("solver.h_max", P, F, "s", "largest implicit substep", {QK::StepSizeMax}, scene.solver.hMax);
  t.add("solver.rho_inf", P, F, "", "generalized-alpha spectral radius at infinity", {QK::SpectralRadius},
        scene.solver.rhoInf);
  t.add("solver.tolerance", P, F, "", "Newton: largest position error left after the last correction (m, rad)",
        {QK::NewtonTolerance}, scene.solver.tolerance);
  t.add("solver.max_substeps", P, F, "", "substeps one communication step may take (rejected ones included)",
        {QK::MaxSubsteps}, scene.solver.maxSubsteps);
  for (int j = 0; j < int(scene.joints.size()); ++j) {
    const JointSpec& jt = scene.joints[j];
    if (jointDofs(jt.type) == 0 || jt.cut || jt.isVirtual) continue;
    const bool rotational = jt.type == JointType::Revolute;
    t.add(jt.name + ".damping", P, Variability::Tunable, rotational ? "N.m.s/rad" : "",
          "viscous damping per joint DOF", {QK::JointDamping, j}, jt.damping);
  }

  for (int b = 0; b < int(scene.flexibleBodies.size()); ++b)
    t.add(scene.flexibleBodies[b].name + ".damping", P, Variability::Tunable, "s",
          "stiffness-proportional material damping coefficient", {QK::FlexibleDamping, b},
          scene.flexibleBodies[b].damping);

  // Inputs: generalized joint forces along the DOFs of actuated joints, and
  // the rates of rate-input drives.
  for (int j = 0; j < int(scene.joints.size()); ++j) {
    const JointSpec& jt = scene.joints[j];
    if (jt.driveRateInput) {
      const bool angular = isAngle(jointCoordinateNames(jt.type)[0]);
      t.add(jt.name + ".drive_rate", Causality::Input, Variability::Continuous, angular ? "rad/s" : "m/s",
            "rate of the driven coordinate, held over a step (the coordinate integrates it)",
            {QK::JointDriveRate, j}, 0.0);
    }
    if (!jt.torqueInput) continue;
    const auto names = jointCoordinateNames(jt.type);
    for (int d = 0; d < int(names.size()); ++d) {
      const bool angular = isAngle(names[d]);
      const std::string name = names.size() == 1 ? (angular ? "torque" : "force")
                                                 : (angular ? "torque_" : "force_") + names[d];
      t.add(jt.name + "." + name, Causality::Input, Variability::Continuous, angular ? "N.m" : "N",
            "generalized force along " + names[d], {QK::JointForceInput, j, d}, 0.0);
    }
  }

  // Force-element inputs and flexible inputs, at the offsets the assembly gave.
  const Model model = assemble(scene);
  for (const ForceElement& e : model.forces) {
    if (e.inputOffset < 0) continue;
    if (e.kind == ForceElement::Kind::SpringDamper) {
      t.add(e.name + ".actuator_force", Causality::Input, Variability::Continuous, "N",
            "actuator tension added to the spring-damper", {QK::ForceInput, e.inputOffset}, 0.0);
      continue;
    }
    const char* frame = e.bodyFrame ? "body frame" : "world";
    for (int c = 0; c < 3; ++c)
      t.add(e.name + ".force." + kAxes[c], Causality::Input, Variability::Continuous, "N",
            std::string("applied force, ") + frame, {QK::ForceInput, e.inputOffset + c}, 0.0);
    for (int c = 0; c < 3; ++c)
      t.add(e.name + ".torque." + kAxes[c], Causality::Input, Variability::Continuous, "N.m",
            std::string("applied torque, ") + frame, {QK::ForceInput, e.inputOffset + 3 + c}, 0.0);
  }
  const FlexibleMesh& mesh = model.flexible;
  auto nodeName = [&](int node) {
    for (const FlexibleBody& fb : mesh.bodies)
      if (node >= fb.firstNode && node < fb.firstNode + fb.nodeCount)
        return fb.name + ".node" + std::to_string(node - fb.firstNode);
    return std::string("?");
  };
  for (std::size_t n = 0; n < mesh.nodes.size(); ++n) {
    const int d = mesh.nodes[n].drive;
    if (d >= 0 && mesh.drives[d].inputOffset >= 0)
      t.add(nodeName(int(n)) + ".drive_rate", Causality::Input, Variability::Continuous, "rad/s",
            "rotation rate of the driven support about its axis", {QK::FlexibleInput, mesh.drives[d].inputOffset},
            0.0);
  }
  for (const FlexLoad& l : mesh.loads) {
    if (l.inputOffset < 0) continue;
    const char* frame = l.follower ? "node frame" : "world";
    for (int c = 0; c < 3; ++c)
      t.add(nodeName(l.node) + ".force." + kAxes[c], Causality::Input, Variability::Continuous, "N",
            std::string("nodal force, ") + frame, {QK::FlexibleInput, l.inputOffset + c}, 0.0);
    for (int c = 0; c < 3; ++c)
      t.add(nodeName(l.node) + ".moment." + kAxes[c], Causality::Input, Variability::Continuous, "N.m",
            std::string("nodal moment, ") + frame, {QK::FlexibleInput, l.inputOffset + 3 + c}, 0.0);
  }

  // Outputs: joints, then bodies, then flexible nodes and elements, as the scene selects.
  for (int j = 0; j < int(scene.joints.size()); ++j) {
    const JointSpec& jt = scene.joints[j];
    if (jt.isVirtual || !scene.outputs.exposesJoint(jt.name)) continue;
    const auto names = jt.cut ? std::vector<std::string>() : jointCoordinateNames(jt.type);
    for (int d = 0; d < int(names.size()); ++d) {
      const bool angular = isAngle(names[d]);
      t.output(jt.name + "." + names[d], angular ? "rad" : "m", "joint coordinate", {QK::JointCoordinate, j, d});
      t.output(jt.name + "." + names[d] + "_rate", angular ? "rad/s" : "m/s", "joint rate", {QK::JointRate, j, d});
    }
    if (jt.driven) {
      const bool angular = isAngle(names[0]);
      t.output(jt.name + (angular ? ".drive_torque" : ".drive_force"), angular ? "N.m" : "N",
               "generalized force the drive applies along its coordinate", {QK::JointDriveForce, j});
    }
    for (int c = 0; c < 3; ++c)
      t.output(jt.name + ".reaction_force." + kAxes[c], "N",
               "force of the parent on the child, child marker frame", {QK::JointReactionForce, j, c});
    for (int c = 0; c < 3; ++c)
      t.output(jt.name + ".reaction_torque." + kAxes[c], "N.m",
               "torque of the parent on the child about the joint origin, child marker frame",
               {QK::JointReactionTorque, j, c});
  }
  // Flexible body joints with the joint or force element that made them.
  for (int k = 0; k < int(model.flexibleBodyJoints.size()); ++k) {
    const std::string& name = model.flexibleBodyJoints[k].name;
    for (int c = 0; c < 3; ++c)
      t.output(name + ".force." + kAxes[c], "N", "force of the node on the virtual body, virtual body frame",
               {QK::FlexibleBodyJointForce, k, c});
    for (int c = 0; c < 3; ++c)
      t.output(name + ".torque." + kAxes[c], "N.m",
               "torque of the node on the virtual body about its origin, virtual body frame",
               {QK::FlexibleBodyJointTorque, k, c});
    t.output(name + ".violation", "", "largest constraint violation of the weld (m, rad)",
             {QK::FlexibleBodyJointViolation, k});
  }
  for (int b = 0; b < int(scene.bodies.size()); ++b) {
    const std::string& name = scene.bodies[b].name;
    if (scene.bodies[b].isVirtual || !scene.outputs.exposesBody(name)) continue;
    for (int c = 0; c < 3; ++c)
      t.output(name + ".position." + kAxes[c], "m", "body frame origin, world", {QK::BodyPosition, b, c});
    for (int c = 0; c < 4; ++c)
      t.output(name + ".orientation." + kQuaternion[c], "", "unit quaternion body -> world",
               {QK::BodyOrientation, b, c});
    for (int c = 0; c < 3; ++c)
      t.output(name + ".velocity." + kAxes[c], "m/s", "velocity of the body frame origin, world",
               {QK::BodyVelocity, b, c});
    for (int c = 0; c < 3; ++c)
      t.output(name + ".angular_velocity." + kAxes[c], "rad/s", "angular velocity, world",
               {QK::BodyAngularVelocity, b, c});
  }
  for (int f = 0; f < int(model.forces.size()); ++f) {
    const ForceElement& e = model.forces[f];
    if (e.kind != ForceElement::Kind::SpringDamper) continue;
    t.output(e.name + ".length", "m", "distance between the spring's points", {QK::SpringLength, f, 0});
    t.output(e.name + ".length_rate", "m/s", "rate of the length", {QK::SpringLength, f, 1});
    t.output(e.name + ".tension", "N", "spring, damper and actuator force (pulling the points together)",
             {QK::SpringLength, f, 2});
  }
  for (std::size_t b = 0; b < scene.flexibleBodies.size(); ++b) {
    const FlexibleBodySpec& spec = scene.flexibleBodies[b];
    const FlexibleBody& fb = mesh.bodies[b];
    for (int i : spec.exposedNodes()) {
      const std::string name = spec.name + ".node" + std::to_string(i);
      const int n = fb.firstNode + i;
      for (int c = 0; c < 3; ++c)
        t.output(name + ".position." + kAxes[c], "m", "node position, world", {QK::NodePosition, n, c});
      for (int c = 0; c < 4; ++c)
        t.output(name + ".orientation." + kQuaternion[c], "", "unit quaternion node -> world",
                 {QK::NodeOrientation, n, c});
      for (int c = 0; c < 3; ++c)
        t.output(name + ".velocity." + kAxes[c], "m/s", "node velocity, world", {QK::NodeVelocity, n, c});
      for (int c = 0; c < 3; ++c)
        t.output(name + ".angular_velocity." + kAxes[c], "rad/s", "node angular velocity, world",
                 {QK::NodeAngularVelocity, n, c});
    }
    if (spec.outputEnergy) {
      t.output(spec.name + ".kinetic_energy", "J", "kinetic energy of the nodal inertia", {QK::FlexibleEnergy, int(b), 0});
      t.output(spec.name + ".strain_energy", "J", "elastic strain energy of the elements", {QK::FlexibleEnergy, int(b), 1});
      t.output(spec.name + ".potential_energy", "J", "potential energy of gravity (zero at the world origin)",
               {QK::FlexibleEnergy, int(b), 2});
    }
    for (int e : spec.outputElements) {
      const std::string name = spec.name + ".element" + std::to_string(e);
      for (int end = 0; end < 2; ++end) {
        const std::string at = name + ".end" + std::to_string(end + 1);
        for (int c = 0; c < 3; ++c)
          t.output(at + ".force." + kAxes[c], "N", "section force (N, Vy, Vz), element frame",
                   {QK::ElementSectionForce, fb.firstElement + e, 6 * end + c});
        for (int c = 0; c < 3; ++c)
          t.output(at + ".moment." + kAxes[c], "N.m", "section moment (T, My, Mz), element frame",
                   {QK::ElementSectionForce, fb.firstElement + e, 6 * end + 3 + c});
      }
    }
  }
  return t.table;
}

std::string sceneGuid(const std::string& sceneText) {
  // Two 64-bit FNV-1a hashes with different offsets make 128 bits.
  const std::string salted = "mfbd-fmu variable table v2\n" + sceneText;
  std::uint64_t h1 = 0xcbf29ce484222325ull, h2 = 0x84222325cbf29ce4ull;
  for (unsigned char c : salted) {
    h1 = (h1 ^ c) * 0x100000001b3ull;
    h2 = (h2 ^ c) * 0x100000001b3ull;
    h2 ^= h2 >> 29;
  }
  char out[40];
  std::snprintf(out, sizeof out, "{%08x-%04x-%04x-%04x-%012llx}", unsigned(h1 >> 32), unsigned((h1 >> 16) & 0xffff),
                unsigned(h1 & 0xffff), unsigned(h2 >> 48), static_cast<unsigned long long>(h2 & 0xffffffffffffull));
  return out;
}

const std::vector<std::pair<std::string, std::string>>& logCategories() {
  static const std::vector<std::pair<std::string, std::string>> categories = {
      {"logEvents", "Initialization, reset, termination"},
      {"logSingularLinearSystems", "Singular iteration matrices"},
      {"logNonlinearSystems", "Newton iterations that fail or slow down"},
      {"logStatusWarning", "Calls that return fmi2Warning"},
      {"logStatusDiscard", "Steps that return fmi2Discard"},
      {"logStatusError", "Calls that return fmi2Error"},
      {"logStep", "Per communication step: substeps, Newton iterations"},
      {"logStatistics", "At fmi2Terminate: substeps, Newton iterations, factorizations of the run"},
      {"logAll", "Everything"},
  };
  return categories;
}

int maxOutputDerivativeOrder(const Scene& scene) {
  if (scene.analysis != Analysis::Dynamic) return 0;
  return scene.flexibleBodies.empty() ? 2 : 1;
}
bool providesDirectionalDerivative(const Scene& scene) { return scene.analysis == Analysis::Dynamic; }

}  // namespace mfbd
