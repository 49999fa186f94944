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

std::string modelDescriptionXml(const Scene& scene, const std::vector<Variable>& table, const std::string& guid,
                                const std::string& modelIdentifier, const Capabilities& caps);

}  // namespace mfbd
