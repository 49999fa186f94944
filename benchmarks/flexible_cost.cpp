// Per-step cost of the flexible mesh: a clamped cantilever of N corotational
// beam elements (the F3 scene of examples/cantilever_vibration, tip pulse
// included; or with --scene driven|hub|coupled the same beam spun up by a
// driven node, a driven hub, or a hub and a tip body: cantilever_scene.hpp)
// advanced by Simulation::doStep with implicit substeps h, for several N.
// Prints one CSV row per N: wall time per substep and per element and
// substep, Newton iterations and factorizations per substep.
//
// Timing: each N runs `repeats` times from a fresh Simulation (scene parse
// and assembly are not timed); the fastest run counts, which filters out
// noise from other processes; the least process CPU time of the runs is
// printed too (cpu_us_per_step), steadier on a shared machine. A benchmark,
// never a test.
//
//   flexible_cost [--elements 10,20,...] [--duration 0.2] [--h 1e-3]
//                 [--communication 0.01] [--min-time 0.5] [--max-repeats 20]
//                 [--tolerance 1e-12] [--state FILE] [--scene cantilever|driven|hub|coupled]
//
// --state FILE writes the final q, v of every N (full precision) so two
// builds can be compared to round-off. benchmarks/flexible_phases.cpp takes
// one Newton iteration apart on the same scene.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "cantilever_scene.hpp"
#include "scene/scene.hpp"
#include "simulation.hpp"

namespace {

struct Options {
  std::vector<int> elements{10, 20, 50, 100, 200, 500, 1000, 2000};
  double duration = 0.2;       // simulated time per run, s
  double h = 1e-3;             // largest implicit substep (scene h_max), s
  double communication = 0.01; // doStep size H, s (the scene's output interval)
  double minTime = 0.5;        // keep repeating a run until this much wall time, s
  double tolerance = 0.0;      // Newton tolerance; 0: the solver's default
  int maxRepeats = 20;
  std::string stateFile;
  std::string scene = "cantilever";  // or "driven", "hub", "coupled": cantilever_scene.hpp
};

// CPU time of this process, s: on a machine shared with other jobs it counts
// only the time this process ran, so it scatters less than the wall time.
double cpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

struct Run {
  double seconds = 0.0;
  double cpuSeconds = 0.0;
  long substeps = 0, newtonIterations = 0, factorizations = 0;
  mfbd::IntegratorState final;
};

Run simulate(const mfbd::Scene& scene, const Options& o) {
  mfbd::Simulation sim(scene);
  std::string message;
  if (!sim.initialize(0.0, message)) {
    std::fprintf(stderr, "initialize failed: %s\n", message.c_str());
    std::exit(1);
  }
  const long steps = std::lround(o.duration / o.communication);
  const auto start = std::chrono::steady_clock::now();
  const double cpuStart = cpuSeconds();
  for (long k = 0; k < steps; ++k) {
    const mfbd::AdvanceResult r = sim.doStep(o.communication);
    if (!r.ok) {
      std::fprintf(stderr, "doStep failed: %s\n", r.message.c_str());
      std::exit(1);
    }
  }
  Run run;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.cpuSeconds = cpuSeconds() - cpuStart;
  run.substeps = sim.state().substeps;
  run.newtonIterations = sim.state().newtonIterations;
  run.factorizations = sim.state().factorizations;
  run.final = sim.state();
  return run;
}

void writeState(std::FILE* f, int elements, const mfbd::IntegratorState& s) {
  std::fprintf(f, "N %d\nq", elements);
  for (double x : s.q.scalars) std::fprintf(f, " %.17g", x);
  for (const mfbd::Mat3& A : s.q.rotations)
    for (int i = 0; i < 9; ++i) std::fprintf(f, " %.17g", A(i));
  std::fprintf(f, "\nv");
  for (double x : s.v) std::fprintf(f, " %.17g", x);
  std::fprintf(f, "\n");
}

std::vector<int> parseList(const char* text) {
  std::vector<int> out;
  std::stringstream s(text);
  std::string item;
  while (std::getline(s, item, ',')) out.push_back(std::stoi(item));
  return out;
}

Options parseOptions(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const char* value = i + 1 < argc ? argv[i + 1] : nullptr;
    if (!value) break;
    if (a == "--elements") o.elements = parseList(value);
    else if (a == "--duration") o.duration = std::atof(value);
    else if (a == "--h") o.h = std::atof(value);
    else if (a == "--communication") o.communication = std::atof(value);
    else if (a == "--min-time") o.minTime = std::atof(value);
    else if (a == "--max-repeats") o.maxRepeats = std::atoi(value);
    else if (a == "--tolerance") o.tolerance = std::atof(value);
    else if (a == "--state") o.stateFile = value;
    else if (a == "--scene" && validScene(value)) o.scene = value;
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      std::exit(2);
    }
    ++i;
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parseOptions(argc, argv);
  std::FILE* state = o.stateFile.empty() ? nullptr : std::fopen(o.stateFile.c_str(), "w");
  std::printf("elements,unknowns,substeps,us_per_step,us_per_element_step,newton_per_step,factorizations_per_step,"
              "repeats,cpu_us_per_step,cpu_us_per_element_step\n");
  for (int n : o.elements) {
    const mfbd::Scene scene = mfbd::parseScene(costScene(o.scene, n, o.h, o.tolerance));
    Run best;
    best.seconds = std::numeric_limits<double>::infinity();
    double total = 0.0, leastCpu = std::numeric_limits<double>::infinity();
    int repeats = 0;
    while (repeats < o.maxRepeats && (repeats == 0 || total < o.minTime)) {
      Run run = simulate(scene, o);
      total += run.seconds;
      ++repeats;
      leastCpu = std::min(leastCpu, run.cpuSeconds);
      if (run.seconds < best.seconds) best = std::move(run);
    }
    const double steps = double(best.substeps);
    const double usPerStep = 1e6 * best.seconds / steps, cpuUsPerStep = 1e6 * leastCpu / steps;
    std::printf("%d,%d,%ld,%.4g,%.4g,%.4g,%.4g,%d,%.4g,%.4g\n", n, int(best.final.v.size()), best.substeps, usPerStep,
                usPerStep / n, best.newtonIterations / steps, best.factorizations / steps, repeats, cpuUsPerStep,
                cpuUsPerStep / n);
    std::fflush(stdout);
    if (state) writeState(state, n, best.final);
  }
  if (state) std::fclose(state);
  return 0;
}
