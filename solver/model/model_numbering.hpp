// ModelNumbering: the numbers assembly gave to what a scene names and the
// FMU exposes: the offsets of inputs in the System's input vectors, mesh
// nodes and elements, flexible body joints and spring-dampers. The one
// place the variable table reads an assembled Model through.
#pragma once
#include <string>
#include <vector>

#include "model/model.hpp"

namespace mfbd {

class ModelNumbering {
 public:
  explicit ModelNumbering(const Model& model) : model_(model) {}

  // Force elements with inputs, in model order: a spring-damper's actuator
  // force (one input) or an applied force and torque (six), at `offset`
  // into the System's force inputs.
  struct ForceInput {
    std::string name;
    bool actuator = false;
    bool bodyFrame = false;  // applied force: components in the body frame
    int offset = 0;
  };
  std::vector<ForceInput> forceInputs() const;

  // Inputs of flexible nodes, at `offset` into the System's flexible
  // inputs: the rotation rates of rate-driven supports (one each, node
  // order), then input loads (six each, load order). `node` names the node
  // as "<flexible body>.node<i>".
  struct NodeInput {
    std::string node;
    bool driveRate = false;  // else a load
    bool follower = false;   // load components in the node frame
    int offset = 0;
  };
  std::vector<NodeInput> nodeInputs() const;

  // Spring-dampers: their index among the model's force elements and name.
  std::vector<std::pair<int, std::string>> springDampers() const;
  // Names of the flexible body joints; their position is their index.
  std::vector<std::string> flexibleBodyJoints() const;
  // Mesh node and element of a flexible body's (scene order) node or element.
  int node(int flexibleBody, int node) const { return model_.flexible.bodies[flexibleBody].firstNode + node; }
  int element(int flexibleBody, int element) const {
    return model_.flexible.bodies[flexibleBody].firstElement + element;
  }

 private:
  std::string nodeName(int node) const;
  const Model& model_;
};

}  // namespace mfbd
