// Scene: the plain, validated description of a mechanism, in SI units.
// Produced by parseScene() from scene JSON (see README "Scene format" and
// scene.schema.json); consumed by assemble() to build the Model.
// No JSON types here: the rest of the solver never sees the file format.
#pragma once
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "scene/beam_section.hpp"
#include "math/rotation.hpp"
#include "scene/time_function.hpp"

namespace mfbd {

// Ranges of scene numbers (README "Scene format"). Every number: 0 or a
// magnitude from the smallest normal double to kLargestNumber. A subnormal
// number (below 2.2e-308) carries fewer than 53 bits and is no physical
// quantity in SI units; refusing it in one place refuses the JSON number
// and the expression alike. 1e20 is far above any quantity of a machine
// (Young's modulus of diamond 1.2e12 Pa) and keeps the solver's products of
// a few scene numbers and their squares (norms) inside the double range.
// World coordinates of the design configuration, and joint coordinates,
// stay within kLargestCoordinate: the solver works in one world frame, where
// the last bit of a coordinate of 1e6 m is already 1e-10 m, ten thousand
// times the default Newton tolerance; squares of coordinates stay finite.
inline constexpr double kLargestNumber = 1e20;
inline constexpr double kLargestCoordinate = 1e6;

// A user parameter: a named number that scene fields may use in expressions
// ("mass": "m", "position": ["L", 0, 0]). Exposed as an FMU parameter.
// The name that stands for the world in joint.parent / joint.child.
inline constexpr const char* kGround = "ground";

struct ParameterSpec {
  std::string name;
  double value = 0.0;
  std::string unit;
  std::string description;
};

struct BodySpec {
  std::string name;
  // A massless virtual body made by the assembly where a joint or force
  // element touches a flexible node (coupling/virtual_bodies.cpp); never
  // written by the user, not an output.
  bool isVirtual = false;
  double mass = 0.0;
  Mat3 inertia = Mat3::Zero();  // about the centre of mass, body axes
  Vec3 centerOfMass = Vec3::Zero();  // in the body frame
  Vec3 position = Vec3::Zero();      // body frame origin, world, design configuration
  Mat3 orientation = Mat3::Identity();  // body frame -> world, design configuration
};

enum class JointType { Revolute, Prismatic, Cylindrical, Universal, Spherical, Planar, Fixed, Free };

// One end of a joint or force element on a flexible body: a node by index,
// or by the distance `at` from node 0 along the line to the last node (a
// node must lie there). `path` is the JSON path, for errors.
struct NodeReference {
  std::string flexibleBody;
  int node = -1;
  double at = -1.0;  // >= 0 when given instead of node
  std::string path;
};

const char* jointTypeName(JointType type);

// A joint between two bodies, placed in the design configuration: its frame
// is at `position` with orientation `frame` (both world; z along the scene's
// `axis`, x along its `x_axis` or, without one, world X projected off z).
// Joint coordinates are zero in the design configuration;
// `initialCoordinates` move away from it.
struct JointSpec {
  std::string name;
  JointType type = JointType::Revolute;
  std::string parent;  // body name or "ground" (a virtual body's, when the end is a node)
  std::string child;
  std::optional<NodeReference> parentNode, childNode;  // ends on flexible nodes
  Vec3 position = Vec3::Zero();
  bool positionGiven = true;  // may be left out when an end is a node: its position
  Mat3 frame = Mat3::Identity();  // columns: the joint frame's x, y, z axes in the world
  bool cut = false;  // closes a loop (Lagrange multipliers) instead of a tree joint
  std::vector<double> initialCoordinates;  // size = joint DOF, or empty = zeros
  std::vector<double> initialRates;
  bool keepRates = false;  // the assembly meets the velocity constraints without changing initialRates
  double damping = 0.0;    // viscous, per DOF, N m s/rad or N s/m
  bool torqueInput = false;  // an FMI input acting along the joint's DOFs
  bool driven = false;       // the (single) coordinate follows `drive`(t): a constraint row
  TimeFunction drive;
  // Driven, with the coordinate's rate from an FMI input <joint>.drive_rate
  // instead of `drive`: the input is held over a step and the coordinate
  // integrates it (as a rate-driven support of a flexible node does).
  bool driveRateInput = false;
  bool isVirtual = false;    // a virtual body's free joint to ground, made by the assembly
};

// A flexible body joint (docs/design.md 3): welds a virtual body to a flexible
// node with 6 constraint rows; its multipliers are the force and torque it
// passes. Made by the assembly with the virtual body.
struct FlexibleBodyJointSpec {
  std::string name;          // "<joint or force>.<end>_flexible_body_joint"
  std::string virtualBody;
  int flexibleBody = 0;      // index into Scene::flexibleBodies
  int node = 0;              // node of that body
};

// A support of a flexible node (Dirichlet condition, eliminated from the
// unknowns): clamp (position and rotation fixed), pin (position fixed),
// slide (position moves along `direction` only), driven (position fixed,
// rotation prescribed about the world `axis`: angle(t), or its rate from an
// FMI input).
struct SupportSpec {
  enum class Kind { Clamp, Pin, Slide, Driven };
  Kind kind = Kind::Clamp;
  int node = 0;
  Vec3 direction = Vec3::UnitX();  // slide direction, or driven rotation axis (world)
  TimeFunction angle;              // driven: rotation angle of time (rad)
  bool rateInput = false;          // driven: the angle's rate comes from an FMI input
};

struct PointMassSpec {
  int node = 0;
  double mass = 0.0;
  Mat3 inertia = Mat3::Zero();  // about the node, node frame
};

// A nodal force and moment: (force, moment) * scale(t), world axes (dead) or
// node axes (follower); or the six components from FMI inputs.
struct NodalLoadSpec {
  int node = 0;
  Vec3 force = Vec3::Zero();
  Vec3 moment = Vec3::Zero();
  bool follower = false;
  TimeFunction scale;
  bool input = false;
};

// Translational inertia of a flexible body's elements: the consistent mass
// of the centre line, linear along the chord and cubic across it
// (flex/consistent_mass.hpp), or half of
// each element lumped at its nodes. The rotary inertia of the section is
// lumped at the nodes either way.
enum class BeamMass { Consistent, Lumped };

// A flexible body: nodes (position; orientation of a beam line's section
// frame), two-node corotational beam elements, one section and material.
struct FlexibleBodySpec {
  std::string name;
  std::vector<Vec3> nodes;
  std::vector<Mat3> nodeOrientations;
  std::vector<std::pair<int, int>> elements;
  Vec3 sectionY = Vec3::UnitY();  // section y axis in the design configuration (world)
  BeamSection section;
  double damping = 0.0;           // stiffness-proportional damping coefficient, s
  BeamMass mass = BeamMass::Consistent;
  std::vector<SupportSpec> supports;
  std::vector<PointMassSpec> pointMasses;
  std::vector<NodalLoadSpec> loads;
  bool allNodes = false;          // outputs: every node, or those listed
  std::vector<int> outputNodes;
  // The nodes exposed as outputs, in order (every node with allNodes).
  std::vector<int> exposedNodes() const {
    std::vector<int> out = outputNodes;
    if (allNodes)
      for (int i = 0; i < int(nodes.size()); ++i) out.push_back(i);
    return out;
  }
  std::vector<int> outputElements;
  bool outputEnergy = false;      // kinetic, strain and gravity potential energy
};

// A force element between bodies (points in world coordinates of the design
// configuration; "ground" allowed): spring_damper (tension k (l - l0) + c
// ldot + actuator input), bushing (6-DOF stiffness and damping in its frame),
// applied_force (force and torque, world or body frame: constant times
// scale(t), or from FMI inputs), or
// rotational_spring_damper on a one-DOF joint (in joint space).
struct ForceSpec {
  enum class Kind { SpringDamper, Bushing, AppliedForce, RotationalSpringDamper };
  std::string name;
  Kind kind = Kind::SpringDamper;
  std::string body1 = kGround, body2 = kGround, joint;
  std::optional<NodeReference> node1, node2;  // ends on flexible nodes (a virtual body each)
  Vec3 point1 = Vec3::Zero(), point2 = Vec3::Zero();
  Mat3 orientation = Mat3::Identity();  // bushing frame
  double stiffness = 0.0, damping = 0.0;
  double freeLength = -1.0;             // < 0: the design distance (or angle 0)
  bool actuated = false;                // spring_damper: actuator force input
  bool bodyFrame = false;               // applied_force: components in the body frame
  bool input = true;                    // applied_force: from FMI inputs, else (force, torque) * scale(t)
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
  TimeFunction scale;
  Vec6 stiffness6 = Vec6::Zero(), damping6 = Vec6::Zero();
};

enum class Analysis { Dynamic, Static };

// The scene's "solver" section as written (defaults where it is silent),
// and the FMU parameters solver.* that overwrite it. The integrator's own
// options (integrator/solver_options.hpp) are made from it by the
// Simulation, which adds what no scene says (the FMI tolerance, the
// scene's length scale); the Newton matrix's form goes to the System.
struct SolverSection {
  double hMax = 1e-3;       // largest implicit substep, s
  double hMin = 1e-9;       // smallest substep before a step is discarded, s
  double rhoInf = 0.8;      // generalized-alpha spectral radius at infinity
  double maxSubsteps = 1e5; // substeps one communication step may take
  double tolerance = 1e-14; // Newton: position error left (m, rad)
  // Whether the scene (or the parameter solver.tolerance, set to another
  // value) gave the Newton tolerance; if not, under an error tolerance it
  // follows that (SolverOptions::newtonFollowsError).
  bool toleranceGiven = false;
  int maxIterations = 12;
  // Dynamics starts from the static equilibrium under gravity and loads at
  // the start time (solved at fmi2ExitInitializationMode), at rest.
  bool initialEquilibrium = false;
  // Form of the Newton matrix of the rigid tree in dynamics: joint space
  // (B^T M B and exact finite-difference derivatives; dense for a chain), or
  // recursive (body-level unknowns, sparse, O(n); see System::recursiveTangent).
  // Automatic: recursive for a tree without cut joints whose joint-space
  // tangent would hold a dense block of kRecursiveNewtonMatrixRates rates.
  enum class NewtonMatrix { Automatic, JointSpace, Recursive };
  NewtonMatrix newtonMatrix = NewtonMatrix::Automatic;
  static constexpr int kRecursiveNewtonMatrixRates = 80;
  // Time integrator of dynamics (solver/integrator_choice.cpp): implicit
  // generalized-alpha, explicit Dormand-Prince 5(4), or automatic (the
  // explicit method under error control for a scene that is not stiff).
  enum class Method { Automatic, GeneralizedAlpha, DormandPrince };
  Method method = Method::Automatic;
};

// Which outputs the FMU exposes. Empty lists with `all` false expose none.
struct OutputSelection {
  bool allBodies = true;
  std::vector<std::string> bodies;
  bool allJoints = true;
  std::vector<std::string> joints;
  bool exposesBody(const std::string& name) const { return allBodies || listed(bodies, name); }
  bool exposesJoint(const std::string& name) const { return allJoints || listed(joints, name); }

 private:
  static bool listed(const std::vector<std::string>& names, const std::string& name) {
    for (const auto& n : names)
      if (n == name) return true;
    return false;
  }
};

// The default experiment the FMU advertises (fmpy and others use it).
struct Experiment {
  double startTime = 0.0;
  double stopTime = 1.0;
  double outputInterval = 0.01;
  double tolerance = 1e-4;  // relative error tolerance (SolverOptions::errorTolerance)
};

struct Scene {
  std::string name;
  std::string description;
  std::vector<ParameterSpec> parameters;
  Vec3 gravity = Vec3::Zero();
  SolverSection solver;
  Experiment experiment;
  std::vector<BodySpec> bodies;
  std::vector<JointSpec> joints;
  std::vector<FlexibleBodySpec> flexibleBodies;
  std::vector<ForceSpec> forces;
  std::vector<FlexibleBodyJointSpec> flexibleBodyJoints;  // made with the virtual bodies
  OutputSelection outputs;
  // Static: each step solves equilibrium at the loads of its end time (load
  // stepping with Newton; halving on failure), no inertia.
  Analysis analysis = Analysis::Dynamic;
  // What parsing decided for the user (e.g. which joints it cut to open
  // loops), for the packer's output and the FMU's log.
  std::vector<std::string> notes;
};

// One bad-input error: where (a JSON path such as "joints[1].axis") and what
// was expected. what() reads "joints[1].axis: expected ...".
class SceneError : public std::runtime_error {
 public:
  SceneError(const std::string& path, const std::string& message);
  const std::string& path() const { return path_; }
 private:
  std::string path_;
};

// Parses and validates scene JSON text. `parameterValues` overrides the
// defaults of user parameters (how FMU parameters reach the scene).
// Throws SceneError naming the first bad field.
Scene parseScene(const std::string& text,
                 const std::map<std::string, double>& parameterValues = {});

}  // namespace mfbd
