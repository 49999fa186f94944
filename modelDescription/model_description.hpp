// modelDescription.xml of a scene, written from its variable table.
#pragma once
#include <string>
#include <vector>

#include "variable_table.hpp"

namespace mfbd {

// Capabilities the FMU binary honours; the XML declares exactly these.
struct Capabilities {
  bool canGetAndSetFMUstate = true;
  bool canSerializeFMUstate = true;
  bool canInterpolateInputs = true;
  // Highest order fmi2SetRealInputDerivatives takes (InputSignals::kMaxOrder):
  // FMI 2.0 has no attribute for it; a VendorAnnotations entry says it.
  int maxInputDerivativeOrder = 2;
};

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

}  // namespace mfbd
