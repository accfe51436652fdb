#include "hystbench/compensation/pid_controller.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "details/validate.hpp"

namespace hystbench::compensation {

PidController::PidController(PidParameters p, double dt_s) : p_(p), dt_(dt_s) {
  details::require_finite(p_.kp, "pid.kp");
  details::require_finite(p_.ki, "pid.ki");
  details::require_finite(p_.kd, "pid.kd");
  details::require(std::isfinite(p_.derivative_filter_hz) && p_.derivative_filter_hz >= 0.0,
                   "pid.derivative_filter_hz must be >= 0");
  details::require(
      !std::isnan(p_.output_min) && !std::isnan(p_.output_max) && p_.output_min <= p_.output_max,
      "pid.output_min must be <= pid.output_max");
  details::require(std::isfinite(dt_s) && dt_s > 0.0, "sample period must be > 0");
  details::require(std::isfinite(p_.output_filter_hz) && p_.output_filter_hz >= 0.0 &&
                       p_.output_filter_hz < 0.5 / dt_s,
                   "pid.output_filter_hz must be >= 0 and below the Nyquist frequency");
  if (p_.output_filter_hz > 0.0) {
    beta_ = 1.0 - std::exp(-2.0 * std::numbers::pi * p_.output_filter_hz * dt_);
  }
  if (p_.derivative_filter_hz > 0.0) {
    const double tau = 1.0 / (2.0 * std::numbers::pi * p_.derivative_filter_hz);
    alpha_ = dt_ / (tau + dt_);
  }
}

double PidController::step(double error) noexcept {
  // hold on a bad measurement; the loop faults on it
  if (!std::isfinite(error)) return out_;
  ef_ = samples_ == 0 ? error : ef_ + alpha_ * (error - ef_);
  if (samples_ == 0) {
    e1_ = error;
    ef1_ = ef2_ = ef_;
  }
  const double dp = p_.kp * (error - e1_);
  double di = p_.ki * dt_ * error;
  const double dd = p_.kd / dt_ * (ef_ - 2.0 * ef1_ + ef2_);
  const bool high = u_ >= p_.output_max || external_saturation_ > 0;
  const bool low = u_ <= p_.output_min || external_saturation_ < 0;
  if ((high && di > 0.0) || (low && di < 0.0)) di = 0.0;  // anti-windup
  u_ = std::clamp(u_ + dp + di + dd, p_.output_min, p_.output_max);
  e1_ = error;
  ef2_ = ef1_;
  ef1_ = ef_;
  ++samples_;
  out_ += beta_ * (u_ - out_);
  return out_;
}

void PidController::reset(double initial_output) noexcept {
  u_ = std::clamp(initial_output, p_.output_min, p_.output_max);
  out_ = u_;
  e1_ = ef_ = ef1_ = ef2_ = 0.0;
  external_saturation_ = 0;
  samples_ = 0;
}

std::complex<double> PidController::response(double f_hz) const noexcept {
  return response_at(std::polar(1.0, -2.0 * std::numbers::pi * f_hz * dt_));
}

std::complex<double> PidController::response_at(std::complex<double> zi) const noexcept {
  const std::complex<double> diff = 1.0 - zi;
  // u = kp e + ki dt e / (1 - 1/z) + kd / dt (1 - 1/z) ef, ef = alpha e / (1 - (1 - alpha) / z),
  // then the output low-pass beta / (1 - (1 - beta) / z).
  const std::complex<double> ef = alpha_ / (1.0 - (1.0 - alpha_) * zi);
  const std::complex<double> u = p_.kp + p_.ki * dt_ / diff + p_.kd / dt_ * diff * ef;
  return u * beta_ / (1.0 - (1.0 - beta_) * zi);
}

}  // namespace hystbench::compensation
