#pragma once
// Checking a configuration's fields: each throws std::invalid_argument("<field>: <what>"), the
// field named as the user wrote it ("actuator.creep.tau_s"). Not real-time (allocates, throws).
#include <cmath>
#include <stdexcept>
#include <string>

namespace hystbench::sim::details {

[[noreturn]] inline void fail(const std::string& field, const std::string& what) {
  throw std::invalid_argument(field + ": " + what);
}

inline void require(bool ok, const std::string& field, const std::string& what) {
  if (!ok) fail(field, what);
}

inline void require_positive(double value, const std::string& field) {
  require(std::isfinite(value) && value > 0.0, field, "must be > 0");
}

}  // namespace hystbench::sim::details
