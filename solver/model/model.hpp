// Model: everything constant after assembly (topology, inertias, joint
// frames, index offsets), as in Pinocchio. Data (data.hpp) holds all
// workspace. Bodies are numbered so that parent[i] < i: recursions over the
// tree are plain forward (positions, velocities) and backward (forces) loops.
#pragma once
#include <string>
#include <vector>

#include "coupling/flexible_body_joint.hpp"
#include "flex/flexible_mesh.hpp"
#include "math/configuration.hpp"
#include "scene/scene.hpp"

namespace mfbd {

inline constexpr int kGroundIndex = -1;

// A frame fixed in a body: origin and orientation in the body frame. Joints
// and force elements are written against markers only (docs/design.md 2).
struct Marker {
  int body = kGroundIndex;
  Vec3 position = Vec3::Zero();
  Mat3 orientation = Mat3::Identity();
};

// A rigid body. Its solver frame sits at the centre of mass, axes parallel
// to the user's body frame, so the body mass matrix is diag(m I, J).
struct Body {
  std::string name;
  bool isVirtual = false;              // massless, welded to a flexible node
  double mass = 0.0;
  Mat3 inertia = Mat3::Zero();         // about the centre of mass, body axes
  Vec3 centerOfMass = Vec3::Zero();    // user body frame origin -> centre of mass, body axes
  int parent = kGroundIndex;           // parent body, < own index
  int inboardJoint = -1;               // the tree joint whose child this body is
};

struct Joint {
  std::string name;
  JointType type = JointType::Revolute;
  Marker parentMarker;  // on the parent body (or ground)
  Marker childMarker;   // on the child body
  int dofs = 0;
  int velocityOffset = 0;  // into v
  int scalarOffset = -1;   // its scalar coordinates in Configuration::scalars
  int rotation = -1;       // its stored rotation in Configuration::rotations
  bool cut = false;
  bool actuated = false;   // generalized force input along its DOFs
  bool keepRates = false;  // assembly keeps its initial rates (others adjust to the constraints)
  int inputOffset = -1;    // into the joint input vector: forces along its DOFs, or its drive rate
  double damping = 0.0;    // tunable
  int constraintOffset = -1;  // cut joints and drives: first row in Phi (and lambda)
  double springStiffness = 0.0, springDamping = 0.0, springFreeCoordinate = 0.0;  // rotational spring-damper
  bool driven = false;        // coordinate = drive(t), a constraint row (lambda: minus the drive force)
  TimeFunction drive;
  bool driveRateInput = false;  // drive(t) integrates the rate input at inputOffset (System::driveCoordinate)
};

// A force element between markers (rigid/force_elements.hpp applies it).
struct ForceElement {
  enum class Kind { SpringDamper, Bushing, AppliedForce };
  std::string name;
  Kind kind = Kind::SpringDamper;
  Marker marker1, marker2;      // applied force: marker1 only
  double stiffness = 0.0, damping = 0.0, freeLength = 0.0;  // spring-damper
  Vec6 bushingStiffness = Vec6::Zero(), bushingDamping = Vec6::Zero();  // in marker1's frame
  bool bodyFrame = false;       // applied force: components in marker1's frame (else world)
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();  // applied force without inputs: times scale(t)
  TimeFunction scale;
  int inputOffset = -1;         // actuator force (1) or applied force and torque (6)
};

struct Model {
  std::string name;
  std::vector<Body> bodies;     // topological order
  std::vector<Joint> joints;    // tree joints (joints[bodies[i].inboardJoint]) and cut joints
  Vec3 gravity = Vec3::Zero();
  SolverSection::NewtonMatrix newtonMatrix = SolverSection::NewtonMatrix::Automatic;  // the System's form
  FlexibleMesh flexible;        // nodes, beam elements, supports, loads, drives
  std::vector<ForceElement> forces;  // between markers on bodies
  std::vector<FlexibleBodyJoint> flexibleBodyJoints;  // virtual body <-> flexible node welds
  int forceInputCount = 0;
  Analysis analysis = Analysis::Dynamic;
  std::vector<CoordinateBlock> blocks;  // the configuration manifold
  int rigidVelocityCount = 0;   // joint rates come first in v, then flexible nodes
  int velocityCount = 0;
  int jointInputCount = 0;
  int constraintCount = 0;      // rows of Phi: drives, cut joints, flexible body joints
  Configuration initialConfiguration;
  VectorXd initialVelocity;
};

// Builds the Model of a validated scene. Throws SceneError for what the
// solver cannot (yet) do with an otherwise valid scene.
Model assemble(const Scene& scene);

int findBody(const Model& model, const std::string& name);   // -1 if absent
int findJoint(const Model& model, const std::string& name);  // -1 if absent

}  // namespace mfbd
