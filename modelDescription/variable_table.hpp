// The variable table of a scene: every FMI variable with its value reference,
// causality, variability, unit and the solver quantity behind it. The one
// source of value references: the packer writes modelDescription.xml from it
// and the FMU binary builds the same table at fmi2Instantiate.
#pragma once
#include <string>
#include <vector>

#include "model/model_numbering.hpp"
#include "simulation.hpp"

namespace mfbd {

enum class Causality { Parameter, Input, Output };
enum class Variability { Fixed, Tunable, Continuous };

struct Variable {
  std::string name;
  unsigned valueReference = 0;
  Causality causality = Causality::Output;
  Variability variability = Variability::Continuous;
  std::string unit;
  std::string description;
  Quantity quantity{QuantityKind::JointCoordinate};
  double start = 0.0;  // parameters and inputs
};

// The variables of a scene, at the numbers its assembled model gave.
std::vector<Variable> variableTable(const Scene& scene, const ModelNumbering& model);

// GUID of an FMU made from this scene text: a hash of the text and of the
// variable-table format, so a binary built for another table refuses it.
std::string sceneGuid(const std::string& sceneText);

// Log categories the binary knows, with their descriptions (declared in
// modelDescription.xml).
const std::vector<std::pair<std::string, std::string>>& logCategories();

// Names of a joint kind's coordinates ("angle", "x", ...), one per DOF.
std::vector<std::string> jointCoordinateNames(JointType type);

// Time derivatives of outputs and partial derivatives of outputs with
// respect to inputs: in dynamics (a static analysis has no motion to
// differentiate and its outputs follow the inputs only through a step).
int maxOutputDerivativeOrder(const Scene& scene);
bool providesDirectionalDerivative(const Scene& scene);

}  // namespace mfbd
