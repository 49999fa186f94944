// Scene JSON -> Scene, strictly: every key known, every number finite, every
// reference resolved, every physical quantity possible. One error, naming the
// JSON path and what was expected.
#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include <cmath>
#include <set>

#include "scene/expression.hpp"
#include "scene/json_field.hpp"
#include "scene/scene.hpp"
#include "scene/virtual_bodies.hpp"

namespace mfbd {

SceneError::SceneError(const std::string& path, const std::string& message)
    : std::runtime_error((path.empty() ? std::string("scene") : path) + ": " + message), path_(path) {}

const char* jointTypeName(JointType type) {
  switch (type) {
    case JointType::Revolute: return "revolute";
    case JointType::Prismatic: return "prismatic";
    case JointType::Cylindrical: return "cylindrical";
    case JointType::Universal: return "universal";
    case JointType::Spherical: return "spherical";
    case JointType::Planar: return "planar";
    case JointType::Fixed: return "fixed";
    case JointType::Free: return "free";
  }
  return "?";
}

namespace {

// The frame with z along `z` and x along `xField`'s direction projected off z.
Mat3 frameFromAxes(const Vec3& z, const Field& xField) {
  const Vec3 xRaw = xField.direction();
  const Vec3 x = xRaw - xRaw.dot(z) * z;
  if (x.norm() < 1e-6) xField.fail("expected a direction not parallel to the z axis");
  Mat3 A;
  A.col(0) = x.normalized();
  A.col(2) = z;
  A.col(1) = z.cross(A.col(0));
  return A;
}

}  // namespace

Mat3 parseOrientation(const Field& f) {
  f.expectObject({"quaternion", "z_axis", "x_axis", "rotation_vector"}, {});
  const int given = f.has("quaternion") + f.has("z_axis") + f.has("rotation_vector");
  if (given != 1) f.fail("expected exactly one of quaternion [w,x,y,z], z_axis (+ x_axis), rotation_vector");
  if (f.has("x_axis") && !f.has("z_axis")) f.at("x_axis").fail("x_axis goes with z_axis");
  if (f.has("quaternion")) {
    const Field q = f.at("quaternion");
    const std::vector<double> v = q.numbers();
    if (v.size() != 4) q.fail("expected 4 numbers [w, x, y, z], got " + std::to_string(v.size()));
    const Eigen::Vector4d wxyz(v[0], v[1], v[2], v[3]);
    const double norm = wxyz.stableNorm();  // no overflow for [1e20, 0, 0, 0]
    if (norm == 0.0) q.fail("expected a non-zero quaternion");
    return Quat(v[0] / norm, v[1] / norm, v[2] / norm, v[3] / norm).toRotationMatrix();
  }
  if (f.has("rotation_vector")) return expSO3(f.at("rotation_vector").vec3());
  const Vec3 z = f.at("z_axis").direction();
  return f.has("x_axis") ? frameFromAxes(z, f.at("x_axis")) : frameFromZAxis(z);
}

namespace {

// The scene's name is the FMU's modelIdentifier: a C identifier (what
// Field::identifier accepts) that names the binary in the archive,
// binaries/<platform>/<name>.so or .dll. Importers extract into a
// temporary folder, and a path on Windows holds 260 characters by default
// (a file name 255 anywhere): 64 leaves room for the folder.
constexpr std::size_t kLongestSceneName = 64;

std::vector<ParameterSpec> parseParameters(const Field& f, const std::map<std::string, double>& overrides,
                                           std::map<std::string, double>& values) {
  std::vector<ParameterSpec> out;
  if (!f.raw().is_object()) f.fail("expected an object of parameters, got " + typeName(f.raw()));
  for (const auto& item : f.raw().items()) {
    const Field p = f.at(item.key());
    ParameterSpec spec;
    spec.name = Field(json(item.key()), p.path(), values).identifier();
    const std::map<std::string, double> none;  // parameter values are plain numbers
    if (p.raw().is_object()) {
      p.expectObject({"value", "unit", "description"}, {"value"});
      spec.value = Field(p.raw().at("value"), p.path() + ".value", none).number();
      if (p.has("unit")) spec.unit = p.at("unit").text();
      if (p.has("description")) spec.description = p.at("description").text();
    } else {
      spec.value = Field(p.raw(), p.path(), none).number();
    }
    if (const auto it = overrides.find(spec.name); it != overrides.end()) {
      p.inRange(it->second);
      spec.value = it->second;
    }
    values[spec.name] = spec.value;
    out.push_back(spec);
  }
  for (const auto& item : overrides)
    if (!values.count(item.first)) throw SceneError("parameters." + item.first, "no such parameter in the scene");
  return out;
}

// A joint's frame: `axis` (z, default world Z) with `x_axis`, or a full
// `orientation` as a body's.
Mat3 parseJointFrame(const Field& f) {
  if (f.has("orientation")) {
    for (const char* axisField : {"axis", "x_axis"})
      if (f.has(axisField)) f.at(axisField).fail("give either orientation or axis (+ x_axis), not both");
    return parseOrientation(f.at("orientation"));
  }
  const Vec3 z = f.has("axis") ? f.at("axis").direction() : Vec3::UnitZ();
  return f.has("x_axis") ? frameFromAxes(z, f.at("x_axis")) : frameFromZAxis(z);
}

// An inertia tensor that a body can have: symmetric, principal moments >= 0
// and each no larger than the sum of the other two.
Mat3 parseInertia(const Field& f) {
  const std::vector<double> v = f.numbers();
  Mat3 J = Mat3::Zero();
  if (v.size() == 3) {
    J.diagonal() << v[0], v[1], v[2];
  } else if (v.size() == 6) {
    J << v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2];
  } else {
    f.fail("expected [Ixx, Iyy, Izz] or [Ixx, Iyy, Izz, Ixy, Ixz, Iyz], got " + std::to_string(v.size()) + " numbers");
  }
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(J);
  const Vec3 p = eig.eigenvalues();
  const double scale = std::max(1.0, p.cwiseAbs().maxCoeff());
  if (p.minCoeff() < -1e-12 * scale)
    f.fail("expected an inertia tensor with principal moments >= 0, got " + vectorText(p));
  for (int i = 0; i < 3; ++i)
    if (p[i] > p[(i + 1) % 3] + p[(i + 2) % 3] + 1e-12 * scale)
      f.fail("principal moments " + vectorText(p) +
             " break the triangle inequality (each must be <= the sum of the other two)");
  return J;
}

// "visual" (shapes, colours) is for the drawing tools (python/mfbd), not the
// physics: only its type is checked here.
void checkVisual(const Field& owner) {
  if (!owner.has("visual")) return;
  const json& v = owner.at("visual").raw();
  if (!v.is_object() && !v.is_array())
    owner.at("visual").fail("expected an object (shape, size, color, ...) or a list of them, got " + typeName(v));
}

BodySpec parseBody(const Field& f) {
  f.expectObject({"name", "mass", "inertia", "center_of_mass", "position", "orientation", "visual"},
                 {"name", "mass", "inertia", "position"});
  checkVisual(f);
  BodySpec b;
  b.name = f.at("name").identifier();
  b.mass = f.at("mass").nonNegative();  // 0: a massless body, its motion fixed by joints
  b.inertia = parseInertia(f.at("inertia"));
  if (f.has("center_of_mass")) b.centerOfMass = f.at("center_of_mass").point();
  b.position = f.at("position").point();
  if (f.has("orientation")) b.orientation = parseOrientation(f.at("orientation"));
  return b;
}

JointType parseJointType(const Field& f) {
  const std::string s = f.string();
  for (JointType t : {JointType::Revolute, JointType::Prismatic, JointType::Cylindrical, JointType::Universal,
                      JointType::Spherical, JointType::Planar, JointType::Fixed, JointType::Free})
    if (s == jointTypeName(t)) return t;
  f.fail("unknown joint type \"" + s +
         "\"; expected revolute, prismatic, cylindrical, universal, spherical, planar, fixed or free");
}

JointSpec parseJoint(const Field& f) {
  f.expectObject({"name", "type", "parent", "child", "position", "axis", "x_axis", "orientation", "cut", "initial",
                  "damping", "actuated", "drive"},
                 {"name", "type", "parent", "child"});
  JointSpec jt;
  jt.name = f.at("name").identifier();
  jt.type = parseJointType(f.at("type"));
  parseEnd(f.at("parent"), jt.parent, jt.parentNode);
  parseEnd(f.at("child"), jt.child, jt.childNode);
  // On a flexible node the joint may sit at the node (the default there).
  jt.positionGiven = f.has("position");
  if (jt.positionGiven) jt.position = f.at("position").point();
  else if (!jt.parentNode && !jt.childNode)
    throw SceneError(f.path() + ".position", "missing required field");
  jt.frame = parseJointFrame(f);
  if (f.has("cut")) jt.cut = f.at("cut").boolean();
  if (f.has("damping")) jt.damping = f.at("damping").nonNegative();
  if (f.has("actuated")) jt.torqueInput = f.at("actuated").boolean();
  if (f.has("drive") && f.at("drive").raw().is_object() && f.at("drive").has("rate_input")) {
    f.at("drive").expectObject({"rate_input"}, {"rate_input"});
    jt.driven = true;
    jt.driveRateInput = f.at("drive").at("rate_input").boolean();
    if (!jt.driveRateInput) f.at("drive").at("rate_input").fail("expected true (or give the drive as an expression of t)");
  } else if (f.has("drive")) {  // a function of t: an expression or a table
    jt.driven = true;
    jt.drive = f.at("drive").timeFunction("coordinate", true);
  }
  if (f.has("initial")) {
    const Field init = f.at("initial");
    init.expectObject({"coordinates", "rates", "keep_rates"}, {});
    if (init.has("coordinates")) {
      const Field q = init.at("coordinates");
      for (std::size_t i = 0; i < q.arraySize(); ++i) jt.initialCoordinates.push_back(q.at(i).coordinate());
    }
    if (init.has("rates")) jt.initialRates = init.at("rates").numbers();
    if (init.has("keep_rates")) jt.keepRates = init.at("keep_rates").boolean();
  }
  return jt;
}

SolverSection parseSolver(const Field& f) {
  f.expectObject({"h_max", "h_min", "rho_inf", "tolerance", "max_iterations", "initial_equilibrium", "newton_matrix",
                  "method"},
                 {});
  SolverSection s;
  if (f.has("h_max")) s.hMax = f.at("h_max").positive();
  if (f.has("h_min")) s.hMin = f.at("h_min").positive();
  if (s.hMin > s.hMax) f.at("h_min").fail("expected h_min <= h_max");
  if (f.has("rho_inf")) {
    s.rhoInf = f.at("rho_inf").number();
    if (s.rhoInf < 0.0 || s.rhoInf > 1.0) f.at("rho_inf").fail("expected a spectral radius in [0, 1]");
  }
  if (f.has("tolerance")) {
    s.tolerance = f.at("tolerance").positive();
    s.toleranceGiven = true;
  }
  if (f.has("max_iterations")) s.maxIterations = f.at("max_iterations").integer(1, 100);
  if (f.has("initial_equilibrium")) s.initialEquilibrium = f.at("initial_equilibrium").boolean();
  if (f.has("newton_matrix")) {
    const std::string form = f.at("newton_matrix").string();
    if (form == "automatic") s.newtonMatrix = SolverSection::NewtonMatrix::Automatic;
    else if (form == "joint_space") s.newtonMatrix = SolverSection::NewtonMatrix::JointSpace;
    else if (form == "recursive") s.newtonMatrix = SolverSection::NewtonMatrix::Recursive;
    else f.at("newton_matrix").fail("expected \"automatic\", \"joint_space\" or \"recursive\"");
  }
  if (f.has("method")) {
    const std::string method = f.at("method").string();
    if (method == "automatic") s.method = SolverSection::Method::Automatic;
    else if (method == "generalized_alpha") s.method = SolverSection::Method::GeneralizedAlpha;
    else if (method == "dormand_prince") s.method = SolverSection::Method::DormandPrince;
    else f.at("method").fail("expected \"automatic\", \"generalized_alpha\" or \"dormand_prince\"");
  }
  return s;
}

Experiment parseExperiment(const Field& f) {
  f.expectObject({"start_time", "stop_time", "output_interval", "tolerance"}, {});
  Experiment e;
  if (f.has("start_time")) e.startTime = f.at("start_time").number();
  if (f.has("stop_time")) e.stopTime = f.at("stop_time").number();
  if (e.stopTime <= e.startTime) f.at("stop_time").fail("expected stop_time > start_time");
  if (f.has("output_interval")) e.outputInterval = f.at("output_interval").positive();
  if (f.has("tolerance")) {
    e.tolerance = f.at("tolerance").positive();
    if (e.tolerance >= 1.0) f.at("tolerance").fail("expected a relative tolerance below 1");
  }
  return e;
}

void parseSelection(const Field& f, bool& all, std::vector<std::string>& names) {
  if (f.raw().is_string()) {
    if (f.string() != "all") f.fail("expected \"all\" or a list of names");
    all = true;
    return;
  }
  all = false;
  for (std::size_t i = 0; i < f.arraySize(); ++i) names.push_back(f.at(i).identifier());
}

}  // namespace

void chooseCutJoints(Scene& scene);      // validate.cpp
void validateScene(const Scene& scene);  // validate.cpp
FlexibleBodySpec parseFlexibleBody(const Field& f);  // parse_flexible.cpp
ForceSpec parseForce(const Field& f);  // parse_forces.cpp

Scene parseScene(const std::string& text, const std::map<std::string, double>& parameterValues) {
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw SceneError("", "empty file; expected a JSON object");
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::exception& e) {  // syntax errors, and numbers beyond double range
    throw SceneError("", std::string("not valid JSON: ") + e.what());
  }
  std::map<std::string, double> params;
  const Field root(doc, "", params);
  root.expectObject({"format", "name", "description", "parameters", "gravity", "solver", "experiment", "analysis",
                     "bodies", "joints", "flexible_bodies", "forces", "outputs"},
                    {"format", "name"});
  if (root.at("format").string() != "mfbd-scene/1")
    root.at("format").fail("expected \"mfbd-scene/1\"");

  Scene scene;
  scene.name = root.at("name").identifier();
  if (scene.name.size() > kLongestSceneName)
    root.at("name").fail("expected at most " + std::to_string(kLongestSceneName) +
                         " characters (the FMU's modelIdentifier names its binary file), got " +
                         std::to_string(scene.name.size()));
  if (root.has("description")) scene.description = root.at("description").text();
  if (root.has("parameters")) scene.parameters = parseParameters(root.at("parameters"), parameterValues, params);
  else if (!parameterValues.empty())
    throw SceneError("parameters." + parameterValues.begin()->first, "no such parameter in the scene");
  if (root.has("gravity")) scene.gravity = root.at("gravity").vec3();
  if (root.has("solver")) scene.solver = parseSolver(root.at("solver"));
  if (root.has("experiment")) scene.experiment = parseExperiment(root.at("experiment"));
  if (root.has("analysis")) {
    const std::string a = root.at("analysis").string();
    if (a != "dynamic" && a != "static") root.at("analysis").fail("expected \"dynamic\" or \"static\"");
    scene.analysis = a == "static" ? Analysis::Static : Analysis::Dynamic;
  }
  if (root.has("bodies")) {
    const Field bodies = root.at("bodies");
    for (std::size_t i = 0; i < bodies.arraySize(); ++i) scene.bodies.push_back(parseBody(bodies.at(i)));
  }
  if (root.has("joints")) {
    const Field joints = root.at("joints");
    for (std::size_t i = 0; i < joints.arraySize(); ++i) scene.joints.push_back(parseJoint(joints.at(i)));
  }
  if (root.has("flexible_bodies")) {
    const Field flexible = root.at("flexible_bodies");
    for (std::size_t i = 0; i < flexible.arraySize(); ++i)
      scene.flexibleBodies.push_back(parseFlexibleBody(flexible.at(i)));
  }
  if (root.has("forces")) {
    const Field forces = root.at("forces");
    for (std::size_t i = 0; i < forces.arraySize(); ++i) scene.forces.push_back(parseForce(forces.at(i)));
  }
  if (root.has("outputs")) {
    const Field out = root.at("outputs");
    out.expectObject({"bodies", "joints"}, {});
    if (out.has("bodies")) parseSelection(out.at("bodies"), scene.outputs.allBodies, scene.outputs.bodies);
    if (out.has("joints")) parseSelection(out.at("joints"), scene.outputs.allJoints, scene.outputs.joints);
  }
  makeVirtualBodies(scene);
  chooseCutJoints(scene);
  validateScene(scene);
  return scene;
}

}  // namespace mfbd
