#include "flex/flexible_energy.hpp"

#include "flex/consistent_mass.hpp"

namespace mfbd {

FlexibleEnergy flexibleBodyEnergy(const FlexibleMesh& mesh, const FlexibleBody& body,
                                  const std::vector<NodeState>& nodes, const Vec3& gravity) {
  FlexibleEnergy e;
  for (int i = body.firstNode; i < body.firstNode + body.nodeCount; ++i) {
    const NodalInertia& in = mesh.nodes[i].inertia;
    const NodeState& s = nodes[i];
    e.kinetic += 0.5 * in.m * s.velocity.v.squaredNorm() + 0.5 * s.velocity.omega.dot(in.J * s.velocity.omega);
    e.gravity -= nodalGravityForce(in, gravity).head<3>().dot(s.pose.r);
  }
  for (int k = body.firstElement; k < body.firstElement + body.elementCount; ++k) {
    const FlexElement& el = mesh.elements[k];
    const LocalDeformation d = localDeformation(el.beam, nodes[el.node1].pose, nodes[el.node2].pose);
    Vec7 local;
    local << d.u, d.theta1, d.theta2;
    e.strain += localStrainEnergy(el.beam, local);
    if (el.mass > 0.0) {  // the consistent centre-line mass
      const NodeState &a = nodes[el.node1], &b = nodes[el.node2];
      const ConsistentEnergy c = consistentEnergy(el.beam, el.mass, a.pose, a.velocity, b.pose, b.velocity, gravity);
      e.kinetic += c.kinetic;
      e.gravity += c.gravity;
    }
  }
  return e;
}

}  // namespace mfbd
