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
constexpr double kDynamicsMargin = 20.0;          // f_c at most f_n / 20
constexpr double kOutputFilterFactor = 100.0;     // f_lp = 100 f_c (rate-free model)
constexpr double kRateOutputFilterFactor = 4.0;   // f_lp = 4 f_c (rate-dependent model)
constexpr double kLoopDelayPeriods = 1.5;         // write-to-read delay plus the zero-order hold
constexpr double kRateLoopFraction = 0.25;        // of 1 / delay
constexpr double kRateZeroMargin = 14.0;          // 2 pi f_c at most (g / K_r) / 14

// Largest change of output per unit of input rate [µm per V/s] of a rate-dependent model.
double rate_gain(const ActuatorModel& model) {
  if (model.hysteresis().kind() != ModelKind::kRateDependentPi) return 0.0;
  const auto& p = static_cast<const RateDependentPiModel&>(model.hysteresis()).parameters();
  const double u_abs = std::max(std::abs(model.input_min), std::abs(model.input_max));
  double sum = 0.0, prev = 0.0;
  for (const double c : p.rate_coefficients) {
    sum += std::abs(c - prev);
    prev = c;
  }
  return sum * u_abs;
}

}  // namespace

PidTuning tune_pid(double gain_um_per_v, double loop_rate_hz, double bandwidth_hz,
                   const ActuatorModel* model) {
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
  const double filter_factor = kr > 0.0 ? kRateOutputFilterFactor : kOutputFilterFactor;
  // Falling, a faster fall raises the output: to a small change of the drive the actuator is
  // g - K_r s, a zero in the right half plane at g / K_r [rad/s]. The integral loop crosses over
  // well below it, or it rings on every falling branch (a 35-40 Hz limit cycle on the loopback).
  const double zero_limit = kr > 0.0 ? gain_um_per_v / kr / (two_pi * kRateZeroMargin) : 0.0;
  if (kr > 0.0 && fc > zero_limit) {
    fc = zero_limit;
    t.basis += ", lowered to " + details::fmt(fc) + " Hz for the model's rate dependence (" +
               "right-half-plane zero of the falling branch at " +
               details::fmt(gain_um_per_v / kr / two_pi) + " Hz)";
  }
  const double hf_limit = kRateLoopFraction * loop_rate_hz / kLoopDelayPeriods;  // [rad/s]
  auto hf_gain = [&](double f) {
    return two_pi * f / gain_um_per_v * two_pi * filter_factor * f * kr;
  };
  if (kr > 0.0 && hf_gain(fc) > hf_limit) {
    fc = std::sqrt(hf_limit / hf_gain(1.0));
    t.basis += ", lowered to " + details::fmt(fc) + " Hz for the model's rate loop gain";
  }
  t.bandwidth_hz = fc;
  t.ki = two_pi * fc / gain_um_per_v;
  t.output_filter_hz = std::min(filter_factor * fc, 0.45 * loop_rate_hz);
  t.basis += "; output low-pass " + details::fmt(t.output_filter_hz) + " Hz";
  return t;
}

}  // namespace hystbench::compensation
