// Input signals of one kind (joint forces and drive rates, force-element
// inputs, flexible-body inputs): the values the master sets and, for
// interpolation within a communication step (fmi2SetRealInputDerivatives),
// their first and second time derivatives. Input i follows
//   u_i(t) = value_i + d1_i (t - anchor_i) + d2_i (t - anchor_i)^2 / 2,
// anchor_i the time at which its value or a derivative was last set.
// Without derivatives u_i(t) = value_i exactly (held over the step).
#pragma once
#include <Eigen/Core>

namespace mfbd {

struct InputSignals {
  static constexpr int kMaxOrder = 2;  // highest derivative order accepted

  Eigen::VectorXd value, d1, d2, anchor;
  int movingCount = 0;  // inputs with a derivative that is not zero
  bool moving = false;  // movingCount > 0

  void resize(int n) {
    value.setZero(n);
    d1.setZero(n);
    d2.setZero(n);
    anchor.setZero(n);
    movingCount = 0;
    moving = false;
  }
  // Value set at time t: its derivatives restart at zero.
  void setValue(int i, double u, double t) {
    value[i] = u;
    setDerivatives(i, 0.0, 0.0);
    anchor[i] = t;
  }
  void setDerivative(int i, int order, double du, double t) {
    setDerivatives(i, order == 1 ? du : d1[i], order == 2 ? du : d2[i]);
    anchor[i] = t;
  }
  double at(int i, double t) const {
    if (!moving) return value[i];
    const double s = t - anchor[i];
    return value[i] + s * (d1[i] + 0.5 * s * d2[i]);
  }
  // du_i/dt at t.
  double rate(int i, double t) const { return moving ? d1[i] + (t - anchor[i]) * d2[i] : 0.0; }
  // The integral of u_i from `from` to t (a rate input's coordinate).
  double integral(int i, double from, double t) const {
    const double h = t - from;
    if (!moving) return value[i] * h;
    const double a = t - anchor[i], b = from - anchor[i];  // a^k - b^k = h (...)
    return h * (value[i] + d1[i] * 0.5 * (a + b) + d2[i] * (a * a + a * b + b * b) / 6.0);
  }
  // All inputs at t, for the forces to read through current(): held ones
  // are read where they are set, not copied at every evaluation.
  void evaluate(double t) {
    if (!moving) return;
    now_.resize(value.size());
    for (int i = 0; i < int(value.size()); ++i) now_[i] = at(i, t);
  }
  // The inputs at the time of the last evaluate().
  const Eigen::VectorXd& current() const { return moving ? now_ : value; }
  template <class Archive>
  void visitState(Archive& ar) {
    ar(value, d1, d2, anchor, movingCount, moving);
  }

 private:
  Eigen::VectorXd now_;  // evaluate()'s inputs while some move
  void setDerivatives(int i, double first, double second) {
    movingCount += int(first != 0.0 || second != 0.0) - int(d1[i] != 0.0 || d2[i] != 0.0);
    d1[i] = first;
    d2[i] = second;
    moving = movingCount > 0;
  }
};

}  // namespace mfbd
