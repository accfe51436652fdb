#include "hystbench/compensation/tracking_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace hystbench::compensation {

double hysteresis_width(std::span<const double> y_ref, std::span<const double> y) {
  const std::size_t n = std::min(y_ref.size(), y.size());
  if (n < 3) return 0.0;
  const auto [lo_it, hi_it] = std::minmax_element(y_ref.begin(), y_ref.begin() + n);
  const double lo = *lo_it, hi = *hi_it, span = hi - lo;
  if (!(span > 0.0)) return 0.0;
  constexpr int kLevels = 100;
  std::vector<double> up_sum(kLevels, 0.0), down_sum(kLevels, 0.0);
  std::vector<int> up_n(kLevels, 0), down_n(kLevels, 0);
  const double first = lo + 0.05 * span, step = 0.9 * span / (kLevels - 1);
  for (std::size_t k = 1; k < n; ++k) {
    const double a = y_ref[k - 1], b = y_ref[k];
    if (a == b) continue;
    const double seg_lo = std::min(a, b), seg_hi = std::max(a, b);
    int i0 = static_cast<int>(std::ceil((seg_lo - first) / step));
    int i1 = static_cast<int>(std::floor((seg_hi - first) / step));
    i0 = std::max(i0, 0);
    i1 = std::min(i1, kLevels - 1);
    for (int i = i0; i <= i1; ++i) {
      const double level = first + i * step;
      if (level < seg_lo || level > seg_hi) continue;
      const double f = (level - a) / (b - a);
      const double yi = y[k - 1] + f * (y[k] - y[k - 1]);
      if (b > a) {
        up_sum[i] += yi;
        ++up_n[i];
      } else {
        down_sum[i] += yi;
        ++down_n[i];
      }
    }
  }
  double width = 0.0;
  for (int i = 0; i < kLevels; ++i) {
    if (up_n[i] > 0 && down_n[i] > 0) {
      width = std::max(width, std::abs(down_sum[i] / down_n[i] - up_sum[i] / up_n[i]));
    }
  }
  return width;
}

double hysteresis_percent(std::span<const double> y_ref, std::span<const double> y) {
  const std::size_t n = std::min(y_ref.size(), y.size());
  if (n < 3) return 0.0;
  const auto [lo, hi] = std::minmax_element(y.begin(), y.begin() + n);
  const double range = *hi - *lo;
  return range > 0.0 ? 100.0 * hysteresis_width(y_ref, y) / range : 0.0;
}

double output_lag_samples(std::span<const double> y_ref, std::span<const double> y) {
  const std::size_t n = std::min(y_ref.size(), y.size());
  if (n < 3) return 0.0;
  double mean = 0.0;
  for (std::size_t k = 1; k + 1 < n; ++k) mean += y[k] - y_ref[k];
  mean /= static_cast<double>(n - 2);
  double eg = 0.0, gg = 0.0;
  for (std::size_t k = 1; k + 1 < n; ++k) {
    const double slope = 0.5 * (y_ref[k + 1] - y_ref[k - 1]);
    eg += (y[k] - y_ref[k] - mean) * slope;
    gg += slope * slope;
  }
  return gg > 0.0 ? -eg / gg : 0.0;
}

StepFigures step_figures(std::span<const double> y_ref, std::span<const double> y, double dt_s,
                         double min_step, double band) {
  StepFigures f;
  const std::size_t n = std::min(y_ref.size(), y.size());
  // The reference's levels: samples equal to the one before. A step is a move between two
  // levels: from the first sample after the last held one to the first held at the new level.
  struct Move {
    std::size_t start, level;  // the first moving sample; a sample of the new level
  };
  std::vector<Move> moves;
  bool holding = false;
  std::size_t held = 0;  // the last sample known to be on a level
  for (std::size_t k = 1; k < n; ++k) {
    if (y_ref[k] != y_ref[k - 1]) continue;
    if (holding && held + 1 < k && std::abs(y_ref[k] - y_ref[held]) >= min_step) {
      moves.push_back({held + 1, k});
    }
    holding = true;
    held = k;
  }
  for (std::size_t i = 0; i < moves.size(); ++i) {
    const std::size_t k0 = moves[i].start;
    const std::size_t end = i + 1 < moves.size() ? moves[i + 1].start : n;
    const double level = y_ref[moves[i].level], step = level - y_ref[k0 - 1];
    const double size = std::abs(step), direction = step > 0.0 ? 1.0 : -1.0;
    double overshoot = 0.0;
    std::size_t last_outside = k0 - 1;  // the last sample outside the band
    for (std::size_t k = k0; k < end; ++k) {
      const double e = y[k] - level;
      overshoot = std::max(overshoot, direction * e / size);
      if (std::abs(e) > band * size) last_outside = k;
    }
    const bool settled = last_outside + 1 < end;
    const double settling = static_cast<double>(last_outside + 1 - k0) * dt_s;
    f.settled = f.settled && settled;
    f.max_settling_s = std::max(f.max_settling_s, settling);
    f.mean_settling_s += settling;
    f.max_overshoot = std::max(f.max_overshoot, overshoot);
    f.mean_overshoot += overshoot;
    f.mean_size += size;
    ++f.steps;
  }
  if (f.steps > 0) {
    const auto count = static_cast<double>(f.steps);
    f.mean_settling_s /= count;
    f.mean_overshoot /= count;
    f.mean_size /= count;
  }
  return f;
}

}  // namespace hystbench::compensation
