// What the integrator sees of a mechanical system (docs/design.md 2): a
// configuration manifold with a retraction, the residual of the equations of
// motion and constraints, and the iteration-matrix blocks with scalar factors.
//   r   = M(q) vdot - Q(q, v, t) + Phi_q^T lambda        (velocityCount rows)
//   phi = Phi(q)                                         (constraintCount rows)
#pragma once
#include <vector>

#include "math/configuration.hpp"
#include "math/triplets.hpp"

namespace mfbd {

class Dynamics {
 public:
  virtual ~Dynamics() = default;
  virtual int velocityCount() const = 0;
  virtual int constraintCount() const = 0;
  // q <- q o exp(dq)
  virtual void retract(Configuration& q, const VectorXd& dq) const = 0;
  // The local chart's velocity: along q(t) = q0 o exp(delta(t)) with
  // velocity v, delta' = dexp^-1_delta(v): T^-1(delta) v on each rotation
  // block (right-trivialised, body-frame angular velocity), v on scalars
  // (Munthe-Kaas). By default every coordinate is a scalar.
  virtual void chartRate(const VectorXd& /*delta*/, const VectorXd& v, VectorXd& rate) const { rate = v; }
  virtual void residual(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                        const VectorXd& lambda, VectorXd& r, VectorXd& phi) = 0;
  // The accelerations vdot = M(q)^-1 Q(q, v, t) where the system can give
  // them directly (a small tree without constraints: its dense joint-space
  // mass matrix); false otherwise, and the integrator solves its iteration
  // matrix with cM = 1.
  virtual bool unconstrainedAccelerations(double /*t*/, const Configuration& /*q*/, const VectorXd& /*v*/,
                                          VectorXd& /*vdot*/) {
    return false;
  }
  // gamma with d2/dt2 Phi = Phi_q vdot + gamma (for consistent accelerations).
  virtual VectorXd constraintAccelerationTerm(double t, const Configuration& q, const VectorXd& v) = 0;
  // Appends cM M + cC dr/dv + cK dr/dq (derivative along the retraction) to
  // `iteration`, and Phi_q to `constraintJacobian` (rows from 0).
  // A system may write its matrix with auxiliary unknowns that keep it
  // sparse (a long rigid tree: body-level variations instead of the dense
  // B^T M B): indices velocityCount() .. + auxiliaryCount(cM) of both lists
  // name them. Their residual rows are zero and their solution is dropped;
  // the velocity block of the Newton matrix is the Schur complement.
  virtual void tangent(double t, const Configuration& q, const VectorXd& v, const VectorXd& vdot,
                       const VectorXd& lambda, double cM, double cC, double cK, Triplets& iteration,
                       Triplets& constraintJacobian) = 0;
  virtual int auxiliaryCount(double /*cM*/) const { return 0; }
  // Optionally, the order in which to eliminate the matrix: pivots as
  // (row, column) pairs in the indices of tangent(), the rest after them.
  // A tree's body blocks from the leaves in (the recursion's own order)
  // factorise with no fill and unit pivots; empty: the solver chooses.
  virtual std::vector<std::pair<int, int>> pivotOrder(double /*cM*/) const { return {}; }
  // Size of the world positions (m) the constraint rows of the last residual
  // were computed from: their round-off is a few ulps of it, which no Newton
  // correction can remove (a 40 m long chain of bodies: ~1e-14 m).
  virtual double constraintLengthScale() const { return 1.0; }
  // Phi_q v + Phi_t at (t, q, v): the velocity constraints' violation
  // (constraintCount rows; empty when the system cannot say).
  virtual VectorXd velocityConstraints(double /*t*/, const Configuration& /*q*/, const VectorXd& /*v*/) { return {}; }
  // The largest violation, at the last residual, of the constraint rows left
  // out of the solve as redundant (System::setRedundantRows: their rows of
  // the residual read zero). They hold where the others do while they stay
  // redundant (TimeStepper::redundantRowsHold).
  virtual double redundantViolation() const { return 0.0; }
  // Takes the rows left out as redundant back into the solve; false when
  // none were left out.
  virtual bool readmitRedundantRows() { return false; }
  // Whether stiff forces read the coordinates (flexible nodes, springs,
  // bushings): then their round-off, a few ulps of the coordinates, makes
  // force noise that the Newton corrections cannot resolve below. A rigid
  // system moved by gravity, inertia and constraints alone resolves
  // corrections far below its coordinates' ulps (they add to the substep's
  // increment, not to the coordinates).
  virtual bool elasticCoordinates() const { return true; }
  // Whether the system has flexible bodies: modes stiff by construction
  // (a beam's axial and shear modes) that substeps are not meant to
  // resolve, removed by the integrator's numerical damping.
  virtual bool flexibleBodies() const { return false; }
  // What a fresh tangent costs, in residual evaluations: an estimate from
  // the system's structure (deterministic, unlike a timing), for the
  // integrator's choice between refreshing the Newton matrix and iterating
  // longer with the one it has.
  virtual double tangentCost() const { return 1.0; }
  // Unknowns whose rows and columns turn with a stored rotation (a flexible
  // node's world translation turns with the node): x <- D x (or D^T x with
  // transpose), D block diagonal, the rotation each such block has turned
  // through from `from` to `to`, identity elsewhere. A Newton matrix
  // factorised at `from` then serves at `to` as D S D^T. Only velocity rows.
  virtual void turnWithRotations(const Configuration& /*from*/, const Configuration& /*to*/, VectorXd& /*x*/,
                                 bool /*transpose*/) const {}
  // The same blocks of x turned through the rotation their bodies make in
  // time h at their present angular velocity (from v): the world-frame
  // acceleration of a point on a spinning body turns with it.
  virtual void turnOverStep(const Configuration& /*q*/, const VectorXd& /*v*/, double /*h*/, VectorXd& /*x*/) const {}
};

}  // namespace mfbd
