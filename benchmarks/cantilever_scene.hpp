// The benchmark scene of flexible_cost.cpp and flexible_phases.cpp: the F3
// cantilever of examples/cantilever_vibration (EI = 1, EA = 1e6 EI/L^2,
// rhoA = 1, L = 1, clamped, tip force pulse of 0.02 s) with N elements and
// implicit substep h, as scene JSON; tolerance > 0 overrides the default
// Newton tolerance.
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
