#include "hystbench/compensation/pid_tuning.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "details/validate.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"

namespace hystbench::compensation {

namespace {

constexpr double kDefaultBandwidthFraction = 1.0 / 500.0;  // of the loop rate
constexpr double kMaxDefaultBandwidthHz = 2.0;
constexpr double kDynamicsMargin = 20.0;         // f_c at most f_n / 20
constexpr double kOutputFilterFactor = 100.0;    // f_lp = 100 f_c (rate-free model)
constexpr double kRateOutputFilterFactor = 4.0;  // f_lp = 4 f_c (rate-dependent model)
constexpr double kLoopDelayPeriods = 1.5;        // write-to-read delay plus the zero-order hold
constexpr double kRateLoopFraction = 0.25;       // of 1 / delay
constexpr double kRateZeroMargin = 14.0;         // 2 pi f_c at most (g / K_r) / 14
constexpr double kPeriodAverageMargin = 10.0;    // f_c at most f_0 / 10 behind the period average

// Largest change of output per unit of input rate [µm per V/s] of a rate-dependent model; with
// `lowering` only the part that lowers the output as the drive rises (a right-half-plane zero):
// with |du/dt| every slope does on the falling branch, with the signed rate the negative ones.
double rate_gain(const ActuatorModel& model, bool lowering = false) {
  if (model.hysteresis().kind() != ModelKind::kRateDependentPi) return 0.0;
  const auto& p = static_cast<const RateDependentPiModel&>(model.hysteresis()).parameters();
  const bool only_negative = lowering && p.rate_law == RateLaw::kSigned;
  const double u_abs = std::max(std::abs(model.input_min), std::abs(model.input_max));
  double sum = 0.0, prev = 0.0;
  for (const double c : p.rate_coefficients) {
    sum += only_negative ? std::max(prev - c, 0.0) : std::abs(c - prev);
    prev = c;
  }
  return sum * u_abs;
}

bool signed_law(const ActuatorModel& model) {
  return model.hysteresis().kind() == ModelKind::kRateDependentPi &&
         static_cast<const RateDependentPiModel&>(model.hysteresis()).parameters().rate_law ==
             RateLaw::kSigned;
}

}  // namespace

PidTuning tune_pid(double gain_um_per_v, double loop_rate_hz, double bandwidth_hz,
                   const ActuatorModel* model, double reference_hz, FeedforwardKind feedforward) {
  details::require(std::isfinite(gain_um_per_v) && gain_um_per_v > 0.0,
                   "PID tuning needs the actuator's gain > 0 [um/V]");
  details::require(std::isfinite(loop_rate_hz) && loop_rate_hz > 0.0,
                   "PID tuning needs the loop rate > 0");
  PidTuning t;
  double fc = bandwidth_hz > 0.0
                  ? bandwidth_hz
                  : std::min(loop_rate_hz * kDefaultBandwidthFraction, kMaxDefaultBandwidthHz);
  t.basis = "integral only, crossover " + details::fmt(fc) + " Hz" +
            (bandwidth_hz > 0.0 ? " (pid.bandwidth_hz)" : " (loop rate / 500, at most 2 Hz)");
  if (model != nullptr && model->dynamics()) {
    const double limit = model->dynamics()->natural_frequency_hz / kDynamicsMargin;
    if (fc > limit) {
      fc = limit;
      t.basis += ", lowered to " + details::fmt(fc) + " Hz for the model's resonance";
    }
  }
  const double kr = model != nullptr ? rate_gain(*model) : 0.0;
  const double two_pi = 2.0 * std::numbers::pi;
  // The rate law's loop gain grows with frequency (K_i K_r at most): the output low-pass caps it
  // for |du/dt|, whose falling branch rang without it. For the signed law the feedback holds the
  // reading to the feedforward's predicted output (the bench), and a low-pass close above the
  // crossover would only add its lag to the sensitivity a few times above the crossover.
  const bool signed_rate = kr > 0.0 && signed_law(*model);
  const double filter_factor =
      kr > 0.0 && !signed_rate ? kRateOutputFilterFactor : kOutputFilterFactor;
  // Falling, a faster fall raises the output (|du/dt|): to a small change of the drive the
  // actuator is g - K_r s, a zero in the right half plane at g / K_r [rad/s]. The integral loop
  // crosses over well below it, or it rings on every falling branch (a limit cycle a little
  // below the zero). The signed law has that zero only where its weights fall with the rate; where
  // they grow, g + K_r s, the rate-dependent feedforward already tracks above g / K_r / 14 to
  // the model's accuracy, and an integral loop crossing over there only adds its sensitivity
  // peak to that residual: the
  // same limit keeps the feedback on the slow errors the model does not predict.
  const double kz = model != nullptr ? rate_gain(*model, true) : 0.0;
  const double k_limit = kz > 0.0 ? kz : kr;
  const double zero_limit =
      k_limit > 0.0 ? gain_um_per_v / k_limit / (two_pi * kRateZeroMargin) : 0.0;
  if (k_limit > 0.0 && fc > zero_limit) {
    fc = zero_limit;
    t.basis += ", lowered to " + details::fmt(fc) + " Hz for the model's rate dependence (" +
               (kz > 0.0 ? "the right-half-plane zero its rate law puts on the drive at "
                         : "the rate-dependent feedforward's band, from ") +
               details::fmt(gain_um_per_v / k_limit / two_pi) + " Hz)";
  }
  const double hf_limit = kRateLoopFraction * loop_rate_hz / kLoopDelayPeriods;  // [rad/s]
  auto hf_gain = [&](double f) {
    return two_pi * f / gain_um_per_v * two_pi * filter_factor * f * kr;
  };
  if (kr > 0.0 && hf_gain(fc) > hf_limit) {
    fc = std::sqrt(hf_limit / hf_gain(1.0));
    t.basis += ", lowered to " + details::fmt(fc) + " Hz for the model's rate loop gain";
  }
  const bool behind_inverse = feedforward == FeedforwardKind::kModelInverse;
  if (std::isfinite(reference_hz) && reference_hz > (behind_inverse ? fc / 2.0 : fc)) {
    t.error_period_s = 1.0 / reference_hz;
    t.basis += "; the error averaged over the reference's period (" + details::fmt(reference_hz) +
               (behind_inverse ? " Hz is above half the crossover" : " Hz is above the crossover") +
               ": what repeats with it the integrator could only raise)";
    if (fc > reference_hz / kPeriodAverageMargin) {
      fc = reference_hz / kPeriodAverageMargin;
      t.basis += ", crossover lowered to " + details::fmt(fc) + " Hz for the average's delay";
    }
  }
  t.bandwidth_hz = fc;
  t.ki = two_pi * fc / gain_um_per_v;
  t.output_filter_hz = std::min(filter_factor * fc, 0.45 * loop_rate_hz);
  t.basis += "; output low-pass " + details::fmt(t.output_filter_hz) + " Hz";
  return t;
}

}  // namespace hystbench::compensation
