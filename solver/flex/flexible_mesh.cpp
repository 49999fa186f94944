#include "flex/flexible_mesh.hpp"

#include <algorithm>

#include "flex/consistent_mass.hpp"
#include "flex/element_force_lanes.hpp"

namespace mfbd {

double DriveState::angle(const FlexibleMesh& mesh, const InputSignals& inputs, int drive, double t) const {
  const FlexDrive& d = mesh.drives[drive];
  if (d.inputOffset < 0) return d.angle(t);
  return startAngle[drive] + inputs.integral(d.inputOffset, stepStart, t);
}

void flexibleNodeStates(const FlexibleMesh& mesh, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                        double t, const DriveState& drives, const InputSignals& inputs, std::vector<NodeState>& nodes) {
  nodes.resize(mesh.nodes.size());
  for (std::size_t i = 0; i < mesh.nodes.size(); ++i) {
    const FlexNode& n = mesh.nodes[i];
    NodeState& s = nodes[i];
    if (n.free) {  // the usual node: 6 consecutive rates, P = I
      s.pose.r = n.reference.r + q.scalars.segment<3>(n.scalarOffset);
      s.velocity.v = v.segment<3>(n.dof[0]);
      s.acceleration.a = vdot.segment<3>(n.dof[0]);
      s.pose.A = q.rotations[n.rotation];
      s.velocity.omega = v.segment<3>(n.dof[3]);
      s.acceleration.omegaDot = vdot.segment<3>(n.dof[3]);
      continue;
    }
    // Translation: r = r0 + T x with T the first three rows of P.
    s.pose.r = n.reference.r;
    s.velocity.v.setZero();
    s.acceleration.a.setZero();
    for (int c = 0; c < 3; ++c) {
      if (n.dof[c] < 0) continue;
      s.pose.r += n.P.block<3, 1>(0, c) * q.scalars[n.scalarOffset + c];
      s.velocity.v += n.P.block<3, 1>(0, c) * v[n.dof[c]];
      s.acceleration.a += n.P.block<3, 1>(0, c) * vdot[n.dof[c]];
    }
    if (n.rotation >= 0) {
      s.pose.A = q.rotations[n.rotation];
      s.velocity.omega = v.segment<3>(n.dof[3]);
      s.acceleration.omegaDot = vdot.segment<3>(n.dof[3]);
    } else if (n.drive >= 0) {
      const FlexDrive& d = mesh.drives[n.drive];
      double angle, rate, acceleration;
      if (d.inputOffset >= 0) {
        angle = drives.angle(mesh, inputs, n.drive, t);
        rate = inputs.at(d.inputOffset, t);
        acceleration = inputs.rate(d.inputOffset, t);
      } else {
        if (drives.samples.size() != mesh.drives.size()) drives.samples.resize(mesh.drives.size());
        const Expression::Jet& law = d.angle.jet(t, drives.samples[n.drive]);
        angle = law.value;
        rate = law.first;
        acceleration = law.second;
      }
      s.pose.A = expSO3(d.axis * angle) * n.reference.A;
      // The axis is fixed in the world: omega_node = A^T axis rate, and its
      // derivative A^T axis rate_dot (the omega x omega term vanishes).
      s.velocity.omega = s.pose.A.transpose() * d.axis * rate;
      s.acceleration.omegaDot = s.pose.A.transpose() * d.axis * acceleration;
    } else {
      s.pose.A = n.reference.A;
      s.velocity.omega.setZero();
      s.acceleration.omegaDot.setZero();
    }
  }
}

namespace {

// External force and moment of a load on its node: [force world; moment node frame].
Vec6 loadVector(const FlexLoad& l, const NodeState& s, const VectorXd& inputs, double t) {
  Vec3 force = l.force, moment = l.moment;
  if (l.inputOffset >= 0) {
    force = inputs.segment<3>(l.inputOffset);
    moment = inputs.segment<3>(l.inputOffset + 3);
  } else {
    const double scale = l.scale(t);
    force *= scale;
    moment *= scale;
  }
  Vec6 f;
  if (l.follower) {
    f << s.pose.A * force, moment;
  } else {
    f << force, s.pose.A.transpose() * moment;
  }
  return f;
}

// Adds P^T g to r for a 6-vector g acting on node n.
void scatter(const FlexNode& n, const Vec6& g, VectorXd& r) {
  if (n.free) {
    r.segment<6>(n.dof[0]) += g;
    return;
  }
  for (int c = 0; c < 6; ++c)
    if (n.dof[c] >= 0) r[n.dof[c]] += n.P.col(c).dot(g);
}

bool isFree(const FlexNode& n) { return n.free; }

// Adds P_a^T B P_b to the triplets for a 6 x 6 block B coupling nodes a, b
// (B itself when both are free: P^T B P would give B exactly anyway).
void scatter(const FlexNode& a, const FlexNode& b, bool bothFree, const Mat6& B, Triplets& out) {
  if (bothFree) {  // consecutive dof: the block as it is, column by column as below
    const int i0 = a.dof[0], j0 = b.dof[0];
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) out.emplace_back(i0 + i, j0 + j, B(i, j));
    return;
  }
  const Mat6 projected = bothFree ? B : Mat6(a.P.transpose() * B * b.P);
  for (int i = 0; i < 6; ++i) {
    if (a.dof[i] < 0) continue;
    for (int j = 0; j < 6; ++j)
      if (b.dof[j] >= 0) out.emplace_back(a.dof[i], b.dof[j], projected(i, j));
  }
}

void scatter(const FlexNode& a, const FlexNode& b, const Mat6& B, Triplets& out) {
  scatter(a, b, isFree(a) && isFree(b), B, out);
}

// Whether the element's consistent mass acts: in dynamics, or in statics
// under gravity (its weight); a static study without gravity skips it.
bool carriesMass(const FlexElement& e, const Vec3& gravity, bool withInertia) {
  return e.mass > 0.0 && (withInertia || gravity != Vec3::Zero());
}

}  // namespace

namespace {

// f += the element's consistent inertia less its weight, where it carries mass.
void addElementInertia(const FlexElement& e, const NodeState& s1, const NodeState& s2, const Vec3& gravity,
                     bool withInertia, Vec12& f) {
  if (!carriesMass(e, gravity, withInertia)) return;
  if (withInertia) {
    f += consistentInertiaForce(e.beam, e.mass, s1.pose, s1.velocity, s1.acceleration, s2.pose, s2.velocity,
                                s2.acceleration, gravity);
  } else {  // statics: the consistent weight alone
    f += consistentInertiaForce(e.beam, e.mass, s1.pose, {}, {}, s2.pose, {}, {}, gravity);
  }
}

}  // namespace

bool elementForce(const FlexElement& e, const NodeState& s1, const NodeState& s2, const Vec3& gravity,
                  bool withInertia, Vec12& f) {
  if (!internalForceVector(e.beam, s1.pose, s2.pose, s1.velocity, s2.velocity, e.damping, f)) return false;
  addElementInertia(e, s1, s2, gravity, withInertia, f);
  return true;
}

bool flexibleResidual(const FlexibleMesh& mesh, const std::vector<NodeState>& nodes, const Vec3& gravity,
                      const VectorXd& inputs, double t, bool withInertia, VectorXd& r) {
  for (std::size_t i = 0; i < mesh.nodes.size(); ++i) {
    const FlexNode& n = mesh.nodes[i];
    Vec6 g = -nodalGravityForce(n.inertia, gravity);
    if (withInertia) g += nodalInertiaForce(n.inertia, nodes[i].velocity, nodes[i].acceleration);
    scatter(n, g, r);
  }
  // elementForce of kForceLanes elements at a time, side by side in vector
  // lanes (elementForceVectors; statics' consistent weight one by one).
  const int count = int(mesh.elements.size());
  for (int first = 0; first < count; first += kForceLanes) {
    const int lanes = std::min(kForceLanes, count - first);
    ElementInputs inputs[kForceLanes];
    for (int i = 0; i < lanes; ++i) {
      const FlexElement& e = mesh.elements[first + i];
      const NodeState &s1 = nodes[e.node1], &s2 = nodes[e.node2];
      const double mass = withInertia ? e.mass : 0.0;  // e.mass: 0 where lumped into the nodes
      inputs[i] = {&e.beam, e.damping, mass, &s1.pose, &s2.pose, &s1.velocity, &s2.velocity, &s1.acceleration,
                   &s2.acceleration};
    }
    Vec12 f[kForceLanes];
    if (!elementForceVectors(lanes, inputs, gravity, f)) return false;
    for (int i = 0; i < lanes; ++i) {
      const FlexElement& e = mesh.elements[first + i];
      if (!withInertia) addElementInertia(e, nodes[e.node1], nodes[e.node2], gravity, withInertia, f[i]);
      scatter(mesh.nodes[e.node1], f[i].head<6>(), r);
      scatter(mesh.nodes[e.node2], f[i].tail<6>(), r);
    }
  }
  for (const FlexLoad& l : mesh.loads) scatter(mesh.nodes[l.node], -loadVector(l, nodes[l.node], inputs, t), r);
  return true;
}

void flexibleTangent(const FlexibleMesh& mesh, const std::vector<NodeState>& nodes, const Vec3& gravity,
                     const VectorXd& inputs, double t, bool withInertia, double cM, double cC, double cK,
                     Triplets& iteration) {
  for (std::size_t i = 0; i < mesh.nodes.size(); ++i) {
    const FlexNode& n = mesh.nodes[i];
    Mat6 S = Mat6::Zero();  // statics (cM = cC = 0): zeros, for the same pattern
    if (cM != 0.0 || cC != 0.0) {
      const NodalInertiaForces in = nodalInertiaForces(n.inertia, nodes[i].velocity, nodes[i].acceleration);
      S = cM * in.M + cC * in.G;
    }
    scatter(n, n, S, iteration);
  }
  for (const FlexElement& e : mesh.elements) {
    const NodeState &s1 = nodes[e.node1], &s2 = nodes[e.node2];
    // A mass matrix alone (consistent initial accelerations) needs no element
    // tangent; its zero blocks still go in, so the pattern is the same.
    Mat12 S = Mat12::Zero();
    if (cK != 0.0 || cC != 0.0) {
      const BeamTangent f = internalForceTangent(e.beam, s1.pose, s2.pose, s1.velocity, s2.velocity, e.damping);
      S = cK * f.K + cC * f.C;
    }
    if (carriesMass(e, gravity, withInertia)) {
      // Statics: the consistent weight's K alone (cM = cC = 0).
      S += withInertia ? consistentInertia(e.beam, e.mass, s1.pose, s1.velocity, s1.acceleration, s2.pose,
                                           s2.velocity, s2.acceleration, gravity, cM, cC, cK).S
                       : consistentInertia(e.beam, e.mass, s1.pose, {}, {}, s2.pose, {}, {}, gravity, 0.0, 0.0, cK).S;
    }
    const FlexNode &a = mesh.nodes[e.node1], &b = mesh.nodes[e.node2];
    const bool freeA = isFree(a), freeB = isFree(b);
    scatter(a, a, freeA, S.topLeftCorner<6, 6>(), iteration);
    scatter(a, b, freeA && freeB, S.topRightCorner<6, 6>(), iteration);
    scatter(b, a, freeA && freeB, S.bottomLeftCorner<6, 6>(), iteration);
    scatter(b, b, freeB, S.bottomRightCorner<6, 6>(), iteration);
  }
  // Loads that turn with the node: d(-f_ext)/d[dr; dtheta].
  for (const FlexLoad& l : mesh.loads) {
    const Vec6 f = loadVector(l, nodes[l.node], inputs, t);
    Mat6 K = Mat6::Zero();
    if (l.follower) {
      // f_world = A f_local: d/dtheta = -A skew(f_local); minus for the residual.
      K.block<3, 3>(0, 3) = nodes[l.node].pose.A * skew(nodes[l.node].pose.A.transpose() * f.head<3>());
    } else {
      // m_node = A^T m_world: d/dtheta = skew(m_node); minus for the residual.
      K.block<3, 3>(3, 3) = -skew(f.tail<3>());
    }
    scatter(mesh.nodes[l.node], mesh.nodes[l.node], cK * K, iteration);
  }
}

}  // namespace mfbd
