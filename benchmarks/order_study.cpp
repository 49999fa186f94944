// Convergence of a rigid scene as h shrinks: runs the scene (JSON) to
// --stop with substeps of --h (several, comma separated) at Newton
// --tolerance and --rho, and prints per run the largest energy change
// over the run (rigid bodies, gravity), the final joint coordinates and
// the substeps and Newton iterations spent. For the error tables of
// benchmarks/README.md (four_bar, slider_crank, double_pendulum); positions
// are compared against the run at the finest h by the caller.
//
//   order_study scene.json --stop 1 --h 1e-3,1e-4 [--tolerance 1e-14] [--rho 0.8]
//               [--communication 0.01]
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "model/model.hpp"
#include "simulation.hpp"

namespace {

double rigidEnergy(const mfbd::System& system) {
  const mfbd::Model& model = system.model();
  double e = 0.0;
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const mfbd::BodyKinematics& k = system.data().body[i];
    const mfbd::Body& b = model.bodies[i];
    const mfbd::Vec3 w = k.orientation.transpose() * k.angularVelocity;
    e += 0.5 * b.mass * k.velocity.squaredNorm() + 0.5 * w.dot(b.inertia * w) - b.mass * model.gravity.dot(k.position);
  }
  return e;
}

std::vector<double> list(const std::string& text) {
  std::vector<double> values;
  std::stringstream s(text);
  for (std::string item; std::getline(s, item, ',');) values.push_back(std::stod(item));
  return values;
}

}  // namespace

int main(int argc, char** argv) {
  std::string path = argv[1];
  double stop = 1.0, tolerance = 1e-14, rho = -1.0, communication = 0.01;
  std::vector<double> steps = {1e-3};
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--stop") stop = std::stod(value);
    else if (key == "--h") steps = list(value);
    else if (key == "--tolerance") tolerance = std::stod(value);
    else if (key == "--rho") rho = std::stod(value);
    else if (key == "--communication") communication = std::stod(value);
  }
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  std::printf("h,tolerance,energy_error,substeps,newton,factorizations,rejected,coordinates\n");
  for (const double h : steps) {
    mfbd::Scene scene = mfbd::parseScene(text.str());
    scene.solver.hMax = h;
    scene.solver.tolerance = tolerance;
    if (rho >= 0.0) scene.solver.rhoInf = rho;
    mfbd::Simulation sim(scene);
    std::string message;
    if (!sim.initialize(0.0, message)) {
      std::fprintf(stderr, "%s\n", message.c_str());
      return 1;
    }
    const mfbd::System& system = sim.system();
    const double e0 = rigidEnergy(system);
    double worst = 0.0;
    const long count = std::lround(stop / communication);
    for (long k = 0; k < count; ++k) {
      const mfbd::AdvanceResult result = sim.doStep(communication);
      if (!result.ok) {
        std::fprintf(stderr, "h = %g: %s\n", h, result.message.c_str());
        return 1;
      }
      worst = std::max(worst, std::abs(rigidEnergy(system) - e0));
    }
    const mfbd::IntegratorState& s = sim.state();
    std::printf("%g,%g,%.6e,%ld,%ld,%ld,%ld", h, tolerance, worst, s.substeps, s.newtonIterations, s.factorizations,
                s.rejectedSubsteps);
    for (int i = 0; i < s.q.scalars.size(); ++i) std::printf(",%.17g", s.q.scalars[i]);
    std::printf("\n");
    std::fflush(stdout);
  }
  return 0;
}
