// Scene flexible bodies -> FlexibleMesh: node coordinates and supports,
// elements from their reference poses and mass (consistent centre-line
// mass or lumped translational, lumped rotary), point masses,
// loads, drives and their FMI inputs.
#include <Eigen/Eigenvalues>

#include "flex/flexible_mesh.hpp"

namespace mfbd {

namespace {

// Columns of P and the coordinates a node's support leaves free.
void layOutNode(FlexNode& n, const SupportSpec* support, std::vector<CoordinateBlock>& blocks, Configuration& q0,
                VectorXd& v0, int& velocityCount) {
  using Kind = SupportSpec::Kind;
  const Kind kind = support ? support->kind : Kind::Clamp;
  int translations = 3;
  if (support) translations = kind == Kind::Slide ? 1 : 0;
  const bool freeRotation = !support || kind == Kind::Pin || kind == Kind::Slide;
  const int firstVelocity = velocityCount;
  if (translations > 0) {
    n.scalarOffset = int(q0.scalars.size());
    q0.scalars.conservativeResize(q0.scalars.size() + translations);
    q0.scalars.tail(translations).setZero();
    blocks.push_back({velocityCount, translations, n.scalarOffset, -1});
    for (int c = 0; c < translations; ++c) {
      n.dof[c] = velocityCount + c;
      n.P.block<3, 1>(0, c) = translations == 3 ? Vec3(Vec3::Unit(c)) : support->direction;
    }
    velocityCount += translations;
  }
  if (freeRotation) {
    n.rotation = int(q0.rotations.size());
    q0.rotations.push_back(n.reference.A);
    blocks.push_back({velocityCount, 3, -1, n.rotation});
    for (int c = 0; c < 3; ++c) {
      n.dof[3 + c] = velocityCount + c;
      n.P(3 + c, 3 + c) = 1.0;
    }
    velocityCount += 3;
  }
  v0.conservativeResize(velocityCount);
  v0.tail(velocityCount - firstVelocity).setZero();
  n.free = n.P == Mat6::Identity();
  for (int c = 0; c < 6; ++c) n.free = n.free && n.dof[c] == n.dof[0] + c;
}

// The body's nodes; a driven support gets its drive.
void addNodes(const FlexibleBodySpec& spec, FlexibleMesh& mesh, std::vector<CoordinateBlock>& blocks,
              Configuration& q0, VectorXd& v0, int& velocityCount) {
  std::vector<const SupportSpec*> supportOf(spec.nodes.size(), nullptr);
  for (const SupportSpec& s : spec.supports) supportOf[s.node] = &s;
  for (std::size_t i = 0; i < spec.nodes.size(); ++i) {
    FlexNode n;
    n.reference = {spec.nodes[i], spec.nodeOrientations[i]};
    const SupportSpec* s = supportOf[i];
    if (s && s->kind == SupportSpec::Kind::Driven) {
      n.drive = int(mesh.drives.size());
      FlexDrive d;
      d.axis = s->direction;
      d.angle = s->angle;
      if (s->rateInput) {
        d.inputOffset = mesh.inputCount;
        mesh.inputCount += 1;
      }
      mesh.drives.push_back(d);
    }
    layOutNode(n, s, blocks, q0, v0, velocityCount);
    mesh.nodes.push_back(n);
  }
}

// The body's elements and point masses, and their inertia on the nodes;
// returns the translational mass per node (the consistent mass's row sums
// lumped), to check it is there.
std::vector<double> addElementsAndMasses(const FlexibleBodySpec& spec, const FlexibleBody& body,
                                         const std::string& path, FlexibleMesh& mesh) {
  std::vector<double> translationalMass(spec.nodes.size(), 0.0);
  for (std::size_t e = 0; e < spec.elements.size(); ++e) {
    const int a = body.firstNode + spec.elements[e].first, c = body.firstNode + spec.elements[e].second;
    FlexElement el;
    el.node1 = a;
    el.node2 = c;
    el.damping = spec.damping;
    try {
      el.beam = CorotationalBeam::fromReference(mesh.nodes[a].reference, mesh.nodes[c].reference, spec.sectionY,
                                                spec.section);
    } catch (const std::invalid_argument& err) {
      throw SceneError(path + ".elements[" + std::to_string(e) + "]", err.what());
    }
    const bool lumped = spec.mass == BeamMass::Lumped;
    if (!lumped) el.mass = spec.section.rhoA * el.beam.L0;
    for (int k = 1; k <= 2; ++k) {
      const NodalInertia half = lumpedNodalInertia(el.beam, k);
      const int node = k == 1 ? a : c;
      NodalInertia& target = mesh.nodes[node].inertia;
      if (lumped) target.m += half.m;
      target.J += half.J;
      translationalMass[node - body.firstNode] += half.m;
    }
    mesh.elements.push_back(el);
  }
  for (const PointMassSpec& p : spec.pointMasses) {
    NodalInertia& target = mesh.nodes[body.firstNode + p.node].inertia;
    target.m += p.mass;
    target.J += p.inertia;
    translationalMass[p.node] += p.mass;
  }
  return translationalMass;
}

void addLoads(const FlexibleBodySpec& spec, const FlexibleBody& body, FlexibleMesh& mesh) {
  for (const NodalLoadSpec& l : spec.loads) {
    FlexLoad load;
    load.node = body.firstNode + l.node;
    load.force = l.force;
    load.moment = l.moment;
    load.follower = l.follower;
    load.scale = l.scale;
    if (l.input) {
      load.inputOffset = mesh.inputCount;
      mesh.inputCount += 6;
    }
    mesh.loads.push_back(load);
  }
}

// Dynamics needs inertia on every free DOF (a node no element touches has none).
void checkInertia(const FlexibleBodySpec& spec, const FlexibleBody& body, const std::string& path,
                  const FlexibleMesh& mesh, const std::vector<double>& translationalMass) {
  for (int i = 0; i < body.nodeCount; ++i) {
    const FlexNode& n = mesh.nodes[body.firstNode + i];
    const bool freeRotation = n.rotation >= 0;
    if ((n.scalarOffset >= 0 && !(translationalMass[i] > 0.0)) ||
        (freeRotation && !(Eigen::SelfAdjointEigenSolver<Mat3>(n.inertia.J).eigenvalues().minCoeff() > 0.0)))
      throw SceneError(path, "node " + std::to_string(i) + " of '" + spec.name +
                                 "' has no mass or rotary inertia on a free DOF; give the section rhoA and "
                                 "rhoJ > 0 or add a point mass");
  }
}

}  // namespace

void assembleFlexibleBodies(const Scene& scene, FlexibleMesh& mesh, std::vector<CoordinateBlock>& blocks,
                            Configuration& q0, VectorXd& v0, int& velocityCount) {
  for (std::size_t b = 0; b < scene.flexibleBodies.size(); ++b) {
    const FlexibleBodySpec& spec = scene.flexibleBodies[b];
    const std::string path = "flexible_bodies[" + std::to_string(b) + "]";
    const FlexibleBody body{spec.name, int(mesh.nodes.size()), int(spec.nodes.size()), int(mesh.elements.size()),
                            int(spec.elements.size())};
    addNodes(spec, mesh, blocks, q0, v0, velocityCount);
    const std::vector<double> translationalMass = addElementsAndMasses(spec, body, path, mesh);
    addLoads(spec, body, mesh);
    if (scene.analysis == Analysis::Dynamic) checkInertia(spec, body, path, mesh, translationalMass);
    mesh.bodies.push_back(body);
  }
}

}  // namespace mfbd
