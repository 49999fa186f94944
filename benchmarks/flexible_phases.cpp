// One Newton iteration of the flexible cantilever (cantilever_scene.hpp)
// taken apart: residual, tangent (element blocks as triplets), assembly of
// the triplets into the kept pattern, KLU factorization, solve, retraction,
// each timed alone (fastest of five repetitions) on the state a run reaches
// after `duration`, and printed in ns per element. Where flexible_cost.cpp
// says how much a step costs, this says where it goes.
//
//   flexible_phases [--elements 10,100,...] [--duration 0.2] [--h 1e-3]
//                   [--communication 0.01] [--scene cantilever|driven|hub|coupled] [--cpu 1]
//
// --scene driven|hub|coupled: the beam spun up by a driven node, a driven
// hub, a hub and a tip body (coupledScene, benchmarks/coupled_cost.py). --cpu 1: process
// CPU time instead of wall time (steadier on a machine shared with other jobs).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "cantilever_scene.hpp"
#include "integrator/linear_solver.hpp"
#include "model/model.hpp"
#include "simulation.hpp"

namespace {

bool useCpuTime = false;  // --cpu: process CPU time instead of wall time

double nowMicroseconds() {
  if (useCpuTime) {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return 1e6 * double(t.tv_sec) + 1e-3 * double(t.tv_nsec);
  }
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Fastest of several repetitions of `body` (itself run `count` times), in us.
template <class Body>
double fastest(int count, Body&& body) {
  double best = std::numeric_limits<double>::infinity();
  for (int trial = 0; trial < 5; ++trial) {
    const double start = nowMicroseconds();
    for (int k = 0; k < count; ++k) body();
    best = std::min(best, nowMicroseconds() - start);
  }
  return best / count;
}

// One Newton iteration taken apart, at the state a run reaches after
// `duration`, with the step's factors (rho_inf = 0.9, h).
void timePhases(const mfbd::Scene& scene, double duration, double communication, double h, int n) {
  mfbd::Simulation sim(scene);
  std::string message;
  sim.initialize(0.0, message);
  for (long k = 0; k < std::lround(duration / communication); ++k) sim.doStep(communication);
  const mfbd::IntegratorState s = sim.state();
  mfbd::System system(mfbd::assemble(scene));
  const double cC = 1.0 / h, cK = 1.0 / (h * h);  // the factors' orders of magnitude
  Eigen::VectorXd r, phi;
  mfbd::Triplets triplets, jacobian;
  mfbd::SparseAssembly assembly;
  mfbd::LinearSolver solver;
  const int count = std::max(1, 20000 / n);
  auto tangent = [&] {
    triplets.clear();
    jacobian.clear();
    system.tangent(s.t, s.q, s.v, s.vdot, s.lambda, 1.0, cC, cK, triplets, jacobian);
  };
  const double residual = fastest(count, [&] { system.residual(s.t, s.q, s.v, s.vdot, s.lambda, r, phi); });
  const double tangentTime = fastest(std::max(1, count / 10), tangent);
  tangent();
  for (int i = 0; i < system.velocityCount(); ++i) triplets.emplace_back(i, i, 0.0);
  assembly.assign(system.velocityCount(), triplets);
  const double assemble = fastest(count, [&] { assembly.assign(system.velocityCount(), triplets); });
  solver.analyzePattern(assembly.matrix());
  const double factorize = fastest(std::max(1, count / 10), [&] { solver.factorize(assembly.matrix()); });
  Eigen::VectorXd x;
  const double solve = fastest(count, [&] { x = solver.solve(r); });
  mfbd::Configuration q = s.q;
  const Eigen::VectorXd dq = 1e-9 * Eigen::VectorXd::Ones(system.velocityCount());
  const double retract = fastest(count, [&] {
    q = s.q;
    system.retract(q, dq);
  });
  std::printf("%d,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g\n", n, 1e3 * residual / n, 1e3 * tangentTime / n, 1e3 * assemble / n,
              1e3 * factorize / n, 1e3 * solve / n, 1e3 * retract / n);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> elements{10, 20, 50, 100, 200, 500, 1000, 2000};
  double duration = 0.2, h = 1e-3, communication = 0.01;
  std::string sceneName = "cantilever";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], value = argv[i + 1];
    if (a == "--elements") {
      elements.clear();
      std::stringstream s(value);
      std::string item;
      while (std::getline(s, item, ',')) elements.push_back(std::stoi(item));
    } else if (a == "--duration") {
      duration = std::stod(value);
    } else if (a == "--h") {
      h = std::stod(value);
    } else if (a == "--communication") {
      communication = std::stod(value);
    } else if (a == "--cpu") {
      useCpuTime = value == "1";
    } else if (a == "--scene" && validScene(value)) {
      sceneName = value;
    } else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  std::printf("elements,residual_ns_per_element,tangent_ns_per_element,assembly_ns_per_element,"
              "factorization_ns_per_element,solve_ns_per_element,retraction_ns_per_element\n");
  for (int n : elements) timePhases(mfbd::parseScene(costScene(sceneName, n, h)), duration, communication, h, n);
  return 0;
}
