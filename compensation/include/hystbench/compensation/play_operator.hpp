#pragma once
// Play (backlash) operator: y(k) = max(u(k) - r, min(u(k) + r, y(k-1))).
// Units: u and y in the caller's input unit, r >= 0 in the same unit.
// Real-time safe: step() and peek() never allocate or throw.
#include <algorithm>

namespace hystbench::compensation {

class PlayOperator {
 public:
  /// threshold r >= 0; initial_output is y(-1), the state before the first sample.
  explicit PlayOperator(double threshold, double initial_output = 0.0);

  /// Advances one sample; returns the new output.
  double step(double u) noexcept { return y_ = peek(u); }
  /// Output the operator would give for input u now, without changing state.
  double peek(double u) const noexcept { return std::max(u - r_, std::min(u + r_, y_)); }

  double threshold() const noexcept { return r_; }
  double output() const noexcept { return y_; }
  void set_output(double y) noexcept { y_ = y; }

 private:
  double r_;
  double y_;
};

}  // namespace hystbench::compensation
