#include "hystbench/compensation/feedback_controller.hpp"

#include <cmath>
#include <numbers>

#include "details/validate.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::compensation {

FeedbackController::FeedbackController(const FeedbackLaw& law, double dt_s)
    : law_(law),
      dt_(dt_s),
      pid_(law.pid, dt_s),
      shaping_(law.shaping, dt_s),
      resonators_(law.harmonics, dt_s) {
  const LowFrequencyBoost& b = law.boost;
  if (b.frequency_hz > 0.0) {
    details::require(std::isfinite(b.frequency_hz) && b.frequency_hz < 0.5 / dt_s,
                     "feedback.boost.frequency_hz must be below the Nyquist frequency, got " +
                         significant(b.frequency_hz, 6));
    details::require(std::isfinite(b.gain) && b.gain > 1.0,
                     "feedback.boost.gain must be > 1, got " + significant(b.gain, 6));
    // (s + w) / (s + w / g), s = K (1 - 1/z) / (1 + 1/z), K = w / tan(w dt / 2).
    const double w = 2.0 * std::numbers::pi * b.frequency_hz;
    const double k = w / std::tan(w * dt_s / 2.0), wp = w / b.gain;
    b0_ = (k + w) / (k + wp);
    b1_ = (w - k) / (k + wp);
    a1_ = (wp - k) / (k + wp);
  }
}

double FeedbackController::step(double error) noexcept {
  if (!std::isfinite(error)) return out_;
  const double boosted = b0_ * error + b1_ * x1_ - a1_ * y1_;
  x1_ = error;
  y1_ = boosted;
  out_ = shaping_.step(pid_.step(boosted)) + resonators_.step(error);
  return out_;
}

void FeedbackController::reset() noexcept {
  pid_.reset(0.0);
  shaping_.reset(0.0);
  resonators_.reset();
  x1_ = y1_ = 0.0;
  out_ = 0.0;
}

std::complex<double> FeedbackController::response(double f_hz) const noexcept {
  return response_at(std::polar(1.0, -2.0 * std::numbers::pi * f_hz * dt_));
}

std::complex<double> FeedbackController::response_at(std::complex<double> zi) const noexcept {
  const std::complex<double> boost = (b0_ + b1_ * zi) / (1.0 + a1_ * zi);
  return boost * pid_.response_at(zi) * shaping_.response_at(zi) + resonators_.response_at(zi);
}

}  // namespace hystbench::compensation
