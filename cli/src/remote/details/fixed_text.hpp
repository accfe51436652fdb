#pragma once
// Numbers in the bench commands' reports: a fixed count of decimals (the library's one rule,
// hystbench/compensation/number_text.hpp), "-" where the daemon's result holds none. Not
// real-time.
#include <nlohmann/json.hpp>
#include <string>

#include "hystbench/compensation/number_text.hpp"

namespace hystbench::cli::details {

using compensation::fixed;

/// A number with `digits` decimals, "-" for null.
inline std::string fixed_or_dash(const nlohmann::json& v, int digits) {
  return v.is_number() ? fixed(v.get<double>(), digits) : "-";
}

}  // namespace hystbench::cli::details
