#pragma once
// Error statistics between a measurement and a prediction, in output units and % of range.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <span>

namespace hystbench::compensation {

struct ErrorStats {
  double rmse = 0.0;     ///< root mean square error [output unit]
  double max_abs = 0.0;  ///< largest absolute error [output unit]
  double range = 0.0;    ///< max(measured) - min(measured) [output unit]
  std::size_t samples = 0;
  double rmse_percent() const noexcept { return range > 0 ? 100.0 * rmse / range : 0.0; }
  double max_percent() const noexcept { return range > 0 ? 100.0 * max_abs / range : 0.0; }
};

/// Statistics of measured - predicted over equal-length spans (the shorter length is used).
ErrorStats error_stats(std::span<const double> measured, std::span<const double> predicted);

/// {"rmse", "max_abs", "range", "rmse_percent", "max_percent", "samples"}, as fit results,
/// model files and the CLI report them.
nlohmann::json to_json(const ErrorStats& s);

}  // namespace hystbench::compensation
