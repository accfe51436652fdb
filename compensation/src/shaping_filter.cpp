#include "hystbench/compensation/shaping_filter.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "details/validate.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::compensation {

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;

void require_section(double f_hz, double damping, double dt, const std::string& what) {
  details::require(std::isfinite(f_hz) && f_hz > 0.0 && f_hz < 0.5 / dt,
                   what + ".frequency_hz must be in (0, " + significant(0.5 / dt, 6) +
                       ") Hz (below the Nyquist frequency), got " + significant(f_hz, 6));
  details::require(std::isfinite(damping) && damping > 0.0 && damping <= 2.0,
                   what + ".damping must be in (0, 2], got " + significant(damping, 6));
}
}  // namespace

// H(s) = (n2 s^2 + n1 w0 s + n0 w0^2) / (s^2 + d1 w0 s + d0 w0^2), s = K (1 - 1/z) / (1 + 1/z),
// K = w0 / tan(w0 dt / 2): exact at w0.
ShapingFilter::Section ShapingFilter::bilinear(double w0, double dt, double n2, double n1,
                                               double n0, double d1, double d0) {
  const double k = w0 / std::tan(w0 * dt / 2.0);
  const double k2 = k * k, w2 = w0 * w0;
  const double a0 = k2 + d1 * w0 * k + d0 * w2;
  Section s;
  s.b0 = (n2 * k2 + n1 * w0 * k + n0 * w2) / a0;
  s.b1 = 2.0 * (n0 * w2 - n2 * k2) / a0;
  s.b2 = (n2 * k2 - n1 * w0 * k + n0 * w2) / a0;
  s.a1 = 2.0 * (d0 * w2 - k2) / a0;
  s.a2 = (k2 - d1 * w0 * k + d0 * w2) / a0;
  return s;
}

ShapingFilter::ShapingFilter(const ShapingFilterSpec& spec, double dt_s) : dt_(dt_s) {
  details::require(std::isfinite(dt_s) && dt_s > 0.0, "shaping filter: dt must be > 0");
  details::require(spec.notches.size() <= kMaxNotches,
                   "feedback.notches: at most " + std::to_string(kMaxNotches) + " notches, got " +
                       std::to_string(spec.notches.size()));
  for (std::size_t i = 0; i < spec.notches.size(); ++i) {
    const Notch& n = spec.notches[i];
    const std::string what = "feedback.notches[" + std::to_string(i) + "]";
    require_section(n.frequency_hz, n.damping, dt_s, what);
    details::require(std::isfinite(n.depth) && n.depth > 0.0 && n.depth <= 1.0,
                     what + ".depth must be in (0, 1], got " + significant(n.depth, 6));
    sections_[count_++] = bilinear(kTwoPi * n.frequency_hz, dt_s, 1.0, 2.0 * n.depth * n.damping,
                                   1.0, 2.0 * n.damping, 1.0);
  }
  if (spec.low_pass.frequency_hz > 0.0) {
    require_section(spec.low_pass.frequency_hz, spec.low_pass.damping, dt_s, "feedback.low_pass");
    sections_[count_++] = bilinear(kTwoPi * spec.low_pass.frequency_hz, dt_s, 0.0, 0.0, 1.0,
                                   2.0 * spec.low_pass.damping, 1.0);
  }
}

double ShapingFilter::step(double x) noexcept {
  for (std::size_t i = 0; i < count_; ++i) {
    Section& s = sections_[i];
    const double y = s.b0 * x + s.s1;
    s.s1 = s.b1 * x - s.a1 * y + s.s2;
    s.s2 = s.b2 * x - s.a2 * y;
    x = y;
  }
  return x;
}

void ShapingFilter::reset(double x0) noexcept {
  // Settled at x0: y = x = x0 with unit DC gain; s2 = (b2 - a2) x0, s1 = y - b0 x0.
  for (std::size_t i = 0; i < count_; ++i) {
    Section& s = sections_[i];
    s.s2 = (s.b2 - s.a2) * x0;
    s.s1 = x0 - s.b0 * x0;
  }
}

std::complex<double> ShapingFilter::response(double f_hz) const noexcept {
  return response_at(std::polar(1.0, -kTwoPi * f_hz * dt_));
}

std::complex<double> ShapingFilter::response_at(std::complex<double> zi) const noexcept {
  std::complex<double> h = 1.0;
  for (std::size_t i = 0; i < count_; ++i) {
    const Section& s = sections_[i];
    h *= (s.b0 + zi * (s.b1 + zi * s.b2)) / (1.0 + zi * (s.a1 + zi * s.a2));
  }
  return h;
}

}  // namespace hystbench::compensation
