#pragma once
// One-sided dead-zone operators and their weighted superposition (Kuhnen's saturation operator).
//   S_d[v] = max(v - d, 0) for d > 0;  v for d = 0;  min(v - d, 0) for d < 0.
//   S[v]   = sum_j ws_j * S_{d_j}[v]   over 2m+1 thresholds d_{-m} < ... < d_0 = 0 < ... < d_m.
// Memory-free. apply()/inverse evaluation are real-time safe (no allocation, no exceptions).
#include <cstddef>
#include <span>
#include <vector>

#include "hystbench/compensation/invertibility.hpp"

namespace hystbench::compensation {

/// One-sided dead-zone operator S_d[v] (see above).
inline double dead_zone(double v, double d) noexcept {
  if (d > 0.0) return v > d ? v - d : 0.0;
  if (d < 0.0) return v < d ? v - d : 0.0;
  return v;
}

/// 2m+1 thresholds spread evenly on both sides of 0 (the constrained-identification choice):
/// d_{+-j} = +-j/(m+1) * above or below, j = 1..m, d_0 = 0, ascending. above, below >= 0.
std::vector<double> uniform_dead_zone_thresholds(std::size_t m, double below, double above);

struct DeadZoneParameters {
  std::vector<double> thresholds;  ///< strictly increasing, contains exactly one 0
  std::vector<double> weights;     ///< same length
};

class DeadZoneSuperposition {
 public:
  /// Identity (a single operator at d = 0 with weight 1).
  DeadZoneSuperposition();
  /// Throws std::invalid_argument naming the field on bad sizes, NaN, order or missing zero.
  explicit DeadZoneSuperposition(DeadZoneParameters p);

  double apply(double v) const noexcept;
  /// dS/dv at v: w_0 plus the weights of the operators past their threshold (v on a threshold
  /// counts as not past it, as apply() does).
  double slope(double v) const noexcept;
  /// Cumulative weights must be > 0 outward from d = 0 on both sides.
  Invertibility invertibility() const;
  /// The analytic inverse (Kuhnen; rate-dependent paper eq. 14, extended to d < 0).
  /// Throws NotInvertibleError when invertibility() fails.
  DeadZoneSuperposition inverse() const;

  const DeadZoneParameters& parameters() const noexcept { return p_; }
  std::size_t zero_index() const noexcept { return zero_; }
  std::size_t size() const noexcept { return p_.thresholds.size(); }

 private:
  DeadZoneParameters p_;
  std::size_t zero_ = 0;
  // Split by side so apply() is branch-free: d > 0 (increasing) and d < 0 (decreasing).
  std::vector<double> pos_d_, pos_w_, neg_d_, neg_w_;
  double w0_ = 1.0;
};

}  // namespace hystbench::compensation
