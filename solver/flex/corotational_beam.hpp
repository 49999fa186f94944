// Two-node 3D corotational beam element (docs/design.md 3 "Flexible bodies").
//
// Element-independent corotational formulation after Battini & Pacoste,
// "Co-rotational beam elements with warping effects in instability problems",
// CMAME 191 (2002): the corotated frame has x along the current
// chord and y, z from the mean of the two nodes' section y axes (their
// variant of Crisfield's mean-rotation frame, same invariance, simpler
// derivative).
// Local deformations e_l = [u; theta1; theta2] (elongation and rotation
// vectors of the nodes relative to the corotated frame, logSO3) carry a local
// Timoshenko element whose axial strain is the shallow arch's (localElastic-
// Force below); f = B^T f_l with the consistent tangent
// K = B^T K_t B + d(B^T)/dq f_l, K_t = df_l/de_l.
//
// Node and force conventions are those of flex/nodal_inertia.hpp; element
// vectors are ordered [f1 (world); m1 (node-1 frame); f2; m2], tangents are
// derivatives with respect to the increments [dr1; dtheta1; dr2; dtheta2].
#pragma once
#include "scene/beam_section.hpp"
#include "flex/nodal_inertia.hpp"

namespace mfbd {

using Vec7 = Eigen::Matrix<double, 7, 1>;
using Mat7 = Eigen::Matrix<double, 7, 7>;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

// Constant data of one element, fixed by its stress-free reference.
struct CorotationalBeam {
  // Reference (stress-free) poses of the two nodes. The element frame E0 has
  // x along the reference chord and y = sectionY orthogonalised against x.
  // Throws std::invalid_argument if the nodes coincide or sectionY is
  // (nearly) parallel to the chord.
  static CorotationalBeam fromReference(const NodePose& n1, const NodePose& n2,
                                        const Vec3& sectionY,
                                        const BeamSection& section);

  double L0 = 0.0;  // reference length [m]
  // Element frame seen from each node: A_i0 * C_i = E0, so A_i * C_i is
  // node i's copy of the element frame in any configuration.
  Mat3 C1 = Mat3::Identity();
  Mat3 C2 = Mat3::Identity();
  // C1, C2 exactly the identity (nodes oriented like the element, as a beam
  // line makes them): products with them are skipped, which gives the same
  // numbers.
  bool identityC1 = true, identityC2 = true;
  BeamSection section;
  Mat7 localStiffness = Mat7::Zero();  // linear, on [u; theta1; theta2]
};

// The local element's elasticity. Its axial strain is the mean strain of the
// shallow arch through the cubic deflection line the end rotations make
// (Crisfield, "Non-linear finite element analysis of solids and
// structures" vol. 1, 1991; Le, Battini & Hjiaj, Comput. Struct. 89, 2011),
//   eps = u / L0 + q,  q = (2 a1^2 - a1 a2 + 2 a2^2 + 2 b1^2 - b1 b2 + 2 b2^2) / 30,
// a_i, b_i the bending rotations theta_i,y and theta_i,z, with the energy
//   1/2 EA L0 eps^2 + 1/2 e_l^T K_l e_l - 1/2 (EA / L0) u^2
// (K_l: localStiffness, the linear Timoshenko matrix). The axial force
// N = EA eps then carries the bowing of the element between its nodes: the
// local geometric stiffness N L0 / 30 [4 -1; -1 4] on each bending pair,
// which the chord's rotation alone (the corotational part) misses, and a
// pure bending moment gives the circle's chord shortening with N = 0 (with
// the linear local element it would compress the bar). Both leave an
// O(L0^2) error per element otherwise.
Vec7 localElasticForce(const CorotationalBeam& beam, const Vec7& e);
// K_t - K_l: what the shallow arch adds to the local tangent.
Mat7 localTangentExcess(const CorotationalBeam& beam, const Vec7& e);
double localStrainEnergy(const CorotationalBeam& beam, const Vec7& e);

// Local deformations and corotated frame of a configuration (for outputs).
struct LocalDeformation {
  Mat3 frame = Mat3::Identity();  // corotated element frame (columns e1 e2 e3, world)
  double length = 0.0;            // current chord length
  double u = 0.0;                 // elongation l - L0
  Vec3 theta1 = Vec3::Zero();     // log(frame^T A1 C1)
  Vec3 theta2 = Vec3::Zero();
  bool valid = false;             // false: frame undefined (see internalForceVector)
};

LocalDeformation localDeformation(const CorotationalBeam& beam, const NodePose& n1,
                                  const NodePose& n2);

// Internal force of elasticity plus stiffness-proportional damping,
//   f = B^T (K_l e_l + beta K_l edot_l),   edot_l = B [v1; omega1; v2; omega2],
// the force the nodes exert on the element (residual: M a + f = f_ext).
// False (f untouched) when the corotated frame is undefined: a collapsed
// chord, or local rotations near 90 deg / relative twist near 180 deg;
// callers treat it as a failed Newton iterate. Four elements at once:
// flex/element_force_lanes.hpp (the same kernel, flex/corotational_force.hpp).
bool internalForceVector(const CorotationalBeam& beam, const NodePose& n1, const NodePose& n2,
                         const NodeVelocity& v1, const NodeVelocity& v2, double dampingBeta, Vec12& f);

// Its tangent:
//   K = df/d[dr1; dtheta1; dr2; dtheta2] at fixed velocities (exact, the
//       damping force's position dependence included),
//   C = df/d[v1; omega1; v2; omega2] = beta B^T K_l B;
// valid = false (K, C zero) where the corotated frame is undefined.
struct BeamTangent {
  Mat12 K = Mat12::Zero();
  Mat12 C = Mat12::Zero();
  bool valid = false;
};

BeamTangent internalForceTangent(const CorotationalBeam& beam, const NodePose& n1, const NodePose& n2,
                                 const NodeVelocity& v1, const NodeVelocity& v2, double dampingBeta);

// Stress resultants at the element ends in the corotated element frame,
// force (N, Vy, Vz) and moment (T, My, Mz); at each end the action of the
// part at larger x on the part at smaller x (N > 0 in tension), computed
// from the forces f the nodes exert on the element: internalForceVector's f, plus
// the element's own inertia minus weight when it has mass (elementForce in
// flex/flexible_mesh.hpp).
struct SectionForces {
  Vec3 force1 = Vec3::Zero(), moment1 = Vec3::Zero();  // at node 1 (x = 0)
  Vec3 force2 = Vec3::Zero(), moment2 = Vec3::Zero();  // at node 2 (x = l)
};

SectionForces sectionForces(const CorotationalBeam& beam, const NodePose& n1,
                            const NodePose& n2, const Vec12& f);

// Lumped inertia of half the element at node 1 or 2 (node = 1 or 2):
// m = rhoA L0 / 2, J = C_i diag(rhoJ) C_i^T L0 / 2 in the node frame.
NodalInertia lumpedNodalInertia(const CorotationalBeam& beam, int node);

}  // namespace mfbd
