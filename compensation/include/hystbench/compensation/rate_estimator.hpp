#pragma once
// The input rate the rate-dependent models see: the per-sample derivative (u(k) - u(k-1)) / dt
// through a first-order low-pass of time constant tau, v(k) = v(k-1) + a (du/dt - v(k-1)),
// a = 1 - exp(-dt / tau); rate = v (RateLaw::kSigned, the rate-dependent paper's eq. 16) or |v|
// (RateLaw::kMagnitude). tau = 0 is the bare per-sample difference.
// Filtering keeps a quantised or noisy input, and the one-sample spike of an input step, from
// reading as a huge rate; for a smooth input the rate lags by about tau.
// Units: u in the input unit, rate in input unit / s, tau and dt in s.
// step()/peek()/reset() are real-time safe.
#include <cmath>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace hystbench::compensation {

/// Which rate a rate-dependent law sees. kSigned: du/dt as the rate-dependent paper's eq. 16
/// writes it, so the weights fall as they rose when the input reverses and the output stays
/// smooth through a reversal. kMagnitude: |du/dt|, the same weights on both branches; the
/// output then has a corner at every reversal (models saved before the law was a choice).
/// kThresholds: |du/dt| widens every play's threshold instead of changing its weight (Al
/// Janaideh, Rakheja and Su's dynamic thresholds); the weights are rate-free.
enum class RateLaw { kMagnitude, kSigned, kThresholds };

/// "signed" / "magnitude" / "thresholds".
const char* to_string(RateLaw law) noexcept;
/// The law named "signed", "magnitude" or "thresholds"; nullopt for any other name.
std::optional<RateLaw> rate_law_from_string(std::string_view name) noexcept;

class RateEstimator {
 public:
  RateEstimator() = default;
  /// tau_s >= 0, dt_s > 0 (not checked here: the owning model validates them).
  RateEstimator(double tau_s, double dt_s, RateLaw law = RateLaw::kMagnitude) {
    configure(tau_s, dt_s, law);
  }

  void configure(double tau_s, double dt_s, RateLaw law = RateLaw::kMagnitude) noexcept {
    dt_ = dt_s;
    a_ = tau_s > 0.0 ? 1.0 - std::exp(-dt_s / tau_s) : 1.0;
    law_ = law;
  }
  /// Rate after input u, without changing the state [input unit / s; >= 0 for kMagnitude].
  double peek(double u) const noexcept { return of(next(u)); }
  /// Advances one sample with input u; returns the rate.
  double step(double u) noexcept {
    v_ = next(u);
    u_prev_ = u;
    return of(v_);
  }
  /// At rest at input u0.
  void reset(double u0) noexcept {
    u_prev_ = u0;
    v_ = 0.0;
  }
  /// Rate after the last step() [input unit / s; >= 0 for kMagnitude].
  double value() const noexcept { return of(v_); }
  /// The low-pass coefficient a (1: the bare per-sample difference).
  double coefficient() const noexcept { return a_; }
  RateLaw law() const noexcept { return law_; }

 private:
  double next(double u) const noexcept { return v_ + a_ * ((u - u_prev_) / dt_ - v_); }
  double of(double v) const noexcept { return law_ == RateLaw::kSigned ? v : std::abs(v); }

  double dt_ = 1e-3;
  double a_ = 1.0;
  double u_prev_ = 0.0;
  double v_ = 0.0;
  RateLaw law_ = RateLaw::kMagnitude;
};

/// The rate of every sample of u (first sample 0), as a RateEstimator started at rest at u[0].
std::vector<double> estimate_rates(std::span<const double> u, double dt_s, double tau_s,
                                   RateLaw law = RateLaw::kMagnitude);

/// The largest per-sample rate |du/dt| of the smooth parts of u [input unit / s]: a sample
/// counts when its rate is at most twice the smallest of the 5 centred on it, so a step, which
/// moves the input in one or two samples, does not; a smooth peak does. 0 for fewer than 6
/// samples or a constant input.
double smooth_max_rate(std::span<const double> u, double dt_s);

}  // namespace hystbench::compensation
