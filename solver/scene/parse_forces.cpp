// "forces" of scene JSON: force elements between bodies and on joints.
#include "scene/json_field.hpp"

namespace mfbd {

namespace {

Vec6 sixNumbers(const Field& f) {
  const std::vector<double> v = f.numbers();
  if (v.size() != 6) f.fail("expected 6 numbers (x, y, z translation, then rotation), got " + std::to_string(v.size()));
  Vec6 out;
  for (int i = 0; i < 6; ++i) {
    if (v[i] < 0.0) f.at(i).fail("expected a value >= 0");
    out[i] = v[i];
  }
  return out;
}

}  // namespace

ForceSpec parseForce(const Field& f) {
  if (!f.raw().is_object()) f.fail("expected an object, got " + typeName(f.raw()));
  if (!f.has("type")) throw SceneError(f.path() + ".type", "missing required field");
  const std::string type = f.at("type").string();
  ForceSpec s;
  if (type == "spring_damper") {
    f.expectObject({"name", "type", "body1", "point1", "body2", "point2", "stiffness", "damping", "free_length",
                    "actuated"},
                   {"name", "body1", "point1", "body2", "point2"});
    s.kind = ForceSpec::Kind::SpringDamper;
    parseEnd(f.at("body1"), s.body1, s.node1);
    s.point1 = f.at("point1").point();
    parseEnd(f.at("body2"), s.body2, s.node2);
    s.point2 = f.at("point2").point();
    if (f.has("free_length")) s.freeLength = f.at("free_length").nonNegative();
    if (f.has("actuated")) s.actuated = f.at("actuated").boolean();
  } else if (type == "bushing") {
    f.expectObject({"name", "type", "body1", "body2", "position", "orientation", "stiffness", "damping"},
                   {"name", "body1", "body2", "position", "stiffness"});
    s.kind = ForceSpec::Kind::Bushing;
    parseEnd(f.at("body1"), s.body1, s.node1);
    parseEnd(f.at("body2"), s.body2, s.node2);
    s.point1 = s.point2 = f.at("position").point();
    if (f.has("orientation")) s.orientation = parseOrientation(f.at("orientation"));
    s.stiffness6 = sixNumbers(f.at("stiffness"));
    if (f.has("damping")) s.damping6 = sixNumbers(f.at("damping"));
  } else if (type == "applied_force") {
    f.expectObject({"name", "type", "body", "point", "frame", "force", "torque", "scale", "input"},
                   {"name", "body", "point"});
    s.kind = ForceSpec::Kind::AppliedForce;
    // As a flexible body's nodal load: given (force, torque) * scale(t), or inputs.
    const bool given = f.has("force") || f.has("torque");
    s.input = f.has("input") ? f.at("input").boolean() : !given;
    if (s.input && (given || f.has("scale")))
      f.fail("an input force takes its force and torque from FMI inputs: give no force, torque or scale");
    if (!s.input && !given) f.fail("expected a force, a torque, or \"input\": true");
    if (f.has("force")) s.force = f.at("force").vec3();
    if (f.has("torque")) s.torque = f.at("torque").vec3();
    if (f.has("scale")) s.scale = f.at("scale").timeFunction("scale", false);
    parseEnd(f.at("body"), s.body1, s.node1);
    s.point1 = f.at("point").point();
    if (f.has("frame")) {
      const std::string frame = f.at("frame").string();
      if (frame != "world" && frame != "body") f.at("frame").fail("expected \"world\" or \"body\"");
      s.bodyFrame = frame == "body";
    }
  } else if (type == "rotational_spring_damper") {
    f.expectObject({"name", "type", "joint", "stiffness", "damping", "free_angle"}, {"name", "joint"});
    s.kind = ForceSpec::Kind::RotationalSpringDamper;
    s.joint = f.at("joint").identifier();
    if (f.has("free_angle")) s.freeLength = f.at("free_angle").coordinate();
    else s.freeLength = 0.0;
  } else {
    f.at("type").fail("unknown force type \"" + type +
                      "\"; expected spring_damper, bushing, applied_force or rotational_spring_damper");
  }
  s.name = f.at("name").identifier();
  if (s.kind == ForceSpec::Kind::SpringDamper || s.kind == ForceSpec::Kind::RotationalSpringDamper) {
    if (f.has("stiffness")) s.stiffness = f.at("stiffness").nonNegative();
    if (f.has("damping")) s.damping = f.at("damping").nonNegative();
  }
  return s;
}

}  // namespace mfbd
