// What the integrator sees of a mechanical system (DESIGN.md 2): a
// configuration manifold with a retraction, the residual of the equations of
// motion and constraints, and the iteration-matrix blocks with scalar factors.
//   r   = M(q) vdot - Q(q, v, t) + Phi_q^T lambda        (velocityCount rows)
//   phi = Phi(q)                                         (constraintCount rows)
#pragma once
#include <vector>

#include <Eigen/SparseCore>

#include "model/configuration.hpp"

namespace mfbd {

using Triplets = std::vector<Eigen::Triplet<double>>;

class Dynamics {
 public:
  virtual ~Dynamics() = default;
  virtual int velocityCount() const = 0;
  virtual int constraintCount() const = 0;
  // q <- q o exp(dq)
  virtual void retract(Configuration& q, const VectorXd& dq) const = 0;
  virtual void residual(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                        const VectorXd& lambda, VectorXd& r, VectorXd& phi) = 0;
  // gamma with d2/dt2 Phi = Phi_q vdot + gamma (for consistent accelerations).
  virtual VectorXd constraintAccelerationTerm(double t, const Configuration& q, const VectorXd& v) = 0;
  // Appends cM M + cC dr/dv + cK dr/dq (derivative along the retraction) to
  // `iteration`, and Phi_q to `constraintJacobian` (rows from 0).
  virtual void tangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                       const VectorXd& lambda, double cM, double cC, double cK, Triplets& iteration,
                       Triplets& constraintJacobian) = 0;
  // Size of the world positions (m) the constraint rows of the last residual
  // were computed from: their round-off is a few ulps of it, which no Newton
  // correction can remove (a 40 m long chain of bodies: ~1e-14 m).
  virtual double constraintLengthScale() const { return 1.0; }
};

}  // namespace mfbd
