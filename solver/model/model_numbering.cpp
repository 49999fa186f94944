#include "model/model_numbering.hpp"

namespace mfbd {

std::vector<ModelNumbering::ForceInput> ModelNumbering::forceInputs() const {
  std::vector<ForceInput> out;
  for (const ForceElement& e : model_.forces)
    if (e.inputOffset >= 0)
      out.push_back({e.name, e.kind == ForceElement::Kind::SpringDamper, e.bodyFrame, e.inputOffset});
  return out;
}

std::string ModelNumbering::nodeName(int node) const {
  for (const FlexibleBody& fb : model_.flexible.bodies)
    if (node >= fb.firstNode && node < fb.firstNode + fb.nodeCount)
      return fb.name + ".node" + std::to_string(node - fb.firstNode);
  return "?";
}

std::vector<ModelNumbering::NodeInput> ModelNumbering::nodeInputs() const {
  const FlexibleMesh& mesh = model_.flexible;
  std::vector<NodeInput> out;
  for (std::size_t n = 0; n < mesh.nodes.size(); ++n) {
    const int d = mesh.nodes[n].drive;
    if (d >= 0 && mesh.drives[d].inputOffset >= 0) out.push_back({nodeName(int(n)), true, false, mesh.drives[d].inputOffset});
  }
  for (const FlexLoad& l : mesh.loads)
    if (l.inputOffset >= 0) out.push_back({nodeName(l.node), false, l.follower, l.inputOffset});
  return out;
}

std::vector<std::pair<int, std::string>> ModelNumbering::springDampers() const {
  std::vector<std::pair<int, std::string>> out;
  for (int f = 0; f < int(model_.forces.size()); ++f)
    if (model_.forces[f].kind == ForceElement::Kind::SpringDamper) out.emplace_back(f, model_.forces[f].name);
  return out;
}

std::vector<std::string> ModelNumbering::flexibleBodyJoints() const {
  std::vector<std::string> out;
  for (const FlexibleBodyJoint& w : model_.flexibleBodyJoints) out.push_back(w.name);
  return out;
}

}  // namespace mfbd
