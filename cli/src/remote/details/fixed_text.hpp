#pragma once
// Numbers in the bench commands' reports: a fixed count of decimals, "-" where the daemon's
// result holds none. Not real-time.
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace hystbench::cli::details {

/// `v` with `digits` decimals.
inline std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

/// A number with `digits` decimals, "-" for null.
inline std::string fixed_or_dash(const nlohmann::json& v, int digits) {
  return v.is_number() ? fixed(v.get<double>(), digits) : "-";
}

}  // namespace hystbench::cli::details
