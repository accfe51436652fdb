#include "hystbench/compensation/moving_response.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <vector>

#include "details/validate.hpp"

namespace hystbench::compensation {

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

// The sine's phasor in x over one ramp (A - jB for A cos + B sin), a cubic taken out with it.
std::complex<double> phasor(std::span<const double> x, double w_per_sample) {
  const auto n = static_cast<Eigen::Index>(x.size());
  Eigen::MatrixXd a(n, 6);
  Eigen::VectorXd b(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double tau = (static_cast<double>(k) - 0.5 * static_cast<double>(n)) /
                       static_cast<double>(n);  // in [-0.5, 0.5): well conditioned
    a(k, 0) = 1.0;
    a(k, 1) = tau;
    a(k, 2) = tau * tau;
    a(k, 3) = tau * tau * tau;
    a(k, 4) = std::cos(w_per_sample * static_cast<double>(k));
    a(k, 5) = std::sin(w_per_sample * static_cast<double>(k));
    b(k) = x[static_cast<std::size_t>(k)];
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(b);
  return {c(4), -c(5)};
}

struct Direction {
  std::vector<std::complex<double>> responses;
  std::complex<double> mean() const {
    std::complex<double> m = 0.0;
    for (const auto& r : responses) m += r / static_cast<double>(responses.size());
    return m;
  }
  // The standard deviation of the mean's phase [rad], from the ramps' spread about it.
  double phase_noise() const {
    if (responses.size() < 2) return 0.0;
    const std::complex<double> m = mean();
    double var = 0.0;
    for (const auto& r : responses) var += std::pow(std::arg(r / m), 2);
    const auto count = static_cast<double>(responses.size());
    return std::sqrt(var / (count - 1.0) / count);
  }
};

}  // namespace

MovingResponse estimate_moving_response(std::span<const double> u, std::span<const double> y,
                                        std::span<const MovingRamp> ramps, double frequency_hz,
                                        double rate_hz, double min_lag_deg) {
  details::require(u.size() == y.size(), "moving response: u and y differ in length");
  details::require(std::isfinite(rate_hz) && rate_hz > 0.0,
                   "moving response: the rate must be > 0");
  details::require(
      std::isfinite(frequency_hz) && frequency_hz > 0.0 && frequency_hz < 0.5 * rate_hz,
      "moving response: the sine's frequency must be in (0, rate / 2)");
  details::require(std::isfinite(min_lag_deg) && min_lag_deg >= 0.0,
                   "moving response: min_lag_deg must be >= 0");
  const double w = 2.0 * std::numbers::pi * frequency_hz / rate_hz;
  const double cycle = rate_hz / frequency_hz;
  Direction up, down;
  for (std::size_t i = 0; i < ramps.size(); ++i) {
    const MovingRamp& r = ramps[i];
    const std::string which = "moving response: ramp " + std::to_string(i);
    details::require(r.first + r.length <= u.size(), which + " ends beyond the record");
    details::require(static_cast<double>(r.length) >= 2.0 * cycle,
                     which + " is shorter than two cycles of the sine");
    const auto ur = u.subspan(r.first, r.length), yr = y.subspan(r.first, r.length);
    details::require_finite(ur, "u");
    details::require_finite(yr, "y");
    const std::complex<double> pu = phasor(ur, w);
    details::require(std::abs(pu) > 1e-12, which + ": the input carries no sine");
    (r.rising ? up : down).responses.push_back(phasor(yr, w) / pu);
  }
  details::require(!up.responses.empty() && !down.responses.empty(),
                   "moving response: needs ramps of both directions");
  MovingResponse m;
  m.frequency_hz = frequency_hz;
  m.rising = up.mean();
  m.falling = down.mean();
  m.ramps = ramps.size();
  const double d = std::arg(m.falling / m.rising);  // < 0: the falling ramps lag
  m.lagging = d < 0.0 ? "falling" : "rising";
  m.lag_deg = std::abs(d) * kDeg;
  m.lag_noise_deg = std::hypot(up.phase_noise(), down.phase_noise()) * kDeg;
  if (m.lag_deg > std::max(3.0 * m.lag_noise_deg, min_lag_deg)) {
    m.zero_hz = frequency_hz / std::tan(0.5 * std::abs(d));
  }
  return m;
}

}  // namespace hystbench::compensation
