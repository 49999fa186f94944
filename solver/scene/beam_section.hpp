// Cross-section properties of a beam, in SI units, in the section frame
// (x along the beam axis, y and z the section's principal axes).
// docs/design.md 3 "Flexible bodies": the local linear Timoshenko stiffness of the
// corotational element and the lumped nodal inertia are built from these.
#pragma once
#include "math/rotation.hpp"

namespace mfbd {

struct BeamSection {
  double EA = 0.0;   // axial stiffness [N]
  double GAy = 0.0;  // shear stiffness along y, shear factor included [N];
                     // 0 or +inf: shear-rigid in y (Euler-Bernoulli)
  double GAz = 0.0;  // shear stiffness along z, as GAy [N]
  double GJ = 0.0;   // torsional stiffness (J = torsion constant) [N m^2]
  double EIy = 0.0;  // bending stiffness about y (deflection along z) [N m^2]
  double EIz = 0.0;  // bending stiffness about z (deflection along y) [N m^2]
  double rhoA = 0.0; // mass per unit length [kg/m]
  Vec3 rhoJ = Vec3::Zero();  // rotary inertia per unit length about the
                             // section x (polar), y and z axes [kg m]
};

// Isotropic linear elastic material [Pa, Pa, kg/m^3].
struct BeamMaterial {
  double E = 0.0;
  double G = 0.0;
  double rho = 0.0;
  double poissonRatio() const { return E / (2.0 * G) - 1.0; }
};

// Shear correction factors are Cowper's (J. Appl. Mech. 33, 1966), which
// depend on Poisson's ratio nu = E/(2G) - 1:
//   rectangle   k = 10(1+nu) / (12+11nu)              (0.850 at nu = 0.3)
//   circle      k = 6(1+nu) / (7+6nu)                 (0.886 at nu = 0.3)
//   tube        k = 6(1+nu)(1+m^2)^2 /
//                   ((7+6nu)(1+m^2)^2 + (20+12nu) m^2),  m = ri/ro
// Invalid dimensions (not positive, ri >= ro) or material (E, G <= 0, rho < 0)
// throw std::invalid_argument naming the argument.

// Solid rectangle: width b along section y, height h along section z [m].
// Torsion constant from the Saint-Venant series (Timoshenko-Goodier).
BeamSection rectangleSection(const BeamMaterial& material, double b, double h);

// Solid circle of diameter d [m].
BeamSection circleSection(const BeamMaterial& material, double d);

// Circular tube of outer radius ro and inner radius ri [m], 0 <= ri < ro.
BeamSection tubeSection(const BeamMaterial& material, double ro, double ri);

}  // namespace mfbd
