// The flexible part of a Model: nodal bodies (position and orientation),
// corotational beam elements, supports eliminated from the unknowns, nodal
// loads and drives; and its contribution to the system residual and tangent.
//
// A node's pose is r = r0 + T x (x: its free translation coordinates, T a
// 3 x k basis: I when free, a direction when sliding, none when fixed) and
// A = stored rotation (free) or the prescribed A(t) = exp(axis angle(t)) A0
// (clamped: angle = 0). Its velocity is [rdot (world); omega (node frame)].
// The map P (6 x 6) from the node's entries in v to [rdot; omega] has zero
// columns for fixed directions; element and inertia blocks are projected
// with it (P^T K P), so supports never appear as equations.
#pragma once
#include <limits>
#include <string>
#include <vector>

#include "flex/corotational_beam.hpp"
#include "math/configuration.hpp"
#include "math/input_signals.hpp"
#include "math/triplets.hpp"
#include "scene/scene.hpp"

namespace mfbd {

struct FlexNode {
  NodePose reference;
  int scalarOffset = -1;  // free translation coordinates in Configuration::scalars
  int rotation = -1;      // stored rotation (free) or -1 (prescribed)
  int drive = -1;         // prescribed rotation: index into FlexibleMesh::drives, -1 = clamped
  std::array<int, 6> dof{{-1, -1, -1, -1, -1, -1}};  // velocity index of each column of P, -1 if fixed
  Mat6 P = Mat6::Zero();
  // P = I with consecutive dof (most of a mesh): its blocks and vectors go
  // in unprojected (P^T B P and P^T g would give them exactly anyway).
  bool free = false;
  NodalInertia inertia;
};

struct FlexElement {
  int node1 = 0, node2 = 0;  // mesh node indices
  CorotationalBeam beam;
  double damping = 0.0;
  // rhoA L0 of the consistent centre-line mass (flex/consistent_mass.hpp);
  // 0 when the element's mass is lumped into its nodes' inertia.
  double mass = 0.0;
};

struct FlexLoad {
  int node = 0;
  Vec3 force = Vec3::Zero(), moment = Vec3::Zero();
  bool follower = false;
  TimeFunction scale;
  int inputOffset = -1;  // six load inputs (force, moment) when >= 0
};

// Rotation of a driven node about a world axis: angle(t), or integrated from
// a rate input (angle = start angle + rate (t - step start)).
struct FlexDrive {
  Vec3 axis = Vec3::UnitZ();
  TimeFunction angle;
  int inputOffset = -1;
};

struct FlexibleBody {
  std::string name;
  int firstNode = 0, nodeCount = 0;
  int firstElement = 0, elementCount = 0;
};

struct FlexibleMesh {
  std::vector<FlexibleBody> bodies;
  std::vector<FlexNode> nodes;
  std::vector<FlexElement> elements;
  std::vector<FlexLoad> loads;
  std::vector<FlexDrive> drives;
  int inputCount = 0;  // load components and drive rates
  bool empty() const { return nodes.empty(); }
};

// Appends the flexible bodies of a scene: nodes to the configuration blocks
// and velocities (after `velocityCount`), elements, loads, drives, inputs.
void assembleFlexibleBodies(const Scene& scene, FlexibleMesh& mesh, std::vector<CoordinateBlock>& blocks,
                            Configuration& q0, VectorXd& v0, int& velocityCount);

// Node poses, velocities and accelerations at time t.
struct NodeState {
  NodePose pose;
  NodeVelocity velocity;
  NodeAcceleration acceleration;
};

// Drive angles and the rate-input state of a step.
struct DriveState {
  std::vector<double> startAngle;  // rate-input drives: angle at the step start
  double stepStart = 0.0;
  double angle(const FlexibleMesh& mesh, const InputSignals& inputs, int drive, double t) const;
  // Per drive: a time-function drive's angle, rate and acceleration for
  // the last time asked (TimeFunction::Sample).
  mutable std::vector<TimeFunction::Sample> samples;
};

void flexibleNodeStates(const FlexibleMesh& mesh, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                        double t, const DriveState& drives, const InputSignals& inputs, std::vector<NodeState>& nodes);

// What the nodes exert on element e, [f1 (world); m1 (node 1 frame); f2; m2]:
// its internal force and, with consistent mass, its inertia minus its weight
// (weight only without inertia, in statics). The element's end forces, so
// also the section forces at its ends: with consistent mass they converge
// faster than the internal force alone (nodal reactions of a Galerkin mesh).
// False if the corotated frame is undefined.
bool elementForce(const FlexElement& e, const NodeState& s1, const NodeState& s2, const Vec3& gravity,
                  bool withInertia, Vec12& f);

// r += inertia + internal forces - gravity - loads, on the free node DOFs.
// Returns false if an element's corotated frame is undefined.
bool flexibleResidual(const FlexibleMesh& mesh, const std::vector<NodeState>& nodes, const Vec3& gravity,
                      const VectorXd& inputs, double t, bool withInertia, VectorXd& r);

// cM M + cC C + cK K of the same terms, projected on the free DOFs
// (without inertia, cM and cC must be 0: K of the weight and loads alone).
void flexibleTangent(const FlexibleMesh& mesh, const std::vector<NodeState>& nodes, const Vec3& gravity,
                     const VectorXd& inputs, double t, bool withInertia, double cM, double cC, double cK,
                     Triplets& iteration);

}  // namespace mfbd
