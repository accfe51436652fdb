#pragma once
// Parameter validation helpers shared by the model constructors. Throw std::invalid_argument
// with a message that names the offending field and index.
#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>
#include <string>

#include "hystbench/compensation/number_text.hpp"

namespace hystbench::compensation::details {

inline void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

/// significant(v, 6), by the name identification.cpp and details/diagnosis_record.cpp call it.
inline std::string fmt(double v) { return significant(v, 6); }

// The messages are built only on failure: these run over whole data columns.
inline void require_finite(std::span<const double> v, const std::string& field) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throw std::invalid_argument(field + "[" + std::to_string(i) + "] is not a finite number (" +
                                  significant(v[i], 6) + ")");
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

/// A measured record for identification or diagnosis: t, u, y finite, t strictly increasing,
/// u not constant (lengths are the caller's to check first).
inline void require_record(std::span<const double> t, std::span<const double> u,
                           std::span<const double> y) {
  require_finite(t, "t");
  require_finite(u, "u");
  require_finite(y, "y");
  for (std::size_t k = 1; k < t.size(); ++k) {
    if (!(t[k] > t[k - 1])) {
      throw std::invalid_argument("t must be strictly increasing: t[" + std::to_string(k) +
                                  "] = " + significant(t[k], 6) + " <= t[" + std::to_string(k - 1) +
                                  "] = " + significant(t[k - 1], 6));
    }
  }
  double lo = u.empty() ? 0.0 : u[0], hi = lo;
  for (const double v : u) lo = std::min(lo, v), hi = std::max(hi, v);
  require(hi > lo, "input u is constant (" + significant(lo, 6) +
                       "): a constant input does not excite any hysteresis");
}

inline void require_same_size(std::size_t a, std::size_t b, const std::string& fa,
                              const std::string& fb) {
  require(a == b, fa + " and " + fb + " must have the same length (" + std::to_string(a) + " vs " +
                      std::to_string(b) + ")");
}

}  // namespace hystbench::compensation::details
