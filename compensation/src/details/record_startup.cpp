#include "details/record_startup.hpp"

#include <algorithm>

namespace hystbench::compensation::details {

std::size_t startup_samples(std::span<const double> u, std::size_t max_samples) {
  if (u.empty()) return 0;
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  const double band = 0.005 * (*hi - *lo);
  bool low = false, high = false;
  for (std::size_t k = 0; k < u.size() && k < max_samples; ++k) {
    low = low || u[k] <= *lo + band;
    high = high || u[k] >= *hi - band;
    if (low && high) return k;
  }
  return std::min(max_samples, u.size());
}

}  // namespace hystbench::compensation::details
