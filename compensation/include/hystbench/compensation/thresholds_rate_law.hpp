#pragma once
// The thresholds rate law (Al Janaideh, Rakheja and Su's dynamic thresholds), as the
// rate-dependent PI (rate_dependent_pi_model.hpp) and the Preisach plane (preisach_model.hpp)
// carry it: where the input moves at rate |du/dt|, every threshold widens by
//   w(rate) = threshold_rate_s * rate                                   (exponent 1), or
//   w(rate) = threshold_rate_s * max_rate * (rate / max_rate)^exponent  (exponent p < 1),
// the rate low-passed with time constant rate_filter_s (RateEstimator) and capped at max_rate
// (when > 0). The loop's tips stay where the input reverses (the rate is 0 there). Real-time safe.
#include <cmath>

namespace hystbench::compensation {

/// The widening [input unit] at rate (>= 0, capped at max_rate > 0 when exponent < 1):
/// threshold_rate_s * rate, or threshold_rate_s * max_rate * (rate / max_rate)^exponent.
inline double threshold_widening(double threshold_rate_s, double exponent, double max_rate,
                                 double rate) noexcept {
  if (exponent == 1.0 || !(max_rate > 0.0) || threshold_rate_s == 0.0) {
    return threshold_rate_s * rate;
  }
  const double rho = std::abs(rate) / max_rate;
  return threshold_rate_s * max_rate * (exponent == 0.5 ? std::sqrt(rho) : std::pow(rho, exponent));
}

struct ThresholdsRateLaw {
  double threshold_rate_s = 0.0;  ///< widening per unit of rate [s], >= 0; 0 = no law
  double exponent = 1.0;          ///< the widening's power of the rate, in (0, 1]
  double max_rate = 0.0;          ///< the rate's cap [input unit / s], >= 0; 0 = none
  /// The identification record's largest smooth rate [input unit / s], >= 0 (0 = unknown).
  double record_max_rate = 0.0;
  double rate_filter_s = 0.0;  ///< the rate's low-pass time constant [s], >= 0

  bool active() const noexcept { return threshold_rate_s > 0.0; }
  /// The widening at |rate| [input unit], the rate capped at max_rate (when > 0).
  double widening(double rate) const noexcept {
    const double r = max_rate > 0.0 ? std::fmin(std::abs(rate), max_rate) : std::abs(rate);
    return threshold_widening(threshold_rate_s, exponent, max_rate, r);
  }
  bool operator==(const ThresholdsRateLaw&) const = default;
};

}  // namespace hystbench::compensation
