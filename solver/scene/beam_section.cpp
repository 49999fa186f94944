#include "scene/beam_section.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mfbd {

namespace {

constexpr double kPi = 3.14159265358979323846;

void requirePositive(double value, const char* name) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string("beam section: ") + name +
                                " must be positive and finite, got " +
                                std::to_string(value));
  }
}

void checkMaterial(const BeamMaterial& m) {
  requirePositive(m.E, "material E");
  requirePositive(m.G, "material G");
  if (!(m.rho >= 0.0) || !std::isfinite(m.rho)) {
    throw std::invalid_argument("beam section: material rho must be >= 0, got " +
                                std::to_string(m.rho));
  }
}

// Section built from area A, second moments Iy = int z^2 dA, Iz = int y^2 dA,
// torsion constant Jt and shear factors ky, kz.
BeamSection fromGeometry(const BeamMaterial& m, double A, double Iy, double Iz,
                         double Jt, double ky, double kz) {
  BeamSection s;
  s.EA = m.E * A;
  s.GAy = ky * m.G * A;
  s.GAz = kz * m.G * A;
  s.GJ = m.G * Jt;
  s.EIy = m.E * Iy;
  s.EIz = m.E * Iz;
  s.rhoA = m.rho * A;
  // Polar rotary inertia uses the polar moment Iy + Iz, not the torsion
  // constant (warping does not reduce the inertia).
  s.rhoJ = m.rho * Vec3(Iy + Iz, Iy, Iz);
  return s;
}

// Saint-Venant torsion constant of a solid a x c rectangle, a >= c:
// J = a c^3/3 [1 - (192/pi^5)(c/a) sum_{n odd} tanh(n pi a / 2c) / n^5].
double rectangleTorsionConstant(double b, double h) {
  const double a = std::max(b, h), c = std::min(b, h);
  double sum = 0.0;
  for (int n = 1; n < 200; n += 2) {  // terms fall like n^-5
    sum += std::tanh(n * kPi * a / (2.0 * c)) / std::pow(n, 5);
  }
  return a * c * c * c / 3.0 * (1.0 - 192.0 / std::pow(kPi, 5) * (c / a) * sum);
}

}  // namespace

BeamSection rectangleSection(const BeamMaterial& material, double b, double h) {
  checkMaterial(material);
  requirePositive(b, "rectangle width b");
  requirePositive(h, "rectangle height h");
  const double nu = material.poissonRatio();
  const double k = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
  return fromGeometry(material, b * h, b * h * h * h / 12.0, h * b * b * b / 12.0,
                      rectangleTorsionConstant(b, h), k, k);
}

BeamSection circleSection(const BeamMaterial& material, double d) {
  checkMaterial(material);
  requirePositive(d, "circle diameter d");
  const double nu = material.poissonRatio();
  const double k = 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu);
  const double I = kPi * std::pow(d, 4) / 64.0;
  return fromGeometry(material, kPi * d * d / 4.0, I, I, 2.0 * I, k, k);
}

BeamSection tubeSection(const BeamMaterial& material, double ro, double ri) {
  checkMaterial(material);
  requirePositive(ro, "tube outer radius ro");
  if (!(ri >= 0.0) || !(ri < ro)) {
    throw std::invalid_argument(
        "beam section: tube inner radius ri must satisfy 0 <= ri < ro, got " + std::to_string(ri));
  }
  const double nu = material.poissonRatio();
  const double m2 = (ri / ro) * (ri / ro);
  const double p = (1.0 + m2) * (1.0 + m2);
  const double k = 6.0 * (1.0 + nu) * p / ((7.0 + 6.0 * nu) * p + (20.0 + 12.0 * nu) * m2);
  const double I = kPi * (std::pow(ro, 4) - std::pow(ri, 4)) / 4.0;
  return fromGeometry(material, kPi * (ro * ro - ri * ri), I, I, 2.0 * I, k, k);
}

}  // namespace mfbd
