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

// Outputs: positions and velocities do not depend directly on inputs; joint
// reactions do (through the accelerations). Initial unknowns depend on all
// parameters and inputs (no dependencies attribute).
void writeStructure(std::ostream& x, const std::vector<Variable>& table) {
  std::string inputs;
  for (std::size_t i = 0; i < table.size(); ++i)
    if (table[i].causality == Causality::Input) inputs += (inputs.empty() ? "" : " ") + std::to_string(i + 1);
  bool anyOutput = false;
  for (const Variable& v : table) anyOutput = anyOutput || v.causality == Causality::Output;
  if (!anyOutput) {  // the schema wants no empty Outputs / InitialUnknowns
    x << "  <ModelStructure/>\n";
    return;
  }
  x << "  <ModelStructure>\n    <Outputs>\n";
  for (std::size_t i = 0; i < table.size(); ++i) {
    if (table[i].causality != Causality::Output) continue;
    const QuantityKind k = table[i].quantity.kind;
    const bool feedthrough = k == QuantityKind::JointReactionForce || k == QuantityKind::JointReactionTorque ||
                             k == QuantityKind::JointDriveForce ||
                             (k == QuantityKind::SpringLength && table[i].quantity.component == 2);
    x << "      <Unknown index=\"" << i + 1 << "\" dependencies=\"" << (feedthrough ? inputs : "") << "\"/>\n";
  }
  x << "    </Outputs>\n    <InitialUnknowns>\n";
  for (std::size_t i = 0; i < table.size(); ++i)
    if (table[i].causality == Causality::Output) x << "      <Unknown index=\"" << i + 1 << "\"/>\n";
  x << "    </InitialUnknowns>\n  </ModelStructure>\n";
}

}  // namespace

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
    << " canInterpolateInputs=\"false\" maxOutputDerivativeOrder=\"0\" canRunAsynchronuously=\"false\""
    << " canBeInstantiatedOnlyOncePerProcess=\"false\" canNotUseMemoryManagementFunctions=\"true\""
    << " canGetAndSetFMUstate=\"" << flag(caps.canGetAndSetFMUstate) << "\" canSerializeFMUstate=\""
    << flag(caps.canSerializeFMUstate) << "\" providesDirectionalDerivative=\"false\"/>\n";
  writeUnits(x, table);
  x << "  <LogCategories>\n";
  for (const auto& [name, description] : logCategories())
    x << "    <Category name=\"" << name << "\" description=\"" << escape(description) << "\"/>\n";
  x << "  </LogCategories>\n";
  x << "  <DefaultExperiment startTime=\"" << number(scene.experiment.startTime) << "\" stopTime=\""
    << number(scene.experiment.stopTime) << "\" tolerance=\"" << number(scene.experiment.tolerance)
    << "\" stepSize=\"" << number(scene.experiment.outputInterval) << "\"/>\n";
  writeVariables(x, table);
  writeStructure(x, table);
  x << "</fmiModelDescription>\n";
  return x.str();
}

}  // namespace mfbd
