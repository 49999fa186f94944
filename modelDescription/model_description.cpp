#include "model_description.hpp"

#include <iomanip>
#include <map>
#include <set>
#include <sstream>

namespace mfbd {

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

namespace {

// Text as an XML attribute value. Tab, line feed and carriage return are
// written as character references, since a reader replaces them by spaces
// when they stand literally in an attribute. The scene parser has refused
// the characters XML 1.0 cannot carry (Field::text).
std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      case '\t': out += "&#9;"; break;
      case '\n': out += "&#10;"; break;
      case '\r': out += "&#13;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string number(double x) {
  std::ostringstream s;
  s << std::setprecision(17) << x;
  return s.str();
}

// SI base-unit exponents of the units the table uses (FMI 2.0 BaseUnit).
std::string baseUnit(const std::string& unit) {
  static const std::map<std::string, std::string> known = {
      {"m", "m=\"1\""},
      {"s", "s=\"1\""},
      {"kg", "kg=\"1\""},
      {"rad", "rad=\"1\""},
      {"m/s", "m=\"1\" s=\"-1\""},
      {"m/s2", "m=\"1\" s=\"-2\""},
      {"rad/s", "rad=\"1\" s=\"-1\""},
      {"N", "kg=\"1\" m=\"1\" s=\"-2\""},
      {"N.m", "kg=\"1\" m=\"2\" s=\"-2\""},
      {"N.s/m", "kg=\"1\" s=\"-1\""},
      {"N.m.s/rad", "kg=\"1\" m=\"2\" s=\"-1\" rad=\"-1\""},
      {"kg.m2", "kg=\"1\" m=\"2\""},
  };
  const auto it = known.find(unit);
  return it == known.end() ? "" : it->second;
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

void writeUnits(std::ostream& x, const std::vector<Variable>& table) {
  std::set<std::string> units;
  for (const Variable& v : table)
    if (!v.unit.empty()) units.insert(v.unit);
  if (units.empty()) return;
  x << "  <UnitDefinitions>\n";
  for (const std::string& u : units) {
    const std::string base = baseUnit(u);
    if (base.empty()) x << "    <Unit name=\"" << escape(u) << "\"/>\n";
    else x << "    <Unit name=\"" << escape(u) << "\"><BaseUnit " << base << "/></Unit>\n";
  }
  x << "  </UnitDefinitions>\n";
}

void writeVariables(std::ostream& x, const std::vector<Variable>& table) {
  x << "  <ModelVariables>\n";
  for (std::size_t i = 0; i < table.size(); ++i) {
    const Variable& v = table[i];
    x << "    <!-- index " << i + 1 << " -->\n";
    x << "    <ScalarVariable name=\"" << escape(v.name) << "\" valueReference=\"" << v.valueReference
      << "\" causality=\"" << causalityName(v.causality) << "\" variability=\"" << variabilityName(v.variability)
      << "\"";
    // Parameters are exact; inputs take a start value but no initial attribute.
    if (v.causality == Causality::Parameter) x << " initial=\"exact\"";
    x << " description=\"" << escape(v.description) << "\">\n      <Real";
    if (!v.unit.empty()) x << " unit=\"" << escape(v.unit) << "\"";
    if (v.causality != Causality::Output) x << " start=\"" << number(v.start) << "\"";
    x << "/>\n    </ScalarVariable>\n";
  }
  x << "  </ModelVariables>\n";
}

// Outputs and the inputs they depend on at a fixed state (outputDependencies).
// Initial unknowns depend on all parameters and inputs (no dependencies
// attribute).
void writeStructure(std::ostream& x, const Scene& scene, const std::vector<Variable>& table) {
  bool anyOutput = false;
  for (const Variable& v : table) anyOutput = anyOutput || v.causality == Causality::Output;
  if (!anyOutput) {  // the schema wants no empty Outputs / InitialUnknowns
    x << "  <ModelStructure/>\n";
    return;
  }
  const Model model = assemble(scene);
  x << "  <ModelStructure>\n    <Outputs>\n";
  for (std::size_t i = 0; i < table.size(); ++i) {
    if (table[i].causality != Causality::Output) continue;
    std::string indices, kinds;
    for (const Dependency& d : outputDependencies(model, table, i)) {
      indices += (indices.empty() ? "" : " ") + std::to_string(d.input + 1);
      kinds += (kinds.empty() ? "" : " ") + std::string(d.constantFactor ? "constant" : "dependent");
    }
    x << "      <Unknown index=\"" << i + 1 << "\" dependencies=\"" << indices << "\"";
    if (!kinds.empty()) x << " dependenciesKind=\"" << kinds << "\"";
    x << "/>\n";
  }
  x << "    </Outputs>\n    <InitialUnknowns>\n";
  for (std::size_t i = 0; i < table.size(); ++i)
    if (table[i].causality == Causality::Output) x << "      <Unknown index=\"" << i + 1 << "\"/>\n";
  x << "    </InitialUnknowns>\n  </ModelStructure>\n";
}

// Outputs that the consistent accelerations or multipliers enter: they
// follow every input that acts as a force at once.
bool readsAccelerations(QuantityKind k) {
  return k == QuantityKind::JointReactionForce || k == QuantityKind::JointReactionTorque ||
         k == QuantityKind::JointDriveForce || k == QuantityKind::FlexibleBodyJointForce ||
         k == QuantityKind::FlexibleBodyJointTorque || k == QuantityKind::ElementSectionForce;
}

}  // namespace

int maxOutputDerivativeOrder(const Scene& scene) {
  if (scene.analysis != Analysis::Dynamic) return 0;
  return scene.flexibleBodies.empty() ? 2 : 1;
}
bool providesDirectionalDerivative(const Scene& scene) { return scene.analysis == Analysis::Dynamic; }

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
  auto flag = [](bool b) { return b ? "true" : "false"; };
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"" << escape(scene.name) << "\" guid=\"" << guid
    << "\" description=\"" << escape(scene.description) << "\" generationTool=\"MFBD-FMU mfbd-pack\""
    << " variableNamingConvention=\"structured\" numberOfEventIndicators=\"0\">\n"
    << "  <CoSimulation modelIdentifier=\"" << escape(modelIdentifier) << "\""
    << " needsExecutionTool=\"false\" canHandleVariableCommunicationStepSize=\"true\""
    << " canInterpolateInputs=\"false\" maxOutputDerivativeOrder=\"" << maxOutputDerivativeOrder(scene)
    << "\" canRunAsynchronuously=\"false\""
    << " canBeInstantiatedOnlyOncePerProcess=\"false\" canNotUseMemoryManagementFunctions=\"true\""
    << " canGetAndSetFMUstate=\"" << flag(caps.canGetAndSetFMUstate) << "\" canSerializeFMUstate=\""
    << flag(caps.canSerializeFMUstate) << "\" providesDirectionalDerivative=\""
    << flag(providesDirectionalDerivative(scene)) << "\"/>\n";
  writeUnits(x, table);
  x << "  <LogCategories>\n";
  for (const auto& [name, description] : logCategories())
    x << "    <Category name=\"" << name << "\" description=\"" << escape(description) << "\"/>\n";
  x << "  </LogCategories>\n";
  x << "  <DefaultExperiment startTime=\"" << number(scene.experiment.startTime) << "\" stopTime=\""
    << number(scene.experiment.stopTime) << "\" stepSize=\"" << number(scene.experiment.outputInterval)
    << "\"/>\n";
  writeVariables(x, table);
  writeStructure(x, scene, table);
  x << "</fmiModelDescription>\n";
  return x.str();
}

}  // namespace mfbd
