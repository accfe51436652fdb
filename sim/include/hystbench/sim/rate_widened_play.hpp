#pragma once
// Rate dependence of domain switching by thresholds that widen with the input rate (Al
// Janaideh, Rakheja and Su's dynamic thresholds, on the simulator's Preisach relays): a relay
// switches up when the input reaches alpha + b rho and down when it falls to beta - b rho,
// rho the low-passed |du/dt|. That is the Preisach model fed through one play operator whose
// half-width is b rho:
//   v = max(u - b rho, min(u + b rho, v_prev)).
// At a reversal the rate passes through zero, so the loop's tips stay where the input turns
// (a delay would carry the output past them); along a branch the relays lag by b rho.
// Units: V, s. Real-time safe step()/reset().
#include <algorithm>

#include "hystbench/compensation/rate_estimator.hpp"

namespace hystbench::sim {

class RateWidenedPlay {
 public:
  /// widening_s: b, the half-width per unit of rate [s] (>= 0); filter_s: the rate's low-pass
  /// time constant [s] (>= 0, 0 = the per-sample difference); dt_s > 0. Throws
  /// std::invalid_argument naming the argument otherwise.
  RateWidenedPlay(double widening_s, double filter_s, double dt_s);

  /// The input u [V] at the next sample; returns what the relays see [V].
  double step(double u) noexcept {
    const double half_width = widening_s_ * rate_.step(u);
    out_ = std::max(u - half_width, std::min(u + half_width, out_));
    return out_;
  }
  /// At rest at u0 [V].
  void reset(double u0) noexcept {
    rate_.reset(u0);
    out_ = u0;
  }

 private:
  double widening_s_;
  compensation::RateEstimator rate_;
  double out_ = 0.0;
};

}  // namespace hystbench::sim
