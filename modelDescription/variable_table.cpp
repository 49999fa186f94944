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
  // Inputs start at 0 (no force, no rate) and vary continuously.
  void input(const std::string& name, const std::string& unit, const std::string& description, Quantity q) {
    add(name, Causality::Input, Variability::Continuous, unit, description, q, 0.0);
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

namespace {

using QK = QuantityKind;

void parameters(const Scene& scene, TableBuilder& t) {
  const Causality P = Causality::Parameter;
  const Variability F = Variability::Fixed;
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
}

// Generalized joint forces along the DOFs of actuated joints, and the rates
// of rate-input drives.
void jointInputs(const Scene& scene, TableBuilder& t) {
  for (int j = 0; j < int(scene.joints.size()); ++j) {
    const JointSpec& jt = scene.joints[j];
    if (jt.driveRateInput) {
      const bool angular = isAngle(jointCoordinateNames(jt.type)[0]);
      t.input(jt.name + ".drive_rate", angular ? "rad/s" : "m/s",
              "rate of the driven coordinate, held over a step (the coordinate integrates it)",
              {QK::JointDriveRate, j});
    }
    if (!jt.torqueInput) continue;
    const auto names = jointCoordinateNames(jt.type);
    for (int d = 0; d < int(names.size()); ++d) {
      const bool angular = isAngle(names[d]);
      const std::string name = names.size() == 1 ? (angular ? "torque" : "force")
                                                 : (angular ? "torque_" : "force_") + names[d];
      t.input(jt.name + "." + name, angular ? "N.m" : "N", "generalized force along " + names[d],
              {QK::JointForceInput, j, d});
    }
  }
}

// Six inputs from `offset`: a force and a torque (moment) in `frame`.
void wrenchInputs(TableBuilder& t, const std::string& owner, const char* torque, const std::string& what,
                  const std::string& frame, QK kind, int offset) {
  for (int c = 0; c < 3; ++c)
    t.input(owner + ".force." + kAxes[c], "N", what + " force, " + frame, {kind, offset + c});
  for (int c = 0; c < 3; ++c)
    t.input(owner + "." + torque + "." + kAxes[c], "N.m", what + " " + torque + ", " + frame, {kind, offset + 3 + c});
}

// Force-element and flexible-node inputs, at the offsets assembly gave.
void modelInputs(const ModelNumbering& model, TableBuilder& t) {
  for (const ModelNumbering::ForceInput& e : model.forceInputs()) {
    if (e.actuator)
      t.input(e.name + ".actuator_force", "N", "actuator tension added to the spring-damper",
              {QK::ForceInput, e.offset});
    else
      wrenchInputs(t, e.name, "torque", "applied", e.bodyFrame ? "body frame" : "world", QK::ForceInput, e.offset);
  }
  for (const ModelNumbering::NodeInput& n : model.nodeInputs()) {
    if (n.driveRate)
      t.input(n.node + ".drive_rate", "rad/s", "rotation rate of the driven support about its axis",
              {QK::FlexibleInput, n.offset});
    else
      wrenchInputs(t, n.node, "moment", "nodal", n.follower ? "node frame" : "world", QK::FlexibleInput, n.offset);
  }
}

void jointOutputs(const Scene& scene, TableBuilder& t) {
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
}

// Flexible body joints, named after the joint or force element that made them.
void flexibleBodyJointOutputs(const ModelNumbering& model, TableBuilder& t) {
  const std::vector<std::string> names = model.flexibleBodyJoints();
  for (int k = 0; k < int(names.size()); ++k) {
    for (int c = 0; c < 3; ++c)
      t.output(names[k] + ".force." + kAxes[c], "N", "force of the node on the virtual body, virtual body frame",
               {QK::FlexibleBodyJointForce, k, c});
    for (int c = 0; c < 3; ++c)
      t.output(names[k] + ".torque." + kAxes[c], "N.m",
               "torque of the node on the virtual body about its origin, virtual body frame",
               {QK::FlexibleBodyJointTorque, k, c});
    t.output(names[k] + ".violation", "", "largest constraint violation of the weld (m, rad)",
             {QK::FlexibleBodyJointViolation, k});
  }
}

void bodyOutputs(const Scene& scene, TableBuilder& t) {
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
}

void springOutputs(const ModelNumbering& model, TableBuilder& t) {
  for (const auto& [f, name] : model.springDampers()) {
    t.output(name + ".length", "m", "distance between the spring's points", {QK::SpringLength, f, 0});
    t.output(name + ".length_rate", "m/s", "rate of the length", {QK::SpringLength, f, 1});
    t.output(name + ".tension", "N", "spring, damper and actuator force (pulling the points together)",
             {QK::SpringLength, f, 2});
  }
}

void nodeOutputs(const std::string& name, int n, TableBuilder& t) {
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

void flexibleBodyOutputs(const Scene& scene, const ModelNumbering& model, TableBuilder& t) {
  for (int b = 0; b < int(scene.flexibleBodies.size()); ++b) {
    const FlexibleBodySpec& spec = scene.flexibleBodies[b];
    for (int i : spec.exposedNodes()) nodeOutputs(spec.name + ".node" + std::to_string(i), model.node(b, i), t);
    if (spec.outputEnergy) {
      t.output(spec.name + ".kinetic_energy", "J", "kinetic energy of the nodal inertia", {QK::FlexibleEnergy, b, 0});
      t.output(spec.name + ".strain_energy", "J", "elastic strain energy of the elements", {QK::FlexibleEnergy, b, 1});
      t.output(spec.name + ".potential_energy", "J", "potential energy of gravity (zero at the world origin)",
               {QK::FlexibleEnergy, b, 2});
    }
    for (int e : spec.outputElements) {
      const std::string name = spec.name + ".element" + std::to_string(e);
      for (int end = 0; end < 2; ++end) {
        const std::string at = name + ".end" + std::to_string(end + 1);
        for (int c = 0; c < 3; ++c)
          t.output(at + ".force." + kAxes[c], "N", "section force (N, Vy, Vz), element frame",
                   {QK::ElementSectionForce, model.element(b, e), 6 * end + c});
        for (int c = 0; c < 3; ++c)
          t.output(at + ".moment." + kAxes[c], "N.m", "section moment (T, My, Mz), element frame",
                   {QK::ElementSectionForce, model.element(b, e), 6 * end + 3 + c});
      }
    }
  }
}

}  // namespace

// Parameters, inputs, then outputs: joints, flexible body joints, bodies,
// spring-dampers, flexible nodes and elements, as the scene selects.
std::vector<Variable> variableTable(const Scene& scene, const ModelNumbering& model) {
  TableBuilder t;
  parameters(scene, t);
  jointInputs(scene, t);
  modelInputs(model, t);
  jointOutputs(scene, t);
  flexibleBodyJointOutputs(model, t);
  bodyOutputs(scene, t);
  springOutputs(model, t);
  flexibleBodyOutputs(scene, model, t);
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
