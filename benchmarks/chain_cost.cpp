// Per-step cost of a rigid n-body pendulum chain against n: n uniform bars
// (1/n m, 1/n kg each) on revolute joints, released from horizontal under
// gravity, advanced by Simulation::doStep with implicit substeps h (modified
// Newton: the iteration matrix is refactorised only when Newton slows, and at
// each communication point). Prints one CSV row per n: wall time per
// substep, Newton iterations and factorizations per substep, and the parts
// of one Newton iteration at the final state (residual, tangent, assembly
// and factorization, solve), each timed alone.
//
// Timing: each n repeats from a fresh Simulation until min-time has passed;
// the fastest run counts (filters out other processes). A benchmark, never
// a test.
//
//   chain_cost [--bodies 2,5,...] [--duration 0.2] [--h 1e-3]
//              [--communication 0.01] [--min-time 0.5] [--max-repeats 20]
//              [--newton-matrix automatic|joint_space|recursive] [--bar-length 0 (= 1/n)]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "integrator/time_stepper.hpp"
#include "scene/scene.hpp"
#include "simulation.hpp"

namespace {

struct Options {
  std::vector<int> bodies{2, 5, 10, 20, 50, 100, 200};
  double duration = 0.2, h = 1e-3, communication = 0.01, minTime = 0.5;
  int maxRepeats = 20;
  std::string newtonMatrix = "automatic";
  double barLength = 0.0;  // 0: 1/n m (the chain's length is 1 m)
};

std::string chainScene(int n, double h, const std::string& newtonMatrix, double barLength) {
  const double length = barLength > 0.0 ? barLength : 1.0 / n, mass = 1.0 / n,
               inertia = mass * length * length / 12.0;
  std::ostringstream s;
  s.precision(17);
  s << "{\"format\": \"mfbd-scene/1\", \"name\": \"chain\", \"gravity\": [0, -9.81, 0],"
    << " \"solver\": {\"h_max\": " << h << ", \"newton_matrix\": \"" << newtonMatrix << "\"}, \"bodies\": [";
  for (int i = 0; i < n; ++i)
    s << (i ? ", " : "") << "{\"name\": \"bar" << i << "\", \"mass\": " << mass << ", \"inertia\": [0, " << inertia
      << ", " << inertia << "], \"position\": [" << (i + 0.5) * length << ", 0, 0]}";
  s << "], \"joints\": [";
  for (int i = 0; i < n; ++i)
    s << (i ? ", " : "") << "{\"name\": \"hinge" << i << "\", \"type\": \"revolute\", \"parent\": \""
      << (i ? "bar" + std::to_string(i - 1) : std::string("ground")) << "\", \"child\": \"bar" << i
      << "\", \"position\": [" << i * length << ", 0, 0]}";
  s << "], \"outputs\": {\"bodies\": [], \"joints\": []}}";
  return s.str();
}

double seconds(const std::function<void()>& work, double minTime = 0.05) {
  int reps = 0;
  const auto start = std::chrono::steady_clock::now();
  double elapsed = 0.0;
  do {
    work();
    ++reps;
    elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  } while (elapsed < minTime);
  return elapsed / reps;
}

// The iteration matrix as the integrator assembles it.
struct Stepper : mfbd::TimeStepper {
  using TimeStepper::TimeStepper;
  using TimeStepper::iterationMatrix;
  using TimeStepper::newtonSize;
  bool initialize(mfbd::Dynamics&, mfbd::IntegratorState&, std::string&) override { return true; }
  bool substep(mfbd::Dynamics&, mfbd::IntegratorState&, double, std::string&) override { return true; }
};

void measure(int n, const Options& o) {
  const mfbd::Scene scene = mfbd::parseScene(chainScene(n, o.h, o.newtonMatrix, o.barLength));
  const long steps = std::lround(o.duration / o.communication);
  double best = 1e300, total = 0.0;
  int repeats = 0;
  long substeps = 0, newton = 0, factorizations = 0, rejected = 0;
  std::unique_ptr<mfbd::Simulation> last;
  while (repeats < o.maxRepeats && (repeats == 0 || total < o.minTime)) {
    auto sim = std::make_unique<mfbd::Simulation>(scene);
    std::string message;
    if (!sim->initialize(0.0, message)) {
      std::fprintf(stderr, "initialize failed: %s\n", message.c_str());
      std::exit(1);
    }
    const auto start = std::chrono::steady_clock::now();
    for (long k = 0; k < steps; ++k)
      if (!sim->doStep(o.communication).ok) {
        std::fprintf(stderr, "n = %d: doStep failed\n", n);
        std::exit(1);
      }
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    best = std::min(best, t);
    total += t;
    ++repeats;
    substeps = sim->state().substeps;
    newton = sim->state().newtonIterations;
    factorizations = sim->state().factorizations;
    rejected = sim->state().rejectedSubsteps;
    last = std::move(sim);
  }
  // One Newton iteration taken apart, at the final state.
  auto& system = const_cast<mfbd::System&>(last->system());
  const mfbd::IntegratorState& s = last->state();
  const double cC = 2.0 / o.h, cK = 4.0 / (o.h * o.h);  // of the order generalized-alpha uses
  Eigen::VectorXd r, phi;
  const double residual = seconds([&] { system.residual(s.t, s.q, s.v, s.vdot, s.lambda, r, phi); });
  const double tangent = seconds([&] {
    mfbd::Triplets S, G;
    system.tangent(s.t, s.q, s.v, s.vdot, s.lambda, 1.0, cC, cK, S, G);
  });
  // Assembly (tangent and matrix) and the numeric factorization, the
  // pattern analysed once as in a run.
  mfbd::LinearSolver solver;
  mfbd::SparseMatrix A;
  const double assemble = seconds([&] { A = Stepper::iterationMatrix(system, s, 1.0, cC, cK); });
  solver.analyzePattern(A);
  const double factorize = seconds([&] { solver.factorize(A); });
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(Stepper::newtonSize(system, 1.0));
  const double solve = seconds([&] { volatile double x = solver.solve(b)[0]; (void)x; });
  std::printf("%d,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%ld,%ld,%d\n", n, 1e6 * best / substeps,
              double(newton) / substeps, double(factorizations) / substeps, 1e6 * residual, 1e6 * tangent,
              1e6 * assemble, 1e6 * factorize, 1e6 * solve, substeps, rejected, repeats);
  std::fflush(stdout);
}

std::vector<int> parseList(const char* text) {
  std::vector<int> out;
  std::stringstream s(text);
  std::string item;
  while (std::getline(s, item, ',')) out.push_back(std::stoi(item));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    const char* value = argv[i + 1];
    if (a == "--bodies") o.bodies = parseList(value);
    else if (a == "--duration") o.duration = std::atof(value);
    else if (a == "--h") o.h = std::atof(value);
    else if (a == "--communication") o.communication = std::atof(value);
    else if (a == "--min-time") o.minTime = std::atof(value);
    else if (a == "--max-repeats") o.maxRepeats = std::atoi(value);
    else if (a == "--newton-matrix") o.newtonMatrix = value;
    else if (a == "--bar-length") o.barLength = std::atof(value);
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  std::printf("bodies,us_per_step,newton_per_step,factorizations_per_step,residual_us,tangent_us,"
              "assembly_us,factorization_us,solve_us,substeps,rejected_substeps,repeats\n");
  for (int n : o.bodies) measure(n, o);
  return 0;
}
