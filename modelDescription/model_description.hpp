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

std::string modelDescriptionXml(const Scene& scene, const std::vector<Variable>& table, const std::string& guid,
                                const std::string& modelIdentifier, const Capabilities& caps);

// Log categories the binary knows, with their descriptions.
const std::vector<std::pair<std::string, std::string>>& logCategories();

}  // namespace mfbd
