// The Newton iteration shared by the dynamic substep (GeneralizedAlpha) and
// static equilibrium (StaticEquilibrium): one loop (solveNewton), a named
// convergence test, and one object that decides when the Newton matrix is
// refreshed (MatrixRefreshPolicy), whose whole memory is one copyable value
// (NewtonMemory).
#pragma once
#include <string>

#include "math/configuration.hpp"

namespace mfbd {

// Everything of the modified Newton iteration that carries over from one
// substep to the next, and so influences the next result: a plain value, so
// that a saved FMU state holds it member by member. The factorised matrix
// itself is rebuilt from the state it was factorised at (origin) and the
// substep size (factoredStep).
struct NewtonMemory {
  double factoredStep = 0.0;  // substep size of the current factorization; 0 = none (refresh)
  // The iterate the current matrix was factorised at: the matrix is a
  // function of it (and of factoredStep), and corrections are turned with
  // the rotations since origin.q (Dynamics::turnWithRotations).
  struct Origin {
    double t = 0.0;
    Configuration q;
    VectorXd v, vdot, lambda;
  } origin;
  double correctionNoise = 0.0;     // of the current factorization (GeneralizedAlpha::constraintNoise)
  bool elasticCoordinates = true;   // of the system, read at the last factorization
  int freshStarts = 0;              // substeps still to start with a fresh matrix
  double lastIterations = 1e9;      // corrections of the last accepted substep (none yet: many)
  double substepsSinceFactorization = 0.0;  // accepted since the current factorization
  double firstRate = 0.0;  // contraction at the first check of the last substep with a kept matrix
  double lastRate = 1.0;   // contraction at the last check of the previous substep (1: unknown)
  // Since the last communication point (beginAdvance): the error Newton
  // left in the substeps' positions, and their local discretisation error.
  double newtonErrorLeft = 0.0;
  double discretisationError = 0.0;
};

// One Newton correction as the convergence test and the policy see it.
struct NewtonIterate {
  int k = 0;                  // index of the correction, from 0
  double size = 0.0;          // largest entry of the correction (m, rad)
  double previous = 0.0;      // the same of correction k - 1
  int withFreshMatrix = -1;   // corrections with a matrix made in this solve (-1: an older one)
  double violation = 0.0;     // largest constraint residual before the correction
  double violationFloor = 0.0;  // its round-off level
};

// What a convergence test found out about a correction.
struct Assessment {
  bool converged = false;
  double rho = 1.0;        // contraction rate size / previous (1 at the first correction)
  double remaining = 0.0;  // estimated error left after the correction
  double resolved = 0.0;   // the error that counts as converged
  double floor = 0.0;      // round-off floor of the corrections
};

class ConvergenceTest {
 public:
  virtual ~ConvergenceTest() = default;
  virtual Assessment assess(const NewtonIterate& it, const NewtonMemory& memory) const = 0;
};

// Statics: the correction itself and the constraint residual below the
// tolerance (full Newton converges quadratically, so the error left after a
// small correction is far smaller still).
class CorrectionSizeTest : public ConvergenceTest {
 public:
  explicit CorrectionSizeTest(double tolerance) : tolerance_(tolerance) {}
  Assessment assess(const NewtonIterate& it, const NewtonMemory& memory) const override;

 private:
  double tolerance_;
};

// Dynamics: the error left after the correction, estimated from the
// contraction rate (rho / (1 - rho) times the correction; Hairer & Wanner
// IV.8), below `target` (see the .cpp), or the corrections at their
// round-off floor.
class ErrorLeftTest : public ConvergenceTest {
 public:
  // `increment`: the substep's increment that the corrections add to (its
  // ulps are part of the floor); `coordinateScale`: the largest coordinate.
  ErrorLeftTest(double tolerance, double target, double coordinateScale, const NewtonMemory& memory,
                const VectorXd& increment);
  Assessment assess(const NewtonIterate& it, const NewtonMemory& memory) const override;

 private:
  double tolerance_, target_, coordinateUlps_, coordinateFloor_;
  const VectorXd& increment_;
};

// When the Newton matrix is refactorised: modified Newton (kept across
// substeps, refreshed when the contraction slows, see the .cpp), or full
// Newton (every iteration).
class MatrixRefreshPolicy {
 public:
  enum class Kind { Modified, Full };
  explicit MatrixRefreshPolicy(Kind kind = Kind::Modified) : kind_(kind) {}

  NewtonMemory memory;

  // At a communication point: a fresh matrix when it pays (see the .cpp).
  void beginAdvance(double tangentCost);
  void beginSolve();
  bool needsFactorization(double h) const;
  void factorized(double h);
  // After every correction, before the convergence verdict.
  void observe(const NewtonIterate& it, const Assessment& a);
  void accepted(const NewtonIterate& it, const Assessment& a);
  // The converged substep's local discretisation error (m, rad), against
  // which beginAdvance judges the error Newton left.
  void addDiscretisationError(double e) { memory.discretisationError += e; }
  // Not converged: refresh the matrix if its contraction is too slow; true
  // when the iteration diverges with a matrix of its own.
  bool diverging(const NewtonIterate& it, const Assessment& a, int maxIterations);
  void failed() { memory.factoredStep = 0.0; }

  static constexpr double kRefreshHorizon = 4.0;
  static constexpr double kStaleRate = 1e-3;
  static constexpr double kNewtonErrorFraction = 1e-2;
  static constexpr int kFreshStarts = 4;

 private:
  Kind kind_;
};

// The problem one Newton iteration solves.
class NewtonSystem {
 public:
  virtual ~NewtonSystem() = default;
  // Residual at the current iterate; false (with why) when not finite.
  // Fills the constraint residual's size and floor of `it`.
  virtual bool evaluate(NewtonIterate& it, std::string& why) = 0;
  virtual bool factorize(double h, std::string& why) = 0;
  // Solves with the current factorization and applies the correction; its
  // largest entry, NaN when some entry is not finite.
  virtual double correct() = 0;
};

// Newton's loop: true when converged; else `why` says what failed.
// `goal` completes "Newton did not ... in N iterations".
bool solveNewton(NewtonSystem& problem, const ConvergenceTest& test, MatrixRefreshPolicy& policy, double h,
                 int maxIterations, const char* goal, std::string& why);

}  // namespace mfbd
