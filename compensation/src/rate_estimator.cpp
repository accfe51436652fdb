#include "hystbench/compensation/rate_estimator.hpp"

#include <algorithm>

namespace hystbench::compensation {

const char* to_string(RateLaw law) noexcept {
  switch (law) {
    case RateLaw::kSigned:
      return "signed";
    case RateLaw::kThresholds:
      return "thresholds";
    case RateLaw::kMagnitude:
      break;
  }
  return "magnitude";
}

std::optional<RateLaw> rate_law_from_string(std::string_view name) noexcept {
  for (const RateLaw law : {RateLaw::kSigned, RateLaw::kMagnitude, RateLaw::kThresholds}) {
    if (name == to_string(law)) return law;
  }
  return std::nullopt;
}

std::vector<double> estimate_rates(std::span<const double> u, double dt_s, double tau_s,
                                   RateLaw law) {
  std::vector<double> rate(u.size(), 0.0);
  if (u.empty()) return rate;
  RateEstimator e(tau_s, dt_s, law);
  e.reset(u[0]);
  for (std::size_t k = 1; k < u.size(); ++k) rate[k] = e.step(u[k]);
  return rate;
}

double smooth_max_rate(std::span<const double> u, double dt_s) {
  constexpr std::size_t kHalf = 2;
  constexpr double kConsistent = 2.0;
  if (u.size() < 2 * kHalf + 2) return 0.0;
  std::vector<double> d(u.size() - 1);
  for (std::size_t k = 0; k + 1 < u.size(); ++k) d[k] = std::abs(u[k + 1] - u[k]) / dt_s;
  double best = 0.0;
  for (std::size_t k = 0; k < d.size(); ++k) {
    const std::size_t lo = k >= kHalf ? k - kHalf : 0;
    const std::size_t hi = std::min(d.size(), k + kHalf + 1);
    const double local = *std::min_element(d.begin() + static_cast<std::ptrdiff_t>(lo),
                                           d.begin() + static_cast<std::ptrdiff_t>(hi));
    if (d[k] <= kConsistent * local) best = std::max(best, d[k]);
  }
  return best;
}

}  // namespace hystbench::compensation
