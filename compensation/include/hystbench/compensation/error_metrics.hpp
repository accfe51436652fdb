#pragma once
// Error statistics between a measurement and a prediction, in output units and % of range.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <span>

namespace hystbench::compensation {

/// `value` as a share of a span: 100 x value / range [%], 0 where the range is not positive (a
/// run or a record that did not move). Real-time safe.
inline double percent_of_range(double value, double range) noexcept {
  return range > 0.0 ? 100.0 * value / range : 0.0;
}

struct ErrorStats {
  double rmse = 0.0;     ///< root mean square error [output unit]
  double max_abs = 0.0;  ///< largest absolute error [output unit]
  double range = 0.0;    ///< max(measured) - min(measured) [output unit]
  std::size_t samples = 0;
  double rmse_percent() const noexcept { return percent_of_range(rmse, range); }
  double max_percent() const noexcept { return percent_of_range(max_abs, range); }
};

/// Statistics of measured - predicted over equal-length spans (the shorter length is used).
ErrorStats error_stats(std::span<const double> measured, std::span<const double> predicted);

/// {"rmse", "max_abs", "range", "rmse_percent", "max_percent", "samples"}, as fit results,
/// model files and the CLI report them.
nlohmann::json to_json(const ErrorStats& s);

}  // namespace hystbench::compensation
