#pragma once
// Output limits enforced after every compensator: a voltage range and a slew rate.
// Violations are clamped and counted. apply() is real-time safe.
#include <algorithm>
#include <cmath>
#include <cstdint>

namespace hystbench::daemon {

struct OutputLimits {
  double u_min = 0.0;         ///< [V]
  double u_max = 150.0;       ///< [V], > u_min
  double slew_v_per_s = 1e6;  ///< > 0 [V/s]
};

class OutputLimiter {
 public:
  struct Applied {
    double u = 0.0;
    bool clamped = false;       ///< range limit hit
    bool slew_limited = false;  ///< slew limit hit
    int direction = 0;          ///< +1 limited from above, -1 from below, 0 not limited
  };

  OutputLimiter(OutputLimits limits, double dt_s)
      : limits_(limits), max_step_(limits.slew_v_per_s * dt_s), last_(limits.u_min) {}

  /// Limits a requested output. NaN requests hold the previous output (and count as clamped).
  Applied apply(double requested) noexcept {
    Applied a;
    double u = requested;
    if (std::isnan(u)) {
      u = last_;
      a.clamped = true;
    }
    if (u > limits_.u_max) {
      u = limits_.u_max;
      a.clamped = true;
      a.direction = +1;
    } else if (u < limits_.u_min) {
      u = limits_.u_min;
      a.clamped = true;
      a.direction = -1;
    }
    const double lo = last_ - max_step_, hi = last_ + max_step_;
    if (u > hi) {
      u = hi;
      a.slew_limited = true;
      a.direction = +1;
    } else if (u < lo) {
      u = lo;
      a.slew_limited = true;
      a.direction = -1;
    }
    // The slew window is anchored on a value within range, but keep the range absolute.
    u = std::clamp(u, limits_.u_min, limits_.u_max);
    clamps_ += a.clamped;
    slews_ += a.slew_limited;
    last_ = u;
    a.u = u;
    return a;
  }
  /// Sets the previous output (e.g. after a safe-state jump) without counting anything.
  void reset(double u) noexcept { last_ = std::clamp(u, limits_.u_min, limits_.u_max); }
  std::uint64_t clamp_count() const noexcept { return clamps_; }
  std::uint64_t slew_count() const noexcept { return slews_; }
  void reset_counts() noexcept { clamps_ = slews_ = 0; }
  const OutputLimits& limits() const noexcept { return limits_; }
  double last() const noexcept { return last_; }

 private:
  OutputLimits limits_;
  double max_step_;
  double last_;
  std::uint64_t clamps_ = 0;
  std::uint64_t slews_ = 0;
};

}  // namespace hystbench::daemon
