// "flexible_bodies" of scene JSON: a beam line or explicit nodes and
// elements, a section (explicit stiffnesses or a shape with a material),
// supports, point masses, nodal loads and the outputs to expose.
#include <stdexcept>

#include "scene/json_field.hpp"

namespace mfbd {

namespace {

BeamSection parseSection(const Field& f, const Field* material) {
  if (!f.has("shape")) {
    f.expectObject({"EA", "GAy", "GAz", "GJ", "EIy", "EIz", "rhoA", "rhoJ"},
                   {"EA", "GJ", "EIy", "EIz", "rhoA", "rhoJ"});
    BeamSection s;
    s.EA = f.at("EA").positive();
    s.GJ = f.at("GJ").positive();
    s.EIy = f.at("EIy").positive();
    s.EIz = f.at("EIz").positive();
    // Shear stiffness 0 (or absent) means shear-rigid (Euler-Bernoulli).
    if (f.has("GAy")) s.GAy = f.at("GAy").nonNegative();
    if (f.has("GAz")) s.GAz = f.at("GAz").nonNegative();
    s.rhoA = f.at("rhoA").positive();
    s.rhoJ = f.at("rhoJ").vec3();
    for (int i = 0; i < 3; ++i)
      if (s.rhoJ[i] < 0.0) f.at("rhoJ").at(i).fail("expected a rotary inertia >= 0");
    return s;
  }
  if (!material) f.fail("a section given by shape needs a \"material\" beside it");
  const std::string shape = f.at("shape").string();
  const Field& m = *material;
  m.expectObject({"E", "G", "nu", "rho"}, {"E", "rho"});
  if (m.has("G") == m.has("nu")) m.fail("expected exactly one of G or nu");
  BeamMaterial mat;
  mat.E = m.at("E").positive();
  mat.rho = m.at("rho").positive();
  if (m.has("G")) {
    mat.G = m.at("G").positive();
  } else {
    const double nu = m.at("nu").number();
    if (!(nu > -1.0 && nu < 0.5)) m.at("nu").fail("expected a Poisson ratio in (-1, 0.5)");
    mat.G = mat.E / (2.0 * (1.0 + nu));
  }
  try {
    if (shape == "rectangle") {
      f.expectObject({"shape", "b", "h"}, {"b", "h"});
      return rectangleSection(mat, f.at("b").positive(), f.at("h").positive());
    }
    if (shape == "circle") {
      f.expectObject({"shape", "d"}, {"d"});
      return circleSection(mat, f.at("d").positive());
    }
    if (shape == "tube") {
      f.expectObject({"shape", "ro", "ri"}, {"ro", "ri"});
      const double ro = f.at("ro").positive(), ri = f.at("ri").nonNegative();
      if (ri >= ro) f.at("ri").fail("expected ri < ro");
      return tubeSection(mat, ro, ri);
    }
  } catch (const std::invalid_argument& e) {
    f.fail(e.what());
  }
  f.at("shape").fail("unknown shape \"" + shape + "\"; expected rectangle, circle or tube");
}

int parseNode(const Field& f, int nodeCount) { return f.integer(0, nodeCount - 1, "a node index"); }

SupportSpec parseSupport(const Field& f, int nodeCount) {
  f.expectObject({"node", "type", "direction", "axis", "angle", "rate_input"}, {"node", "type"});
  SupportSpec s;
  s.node = parseNode(f.at("node"), nodeCount);
  const std::string kind = f.at("type").string();
  if (kind == "clamp") {
    s.kind = SupportSpec::Kind::Clamp;
  } else if (kind == "pin") {
    s.kind = SupportSpec::Kind::Pin;
  } else if (kind == "slide") {
    s.kind = SupportSpec::Kind::Slide;
    if (!f.has("direction")) throw SceneError(f.path() + ".direction", "missing required field (slide direction)");
    s.direction = f.at("direction").direction();
  } else if (kind == "driven") {
    s.kind = SupportSpec::Kind::Driven;
    if (!f.has("axis")) throw SceneError(f.path() + ".axis", "missing required field (rotation axis)");
    s.direction = f.at("axis").direction();
    if (f.has("rate_input")) s.rateInput = f.at("rate_input").boolean();
    if (f.has("angle") == s.rateInput)
      f.fail("a driven support takes exactly one of \"angle\" (a function of t) or \"rate_input\": true");
    if (f.has("angle")) s.angle = f.at("angle").timeFunction("angle", true);
  } else {
    f.at("type").fail("unknown support \"" + kind + "\"; expected clamp, pin, slide or driven");
  }
  return s;
}

PointMassSpec parsePointMass(const Field& f, int nodeCount) {
  f.expectObject({"node", "mass", "inertia"}, {"node", "mass"});
  PointMassSpec p;
  p.node = parseNode(f.at("node"), nodeCount);
  p.mass = f.at("mass").positive();
  if (f.has("inertia")) {
    const Vec3 J = f.at("inertia").vec3();
    for (int i = 0; i < 3; ++i)
      if (J[i] < 0.0) f.at("inertia").at(i).fail("expected a principal moment >= 0");
    p.inertia = J.asDiagonal();
  }
  return p;
}

NodalLoadSpec parseLoad(const Field& f, int nodeCount) {
  f.expectObject({"node", "force", "moment", "follower", "scale", "input"}, {"node"});
  NodalLoadSpec l;
  l.node = parseNode(f.at("node"), nodeCount);
  if (f.has("input")) l.input = f.at("input").boolean();
  if (l.input && (f.has("force") || f.has("moment") || f.has("scale")))
    f.fail("an input load takes its force and moment from FMI inputs: give no force, moment or scale");
  if (!l.input && !f.has("force") && !f.has("moment")) f.fail("expected a force, a moment, or \"input\": true");
  if (f.has("force")) l.force = f.at("force").vec3();
  if (f.has("moment")) l.moment = f.at("moment").vec3();
  if (f.has("follower")) l.follower = f.at("follower").boolean();
  if (f.has("scale")) l.scale = f.at("scale").timeFunction("scale", false);
  return l;
}

// Nodes and elements of a beam line, with node frames x along the line and
// y along the section axis.
void parseBeamLine(const Field& f, FlexibleBodySpec& b) {
  f.expectObject({"start", "end", "elements", "section_y"}, {"start", "end", "elements"});
  const Vec3 start = f.at("start").point(), end = f.at("end").point();
  const int n = f.at("elements").integer(1, 1000000, "an element count");
  if ((end - start).norm() < 1e-12) f.at("end").fail("expected an end point away from start");
  if (f.has("section_y")) b.sectionY = f.at("section_y").direction();
  const Vec3 x = (end - start).normalized();
  const Vec3 y = b.sectionY - b.sectionY.dot(x) * x;
  if (y.norm() < 1e-6) f.at("section_y").fail("expected a section axis not parallel to the beam");
  Mat3 frame;
  frame << x, y.normalized(), x.cross(y.normalized());
  for (int i = 0; i <= n; ++i) {
    b.nodes.push_back(start + (end - start) * (double(i) / n));
    b.nodeOrientations.push_back(frame);
  }
  for (int i = 0; i < n; ++i) b.elements.emplace_back(i, i + 1);
}

void parseMesh(const Field& f, FlexibleBodySpec& b) {
  const Field nodes = f.at("nodes");
  for (std::size_t i = 0; i < nodes.arraySize(); ++i) {
    b.nodes.push_back(nodes.at(i).point());
    b.nodeOrientations.push_back(Mat3::Identity());
  }
  const Field elements = f.at("elements");
  for (std::size_t e = 0; e < elements.arraySize(); ++e) {
    const Field el = elements.at(e);
    if (el.arraySize() != 2) el.fail("expected two node indices");
    const int a = parseNode(el.at(0), int(b.nodes.size())), c = parseNode(el.at(1), int(b.nodes.size()));
    if (a == c) el.fail("expected two different nodes");
    if ((b.nodes[a] - b.nodes[c]).norm() < 1e-12) el.fail("expected nodes at different positions");
    b.elements.emplace_back(a, c);
  }
  if (f.has("section_y")) b.sectionY = f.at("section_y").direction();
  for (std::size_t e = 0; e < b.elements.size(); ++e) {
    const Vec3 x = (b.nodes[b.elements[e].second] - b.nodes[b.elements[e].first]).normalized();
    if ((b.sectionY - b.sectionY.dot(x) * x).norm() < 1e-6)
      f.at("section_y").fail("expected a section axis not parallel to element " + std::to_string(e));
  }
}

}  // namespace

FlexibleBodySpec parseFlexibleBody(const Field& f) {
  f.expectObject({"name", "beam", "nodes", "elements", "section_y", "section", "material", "damping", "mass", "supports",
                  "point_masses", "loads", "outputs", "visual"},
                 {"name", "section"});
  if (f.has("visual") && !f.at("visual").raw().is_object())  // for the drawing tools only
    f.at("visual").fail("expected an object (color, section), got " + typeName(f.at("visual").raw()));
  FlexibleBodySpec b;
  b.name = f.at("name").identifier();
  if (f.has("beam") == f.has("nodes")) f.fail("expected either \"beam\" (a line) or \"nodes\" and \"elements\"");
  if (f.has("beam")) {
    if (f.has("elements") || f.has("section_y")) f.fail("a \"beam\" line gives its own elements and section_y");
    parseBeamLine(f.at("beam"), b);
  } else {
    if (!f.has("elements")) throw SceneError(f.path() + ".elements", "missing required field");
    parseMesh(f, b);
  }
  const Field material = f.has("material") ? f.at("material") : f;
  b.section = parseSection(f.at("section"), f.has("material") ? &material : nullptr);
  if (f.has("damping")) b.damping = f.at("damping").nonNegative();
  if (f.has("mass")) {
    const std::string mass = f.at("mass").string();
    if (mass != "consistent" && mass != "lumped") f.at("mass").fail("expected \"consistent\" or \"lumped\"");
    b.mass = mass == "lumped" ? BeamMass::Lumped : BeamMass::Consistent;
  }
  const int n = int(b.nodes.size());
  if (f.has("supports"))
    for (std::size_t i = 0; i < f.at("supports").arraySize(); ++i)
      b.supports.push_back(parseSupport(f.at("supports").at(i), n));
  for (std::size_t i = 0; i < b.supports.size(); ++i)
    for (std::size_t k = 0; k < i; ++k)
      if (b.supports[i].node == b.supports[k].node)
        f.at("supports").at(i).fail("node " + std::to_string(b.supports[i].node) + " already has a support");
  if (f.has("point_masses"))
    for (std::size_t i = 0; i < f.at("point_masses").arraySize(); ++i)
      b.pointMasses.push_back(parsePointMass(f.at("point_masses").at(i), n));
  if (f.has("loads"))
    for (std::size_t i = 0; i < f.at("loads").arraySize(); ++i)
      b.loads.push_back(parseLoad(f.at("loads").at(i), n));
  if (f.has("outputs")) {
    const Field out = f.at("outputs");
    out.expectObject({"nodes", "elements", "energy"}, {});
    if (out.has("energy")) b.outputEnergy = out.at("energy").boolean();
    if (out.has("nodes")) {
      const Field nodes = out.at("nodes");
      if (nodes.raw().is_string()) {
        if (nodes.string() != "all") nodes.fail("expected \"all\" or a list of node indices");
        b.allNodes = true;
      } else {
        for (std::size_t i = 0; i < nodes.arraySize(); ++i) b.outputNodes.push_back(parseNode(nodes.at(i), n));
      }
    }
    if (out.has("elements"))
      for (std::size_t i = 0; i < out.at("elements").arraySize(); ++i)
        b.outputElements.push_back(parseNode(out.at("elements").at(i), int(b.elements.size())));
  }
  return b;
}

}  // namespace mfbd
