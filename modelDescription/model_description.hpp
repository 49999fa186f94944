// modelDescription.xml of a scene, written from its variable table.
#pragma once
#include <string>
#include <vector>

#include "variable_table.hpp"

namespace mfbd {

// Capabilities the FMU binary honours; the XML declares exactly these.
struct Capabilities {
  bool canGetAndSetFMUstate = false;
  bool canSerializeFMUstate = false;
};

// Time derivatives of outputs and partial derivatives of outputs with
// respect to inputs: in dynamics (a static analysis has no motion to
// differentiate and its outputs follow the inputs only through a step).
int maxOutputDerivativeOrder(const Scene& scene);
bool providesDirectionalDerivative(const Scene& scene);

// The inputs (table indices) that output `output` depends on at a fixed
// state, as ModelStructure declares them; `constantFactor` per input when
// the output is that input times a constant plus terms of the state.
struct Dependency {
  std::size_t input;
  bool constantFactor;
};
std::vector<Dependency> outputDependencies(const Model& model, const std::vector<Variable>& table, std::size_t output);

std::string modelDescriptionXml(const Scene& scene, const std::vector<Variable>& table, const std::string& guid,
                                const std::string& modelIdentifier, const Capabilities& caps);

// Log categories the binary knows, with their descriptions.
const std::vector<std::pair<std::string, std::string>>& logCategories();

}  // namespace mfbd
