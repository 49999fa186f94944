#include "model_description.hpp"

#include <pugixml.hpp>

#include <iomanip>
#include <map>
#include <set>
#include <sstream>

namespace mfbd {

namespace {

// Text goes in through pugixml, which escapes it (& < > " and, in
// attributes, tab, line feed and carriage return as character references,
// since a reader replaces them by spaces when they stand literally). The
// scene parser has refused the characters XML 1.0 cannot carry
// (Field::text).
using Node = pugi::xml_node;

std::string number(double x) {
  std::ostringstream s;
  s << std::setprecision(17) << x;
  return s.str();
}

// SI base-unit exponents of the units the table uses (FMI 2.0 BaseUnit).
using Exponents = std::vector<std::pair<const char*, int>>;
Exponents baseUnit(const std::string& unit) {
  static const std::map<std::string, Exponents> known = {
      {"m", {{"m", 1}}},
      {"s", {{"s", 1}}},
      {"kg", {{"kg", 1}}},
      {"rad", {{"rad", 1}}},
      {"m/s", {{"m", 1}, {"s", -1}}},
      {"m/s2", {{"m", 1}, {"s", -2}}},
      {"rad/s", {{"rad", 1}, {"s", -1}}},
      {"N", {{"kg", 1}, {"m", 1}, {"s", -2}}},
      {"N.m", {{"kg", 1}, {"m", 2}, {"s", -2}}},
      {"N.s/m", {{"kg", 1}, {"s", -1}}},
      {"N.m.s/rad", {{"kg", 1}, {"m", 2}, {"s", -1}, {"rad", -1}}},
      {"kg.m2", {{"kg", 1}, {"m", 2}}},
  };
  const auto it = known.find(unit);
  return it == known.end() ? Exponents{} : it->second;
}

const char* causalityName(Causality c) {
  switch (c) {
    case Causality::Parameter: return "parameter";
    case Causality::Input: return "input";
    case Causality::Output: return "output";
  }
  return "";
}

const char* variabilityName(Variability v) {
  switch (v) {
    case Variability::Fixed: return "fixed";
    case Variability::Tunable: return "tunable";
    case Variability::Continuous: return "continuous";
  }
  return "";
}

void writeUnits(Node x, const std::vector<Variable>& table) {
  std::set<std::string> units;
  for (const Variable& v : table)
    if (!v.unit.empty()) units.insert(v.unit);
  if (units.empty()) return;
  Node definitions = x.append_child("UnitDefinitions");
  for (const std::string& u : units) {
    Node unit = definitions.append_child("Unit");
    unit.append_attribute("name") = u.c_str();
    const Exponents base = baseUnit(u);
    if (base.empty()) continue;
    Node baseNode = unit.append_child("BaseUnit");
    for (const auto& [name, exponent] : base) baseNode.append_attribute(name) = exponent;
  }
}

void writeVariables(Node x, const std::vector<Variable>& table) {
  Node variables = x.append_child("ModelVariables");
  for (std::size_t i = 0; i < table.size(); ++i) {
    const Variable& v = table[i];
    variables.append_child(pugi::node_comment).set_value((" index " + std::to_string(i + 1) + " ").c_str());
    Node s = variables.append_child("ScalarVariable");
    s.append_attribute("name") = v.name.c_str();
    s.append_attribute("valueReference") = v.valueReference;
    s.append_attribute("causality") = causalityName(v.causality);
    s.append_attribute("variability") = variabilityName(v.variability);
    // Parameters are exact; inputs take a start value but no initial attribute.
    if (v.causality == Causality::Parameter) s.append_attribute("initial") = "exact";
    s.append_attribute("description") = v.description.c_str();
    Node real = s.append_child("Real");
    if (!v.unit.empty()) real.append_attribute("unit") = v.unit.c_str();
    if (v.causality != Causality::Output) real.append_attribute("start") = number(v.start).c_str();
  }
}

// Outputs and the inputs they depend on at a fixed state (outputDependencies).
// Initial unknowns depend on all parameters and inputs (no dependencies
// attribute).
void writeStructure(Node x, const Scene& scene, const std::vector<Variable>& table) {
  bool anyOutput = false;
  for (const Variable& v : table) anyOutput = anyOutput || v.causality == Causality::Output;
  Node structure = x.append_child("ModelStructure");
  if (!anyOutput) return;  // the schema wants no empty Outputs / InitialUnknowns
  const Model model = assemble(scene);
  Node outputs = structure.append_child("Outputs");
  for (std::size_t i = 0; i < table.size(); ++i) {
    if (table[i].causality != Causality::Output) continue;
    std::string indices, kinds;
    for (const Dependency& d : outputDependencies(model, table, i)) {
      indices += (indices.empty() ? "" : " ") + std::to_string(d.input + 1);
      kinds += (kinds.empty() ? "" : " ") + std::string(d.constantFactor ? "constant" : "dependent");
    }
    Node unknown = outputs.append_child("Unknown");
    unknown.append_attribute("index") = unsigned(i + 1);
    unknown.append_attribute("dependencies") = indices.c_str();
    if (!kinds.empty()) unknown.append_attribute("dependenciesKind") = kinds.c_str();
  }
  Node initial = structure.append_child("InitialUnknowns");
  for (std::size_t i = 0; i < table.size(); ++i)
    if (table[i].causality == Causality::Output) initial.append_child("Unknown").append_attribute("index") = unsigned(i + 1);
}

// Outputs that the consistent accelerations or multipliers enter: they
// follow every input that acts as a force at once.
bool readsAccelerations(QuantityKind k) {
  return k == QuantityKind::JointReactionForce || k == QuantityKind::JointReactionTorque ||
         k == QuantityKind::JointDriveForce || k == QuantityKind::FlexibleBodyJointForce ||
         k == QuantityKind::FlexibleBodyJointTorque || k == QuantityKind::ElementSectionForce;
}

}  // namespace


// At a fixed state (q, v, t): force inputs (joint torques and forces,
// applied forces, spring actuators, nodal loads) move the accelerations and
// multipliers, so every output that reads those; a spring's tension is its
// actuator force plus terms of the state; a rate-driven support's rate is
// its node's angular velocity at once (and that node's share of the body's
// kinetic energy, and through damping the accelerations). A rate-input
// joint drive's rate is not part of the state at the present instant: it
// sets the velocity jump at the next step and the coordinate's motion over
// it, so no output depends on it without a step.
std::vector<Dependency> outputDependencies(const Model& model, const std::vector<Variable>& table, std::size_t output) {
  const Quantity& out = table[output].quantity;
  const FlexibleMesh& mesh = model.flexible;
  auto drivenNodeInput = [&](int node) {
    const int d = mesh.nodes[node].drive;
    return d >= 0 ? mesh.drives[d].inputOffset : -1;
  };
  std::vector<Dependency> deps;
  for (std::size_t i = 0; i < table.size(); ++i) {
    if (table[i].causality != Causality::Input) continue;
    const Quantity& in = table[i].quantity;
    if (in.kind == QuantityKind::JointDriveRate) continue;
    if (readsAccelerations(out.kind)) {
      deps.push_back({i, false});
    } else if (out.kind == QuantityKind::SpringLength && out.component == 2) {
      if (in.kind == QuantityKind::ForceInput && in.index == model.forces[out.index].inputOffset) deps.push_back({i, true});
    } else if (in.kind == QuantityKind::FlexibleInput) {
      bool depends = false;
      if (out.kind == QuantityKind::NodeVelocity || out.kind == QuantityKind::NodeAngularVelocity)
        depends = drivenNodeInput(out.index) == in.index;
      if (out.kind == QuantityKind::FlexibleEnergy && out.component == 0) {
        const FlexibleBody& b = mesh.bodies[out.index];
        for (int n = b.firstNode; n < b.firstNode + b.nodeCount; ++n) depends = depends || drivenNodeInput(n) == in.index;
      }
      if (depends) deps.push_back({i, false});
    }
  }
  return deps;
}

std::string modelDescriptionXml(const Scene& scene, const std::vector<Variable>& table, const std::string& guid,
                                const std::string& modelIdentifier, const Capabilities& caps) {
  pugi::xml_document document;
  Node declaration = document.append_child(pugi::node_declaration);
  declaration.append_attribute("version") = "1.0";
  declaration.append_attribute("encoding") = "UTF-8";
  Node x = document.append_child("fmiModelDescription");
  x.append_attribute("fmiVersion") = "2.0";
  x.append_attribute("modelName") = scene.name.c_str();
  x.append_attribute("guid") = guid.c_str();
  x.append_attribute("description") = scene.description.c_str();
  x.append_attribute("generationTool") = "MFBD-FMU mfbd-pack";
  x.append_attribute("variableNamingConvention") = "structured";
  x.append_attribute("numberOfEventIndicators") = "0";
  Node cs = x.append_child("CoSimulation");
  cs.append_attribute("modelIdentifier") = modelIdentifier.c_str();
  cs.append_attribute("needsExecutionTool") = "false";
  cs.append_attribute("canHandleVariableCommunicationStepSize") = "true";
  cs.append_attribute("canInterpolateInputs") = caps.canInterpolateInputs;
  cs.append_attribute("maxOutputDerivativeOrder") = maxOutputDerivativeOrder(scene);
  cs.append_attribute("canRunAsynchronuously") = "false";
  cs.append_attribute("canBeInstantiatedOnlyOncePerProcess") = "false";
  cs.append_attribute("canNotUseMemoryManagementFunctions") = "true";
  cs.append_attribute("canGetAndSetFMUstate") = caps.canGetAndSetFMUstate;
  cs.append_attribute("canSerializeFMUstate") = caps.canSerializeFMUstate;
  cs.append_attribute("providesDirectionalDerivative") = providesDirectionalDerivative(scene);
  writeUnits(x, table);
  Node categories = x.append_child("LogCategories");
  for (const auto& [name, description] : logCategories()) {
    Node category = categories.append_child("Category");
    category.append_attribute("name") = name.c_str();
    category.append_attribute("description") = description.c_str();
  }
  Node experiment = x.append_child("DefaultExperiment");
  experiment.append_attribute("startTime") = number(scene.experiment.startTime).c_str();
  experiment.append_attribute("stopTime") = number(scene.experiment.stopTime).c_str();
  experiment.append_attribute("tolerance") = number(scene.experiment.tolerance).c_str();
  experiment.append_attribute("stepSize") = number(scene.experiment.outputInterval).c_str();
  // (FMI 2.0 places VendorAnnotations between DefaultExperiment and ModelVariables.)
  if (caps.canInterpolateInputs) {
    Node tool = x.append_child("VendorAnnotations").append_child("Tool");
    tool.append_attribute("name") = "MFBD-FMU";
    tool.append_child("InputDerivatives").append_attribute("maxOrder") = caps.maxInputDerivativeOrder;
  }
  writeVariables(x, table);
  writeStructure(x, scene, table);
  std::ostringstream out;
  document.save(out, "  ", pugi::format_default, pugi::encoding_utf8);
  return out.str();
}

}  // namespace mfbd
