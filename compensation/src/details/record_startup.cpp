#include "details/record_startup.hpp"

#include <algorithm>

namespace hystbench::compensation::details {

std::size_t startup_samples(std::span<const double> u, std::size_t max_samples, std::size_t end) {
  const std::span<const double> part = u.first(end == 0 ? u.size() : std::min(end, u.size()));
  if (part.empty()) return 0;
  const auto [lo, hi] = std::minmax_element(part.begin(), part.end());
  const double band = 0.005 * (*hi - *lo);
  bool low = false, high = false;
  for (std::size_t k = 0; k < part.size() && k < max_samples; ++k) {
    low = low || part[k] <= *lo + band;
    high = high || part[k] >= *hi - band;
    if (low && high) return k;
  }
  return std::min(max_samples, part.size());
}

}  // namespace hystbench::compensation::details
