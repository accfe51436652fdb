#pragma once
// Identical second-order dynamics over several signals, stepped together (internals): one state
// pair per signal, kept in arrays, and the same arithmetic as SecondOrderDynamics::step, so a
// fit that filters many regressor columns sample by sample does not step an object per column.
// Real-time safe step() and reset().
#include <cstddef>
#include <vector>

#include "hystbench/compensation/second_order_dynamics.hpp"

namespace hystbench::compensation::details {

class SecondOrderBank {
 public:
  SecondOrderBank(const SecondOrderDynamics& d, std::size_t signals)
      : p00_(d.phi(0, 0)),
        p01_(d.phi(0, 1)),
        p10_(d.phi(1, 0)),
        p11_(d.phi(1, 1)),
        g0_(d.gam(0)),
        g1_(d.gam(1)),
        s0_(signals, 0.0),
        s1_(signals, 0.0) {}

  /// Signal i settled at x0.
  void reset(std::size_t i, double x0) noexcept {
    s0_[i] = x0;
    s1_[i] = 0.0;
  }
  /// Signals first .. first + n - 1 settled at x[0 .. n).
  void reset(std::size_t first, const double* x, std::size_t n) noexcept {
    for (std::size_t i = 0; i < n; ++i) reset(first + i, x[i]);
  }
  /// Signals first .. first + n - 1 hold x[0 .. n) for one sample; their outputs at the end of it
  /// go to y[0 .. n) (y may be x).
  void step(std::size_t first, const double* x, double* y, std::size_t n) noexcept {
    double* s0 = s0_.data() + first;
    double* s1 = s1_.data() + first;
    for (std::size_t i = 0; i < n; ++i) {
      const double in = x[i];
      const double y0 = p00_ * s0[i] + p01_ * s1[i] + g0_ * in;
      const double y1 = p10_ * s0[i] + p11_ * s1[i] + g1_ * in;
      s0[i] = y0;
      s1[i] = y1;
      y[i] = y0;
    }
  }

 private:
  double p00_, p01_, p10_, p11_, g0_, g1_;
  std::vector<double> s0_, s1_;
};

}  // namespace hystbench::compensation::details
