#pragma once
// Parameter validation helpers shared by the model constructors. Throw std::invalid_argument
// with a message that names the offending field and index.
#include <cmath>
#include <cstdio>
#include <span>
#include <stdexcept>
#include <string>

namespace hystbench::compensation::details {

inline void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

/// A value for a message: 6 significant digits.
inline std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// The messages are built only on failure: these run over whole data columns.
inline void require_finite(std::span<const double> v, const std::string& field) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throw std::invalid_argument(field + "[" + std::to_string(i) + "] is not a finite number (" +
                                  fmt(v[i]) + ")");
    }
  }
}

inline void require_finite(double v, const std::string& field) {
  require(std::isfinite(v), field + " is not a finite number");
}

inline void require_strictly_increasing(std::span<const double> v, const std::string& field) {
  for (std::size_t i = 1; i < v.size(); ++i) {
    if (!(v[i] > v[i - 1])) {
      throw std::invalid_argument(field + " must be strictly increasing: " + field + "[" +
                                  std::to_string(i) + "] = " + std::to_string(v[i]) +
                                  " <= " + field + "[" + std::to_string(i - 1) +
                                  "] = " + std::to_string(v[i - 1]));
    }
  }
}

inline void require_same_size(std::size_t a, std::size_t b, const std::string& fa,
                              const std::string& fb) {
  require(a == b, fa + " and " + fb + " must have the same length (" + std::to_string(a) + " vs " +
                      std::to_string(b) + ")");
}

}  // namespace hystbench::compensation::details
