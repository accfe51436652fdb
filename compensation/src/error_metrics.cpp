#include "hystbench/compensation/error_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hystbench::compensation {

ErrorStats error_stats(std::span<const double> measured, std::span<const double> predicted) {
  ErrorStats s;
  const std::size_t n = std::min(measured.size(), predicted.size());
  s.samples = n;
  if (n == 0) return s;
  double sum2 = 0.0;
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (std::size_t k = 0; k < n; ++k) {
    const double e = measured[k] - predicted[k];
    sum2 += e * e;
    s.max_abs = std::max(s.max_abs, std::abs(e));
    lo = std::min(lo, measured[k]);
    hi = std::max(hi, measured[k]);
  }
  s.rmse = std::sqrt(sum2 / static_cast<double>(n));
  s.range = hi - lo;
  return s;
}

nlohmann::json to_json(const ErrorStats& s) {
  return {{"rmse", s.rmse},
          {"max_abs", s.max_abs},
          {"range", s.range},
          {"rmse_percent", s.rmse_percent()},
          {"max_percent", s.max_percent()},
          {"samples", s.samples}};
}

}  // namespace hystbench::compensation
