#pragma once
// Rate-dependent modified PI, two laws of the input rate:
// - weights (rate-dependent paper, eq. 15-21): the cumulative play weights are linear in the
//   rate, W_i(rate) = W^_i + c_i * rate [input unit / s]; w_i(rate) = W_i(rate) - W_{i-1}(rate).
//   The rate is du/dt (RateLaw::kSigned, eq. 16) or |du/dt| (kMagnitude).
// - thresholds (RateLaw::kThresholds, Al Janaideh, Rakheja and Su's dynamic thresholds): every
//   play's threshold widens with |du/dt|, r_i(rate) = r_i + threshold_rate_s * rate for
//   r_i > 0 (the r_0 = 0 play is the paper's linear term p_0 u and stays one); the weights are
//   rate-free. The loop's tips stay where the input reverses (the rate is 0 there),
//   where a delay would carry the output past them. With an exponent p < 1 the widening grows
//   as a power of the rate, threshold_rate_s * max_rate * (rate / max_rate)^p (the same at
//   max_rate): a loop whose width grows with the square root of the rate (p = 1/2) as the
//   domain walls of a piezoceramic move with the field's overdrive.
// The rate is capped at max_rate (when > 0) and low-passed with time constant rate_filter_s
// (RateEstimator; 0 = the per-sample difference (u(k) - u(k-1)) / dt, the paper's form).
// Dead zones are rate-independent.
// Needs set_sample_period(). Real-time safe step()/peek()/peek_at_rate().
#include <cmath>
#include <optional>
#include <span>
#include <vector>

#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/rate_estimator.hpp"
#include "hystbench/compensation/thresholds_rate_law.hpp"

namespace hystbench::compensation {

struct RateDependentPiParameters {
  ModifiedPiParameters base;              ///< weights at rate 0 (W^ via cumulative sums)
  std::vector<double> rate_coefficients;  ///< c_i, one per play [output/input per (input/s)]
  double max_rate = 0.0;  ///< largest |rate| of the identification record's smooth parts; the
                          ///< rate is capped there and invertibility is checked on [0, max_rate]
                          ///< [input unit / s]
  double rate_filter_s = 0.0;  ///< time constant of the rate's low-pass [s], >= 0
  /// The largest rate of the identification record's smooth parts [input unit / s], >= 0; 0 =
  /// unknown (taken as max_rate). Above max_rate: the record showed the law level off at
  /// max_rate (a saturation); equal: max_rate is only where the record ended (an extrapolation
  /// guard).
  double record_max_rate = 0.0;
  /// du/dt or |du/dt| on the weights, or |du/dt| on the thresholds. Model files without the
  /// key are kMagnitude.
  RateLaw rate_law = RateLaw::kMagnitude;
  /// kThresholds: how far every play's threshold widens per unit of rate [s] (input unit per
  /// input unit / s), >= 0; the rate coefficients are then all 0. Other laws: 0. With an
  /// exponent below 1: the widening at max_rate divided by max_rate.
  double threshold_rate_s = 0.0;
  /// kThresholds: p of the widening's power of the rate, in (0, 1]; 1 = linear in the rate.
  /// Below 1 needs max_rate > 0. Other laws: 1. Model files without the key are 1.
  double threshold_rate_exponent = 1.0;
};

class RateDependentPiModel final : public HysteresisModel {
 public:
  explicit RateDependentPiModel(RateDependentPiParameters p, double dt_s = 1e-3);

  ModelKind kind() const noexcept override { return ModelKind::kRateDependentPi; }
  double step(double u) noexcept override;
  double peek(double u) const noexcept override;
  double peek_at_rate(double u, double rate) const noexcept override;
  /// Exact for the weight laws: the output is S[a(u) + b(u) rate], so rate = (S^-1[y] - a) / b
  /// (before the cap; kMagnitude: 0 where that is negative). kThresholds: NaN (not linear).
  double rate_for_output(double u, double y) const noexcept override;
  void reset(double u0) noexcept override;
  void set_sample_period(double dt_s) override;
  std::size_t operator_count() const noexcept override;
  /// The thresholds law's numbers; nullopt for the weight laws.
  std::optional<ThresholdsRateLaw> thresholds_law() const override;
  /// The modified PI of its weights at rate 0 (base).
  std::unique_ptr<HysteresisModel> rate_free_part() const override;
  Invertibility invertibility() const override;
  std::unique_ptr<HysteresisModel> clone() const override;

  const RateDependentPiParameters& parameters() const noexcept { return p_; }
  double sample_period() const noexcept { return dt_; }
  /// Per play, how its weight grows with the rate: c_i - c_{i-1} [output/input per (input/s)].
  std::span<const double> rate_slopes() const noexcept { return dw_; }
  /// True when the law changes nothing with the rate: every rate coefficient and the threshold
  /// widening are 0 (a modified PI written as a rate-dependent one).
  bool rate_free() const noexcept;
  /// The signed law with every play's weight growing with the rate: the output grows with the
  /// input and with its own rate on both branches, so each tick inverts exactly at the drive's
  /// own rate (no right-half-plane zero, nothing to plan).
  bool grows_with_signed_rate() const noexcept;

 private:
  /// Output for input u at the given rate; writes the new play outputs to state_out when it is
  /// not null.
  double evaluate(double u, double rate, double* state_out) const noexcept;
  double capped(double rate) const noexcept;

  RateDependentPiParameters p_;
  PiModel pi_;  // plays and their state; weights taken from p_ per rate
  DeadZoneSuperposition dz_;
  std::optional<DeadZoneSuperposition>
      dz_inverse_;          // absent when the dead zones are not invertible
  std::vector<double> dw_;  // c_i - c_{i-1}: per-weight rate slope
  double dt_ = 1e-3;
  RateEstimator rate_;
};

}  // namespace hystbench::compensation
