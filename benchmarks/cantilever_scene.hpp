// The benchmark scenes of flexible_cost.cpp and flexible_phases.cpp, as scene
// JSON with N elements and implicit substep h; tolerance > 0 overrides the
// default Newton tolerance.
//   cantileverScene: the F3 cantilever of examples/cantilever_vibration
//     (EI = 1, EA = 1e6 EI/L^2, rhoA = 1, L = 1, clamped, tip force pulse of
//     0.02 s).
//   coupledScene: the same beam spun up about z (a smooth ramp to 2 rad/s
//     over 0.2 s) instead of clamped (benchmarks/coupled_cost.py), held
//     HubAndTipBody: by a hub (1 kg) on a revolute joint to ground whose
//       angle is driven, welded to node 0 by a fixed joint, and with a tip
//       body (1 kg) on a fixed joint at the beam's end: two virtual bodies
//       and flexible body joints, one drive row;
//     Hub: the hub alone;
//     DrivenNode: no rigid body, node 0's rotation prescribed (a "driven"
//       support): the same motion, the baseline of the other two.
#pragma once
#include <sstream>
#include <string>

inline std::string cantileverScene(int elements, double h, double tolerance = 0.0) {
  std::ostringstream s;
  s.precision(17);
  s << R"json({
  "format": "mfbd-scene/1",
  "name": "flexible_cost",
  "parameters": {"L": {"value": 1.0}, "EI": {"value": 1.0}, "rhoA": {"value": 1.0}, "pulse": {"value": 0.02}},
  "solver": {"h_max": )json" << h;
  if (tolerance > 0.0) s << ", \"tolerance\": " << tolerance;
  s << R"json(, "rho_inf": 0.9},
  "flexible_bodies": [{
    "name": "beam",
    "beam": {"start": [0, 0, 0], "end": ["L", 0, 0], "elements": )json" << elements << R"json(, "section_y": [0, 1, 0]},
    "section": {"EA": "1e6*EI/L^2", "GJ": "EI", "EIy": "EI", "EIz": "EI", "rhoA": "rhoA",
                "rhoJ": ["2e-6*rhoA*L^2", "1e-6*rhoA*L^2", "1e-6*rhoA*L^2"]},
    "supports": [{"node": 0, "type": "clamp"}],
    "loads": [{"node": )json" << elements << R"json(, "force": [0, "0.01*EI/L^2", 0], "scale": "if(pulse - t, sin(pi*t/pulse)^2, 0)"}],
    "outputs": {"nodes": [)json" << elements << R"json(]}
  }]
})json";
  return s.str();
}

enum class Attachment { DrivenNode, Hub, HubAndTipBody };

inline std::string coupledScene(int elements, double h, double tolerance = 0.0,
                                Attachment attachment = Attachment::HubAndTipBody) {
  const char* angle =
      "if(T - t, omega/T*(t^2/2 + (T/(2*pi))^2*(cos(2*pi*t/T) - 1)), omega*T/2 + omega*(t - T))";
  const bool hub = attachment != Attachment::DrivenNode, tip = attachment == Attachment::HubAndTipBody;
  std::ostringstream s;
  s.precision(17);
  s << R"json({
  "format": "mfbd-scene/1",
  "name": "coupled_cost",
  "parameters": {"L": {"value": 1.0}, "EI": {"value": 1.0}, "rhoA": {"value": 1.0},
                 "omega": {"value": 2.0}, "T": {"value": 0.2}},
  "solver": {"h_max": )json" << h;
  if (tolerance > 0.0) s << ", \"tolerance\": " << tolerance;
  s << R"json(, "rho_inf": 0.9},)json";
  if (hub) {
    s << R"json(
  "bodies": [
    {"name": "hub", "mass": 1.0, "inertia": [0.01, 0.01, 0.01], "position": [0, 0, 0]})json";
    if (tip) s << R"json(,
    {"name": "tip", "mass": 1.0, "inertia": [0.001, 0.001, 0.001], "position": ["L", 0, 0]})json";
    s << R"json(
  ],
  "joints": [
    {"name": "motor", "type": "revolute", "parent": "ground", "child": "hub", "position": [0, 0, 0], "axis": [0, 0, 1],
     "drive": ")json" << angle << R"json("},
    {"name": "root", "type": "fixed", "parent": "hub", "child": {"flexible": "beam", "node": 0}})json";
    if (tip) s << R"json(,
    {"name": "weld", "type": "fixed", "parent": {"flexible": "beam", "at": 1.0}, "child": "tip"})json";
    s << R"json(
  ],)json";
  }
  s << R"json(
  "flexible_bodies": [{
    "name": "beam",
    "beam": {"start": [0, 0, 0], "end": ["L", 0, 0], "elements": )json" << elements << R"json(, "section_y": [0, 1, 0]},
    "section": {"EA": "1e6*EI/L^2", "GJ": "EI", "EIy": "EI", "EIz": "EI", "rhoA": "rhoA",
                "rhoJ": ["2e-6*rhoA*L^2", "1e-6*rhoA*L^2", "1e-6*rhoA*L^2"]},)json";
  if (!hub) s << R"json(
    "supports": [{"node": 0, "type": "driven", "axis": [0, 0, 1], "angle": ")json" << angle << R"json("}],)json";
  s << R"json(
    "outputs": {"nodes": [)json" << elements << R"json(]}
  }]
})json";
  return s.str();
}

inline bool validScene(const std::string& name) {
  return name == "cantilever" || name == "driven" || name == "hub" || name == "coupled";
}

// The scene of the benchmarks' --scene option by name (validScene).
inline std::string costScene(const std::string& name, int elements, double h, double tolerance = 0.0) {
  if (name == "cantilever") return cantileverScene(elements, h, tolerance);
  const Attachment a = name == "driven" ? Attachment::DrivenNode : name == "hub" ? Attachment::Hub
                                                                                 : Attachment::HubAndTipBody;
  return coupledScene(elements, h, tolerance, a);
}
