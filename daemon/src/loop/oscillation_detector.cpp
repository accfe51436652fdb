#include "hystbench/daemon/loop/oscillation_detector.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace hystbench::daemon {

namespace {
constexpr double kPeriodsPerWindow = 8.0;
constexpr double kGrowth = 1.4;
constexpr int kGrowingWindows = 4;
constexpr double kSustainedFraction = 0.05;  // of the span
constexpr double kSustainedS = 0.02;
constexpr int kMinSustainedWindows = 5;
constexpr double kNoiseFactor = 10.0;
constexpr double kFloorFraction = 0.002;  // of the span
}  // namespace

OscillationDetector::OscillationDetector(OscillationOptions o) : o_(o) {
  o_.rate_hz = std::isfinite(o_.rate_hz) && o_.rate_hz > 0.0 ? o_.rate_hz : 10000.0;
  const double nyquist = o_.rate_hz / 2.0;
  o_.frequency_hz = std::isfinite(o_.frequency_hz) && o_.frequency_hz > 0.0
                        ? std::min(o_.frequency_hz, 0.9 * nyquist)
                        : 0.2 * o_.rate_hz;
  o_.span_um = std::isfinite(o_.span_um) && o_.span_um > 0.0 ? o_.span_um : 1.0;
  o_.noise_rms_um = std::isfinite(o_.noise_rms_um) && o_.noise_rms_um > 0.0 ? o_.noise_rms_um : 0.0;
  // A band-pass of Q 1 around f0 (bilinear, prewarped): H(s) = (w0 s) / (s^2 + w0 s + w0^2).
  const double w0 = 2.0 * std::numbers::pi * o_.frequency_hz;
  const double k = w0 / std::tan(w0 / (2.0 * o_.rate_hz));
  const double a0 = k * k + w0 * k + w0 * w0;
  b0_ = w0 * k / a0;
  b2_ = -b0_;
  a1_ = 2.0 * (w0 * w0 - k * k) / a0;
  a2_ = (k * k - w0 * k + w0 * w0) / a0;
  window_ = std::max<std::uint64_t>(
      16,
      static_cast<std::uint64_t>(std::lround(kPeriodsPerWindow * o_.rate_hz / o_.frequency_hz)));
  floor_ = std::max(kNoiseFactor * o_.noise_rms_um, kFloorFraction * o_.span_um);
  sustained_level_ = kSustainedFraction * o_.span_um;
  const double window_s = static_cast<double>(window_) / o_.rate_hz;
  sustained_needed_ =
      std::max(kMinSustainedWindows, static_cast<int>(std::ceil(kSustainedS / window_s)));
  trip_.frequency_hz = o_.frequency_hz;
  if (std::isfinite(o_.period_samples) && o_.period_samples >= 2.0 &&
      o_.period_samples <= kMaxPeriodTicks) {
    whole_ = static_cast<std::size_t>(std::floor(o_.period_samples));
    frac_ = o_.period_samples - std::floor(o_.period_samples);
    history_.assign(whole_ + 2, 0.0);
  } else {
    o_.period_samples = 0.0;
  }
}

double OscillationDetector::change_over_period(double e) noexcept {
  if (history_.empty()) return e;
  const std::size_t n = history_.size();
  // e(k - P), linear between e(k - whole) and e(k - whole - 1); before a whole period has
  // passed there is nothing to compare with and the error itself is watched.
  double change = e;
  if (seen_ > whole_) {
    const double a = history_[(head_ + n - whole_) % n];
    const double b = history_[(head_ + n - whole_ - 1) % n];
    change = e - ((1.0 - frac_) * a + frac_ * b);
  }
  history_[head_] = e;
  head_ = (head_ + 1) % n;
  ++seen_;
  return change;
}

bool OscillationDetector::update(double e, std::uint64_t k) noexcept {
  if (trip_.tripped) return true;
  if (!std::isfinite(e)) return false;
  const double x = change_over_period(e);
  const double y = b0_ * x + b2_ * x2_ - a1_ * y1_ - a2_ * y2_;
  x2_ = x1_;
  x1_ = x;
  y2_ = y1_;
  y1_ = y;
  sum2_ += y * y;
  if (++in_window_ < window_) return false;
  const double rms = std::sqrt(sum2_ / static_cast<double>(window_));
  sum2_ = 0.0;
  in_window_ = 0;
  growing_ = rms > floor_ && rms >= kGrowth * last_rms_ ? growing_ + 1 : 0;
  sustained_ = rms > sustained_level_ ? sustained_ + 1 : 0;
  last_rms_ = rms;
  if (growing_ >= kGrowingWindows || sustained_ >= sustained_needed_) {
    trip_.tripped = true;
    trip_.growing = growing_ >= kGrowingWindows;
    trip_.rms_um = rms;
    trip_.tick = k;
  }
  return trip_.tripped;
}

}  // namespace hystbench::daemon
