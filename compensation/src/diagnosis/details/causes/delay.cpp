// Candidate `delay`: a pure time shift between input and output. Statistic: the shift (whole
// samples) that best aligns the baseline prediction with the output (y ~ a yhat(k - s) + b),
// searched up to 20 ms (5..500 samples); significant from one sample. Extension: the baseline
// structure refitted on the input delayed by the best total delay (+-1 sample, by fit error).
#include <algorithm>
#include <cmath>
#include <limits>

#include "diagnosis/details/candidates.hpp"

namespace hystbench::compensation::details {

namespace {

constexpr double kDelayThreshold = 1.0;  // samples
constexpr double kMaxDelaySeconds = 0.02;

// Mean square error of y(k) ~ a x(k - s) + b over the search rows.
double shifted_mse(const DiagnosisRecord& r, std::span<const double> x, long s) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  EveryNth search_rows(r.search_stride);
  const auto last = static_cast<long>(r.n) - 1;
  for (std::size_t k = 0; k < r.n; ++k) {
    if (!r.fit_row(k) || !search_rows.take()) continue;
    const long j = std::clamp(static_cast<long>(k) - s, 0L, last);
    const double v = x[static_cast<std::size_t>(j)], y = r.y[k];
    n += 1, sx += v, sy += y, sxx += v * v, sxy += v * y, syy += y * y;
  }
  const double vx = sxx - sx * sx / n, vy = syy - sy * sy / n, c = sxy - sx * sy / n;
  return vx > 0.0 ? std::max(0.0, vy - c * c / vx) / n : vy / n;
}

}  // namespace

CandidateOutcome test_delay(const CandidateContext& c) {
  CandidateOutcome out;
  const DiagnosisRecord& r = c.record;
  const auto d0 = std::lround(c.base.delay_samples);
  const long max_shift = std::min<long>(
      static_cast<long>(r.n / 20), std::clamp<long>(std::lround(kMaxDelaySeconds / r.dt), 5, 500));
  // Best shift of a prediction, over -current .. max_shift.
  auto best_shift_of = [&](std::span<const double> x, long current, double& mse) {
    long best_shift = 0;
    mse = shifted_mse(r, x, 0);
    for (long s = -current; s <= max_shift; ++s) {
      const double m = s == 0 ? mse : shifted_mse(r, x, s);
      if (m < mse) mse = m, best_shift = s;
    }
    return best_shift;
  };
  double at_zero = shifted_mse(r, c.base_fit.prediction, 0);
  double best = 0.0;
  const long first_shift = best_shift_of(c.base_fit.prediction, d0, best);
  // A baseline fitted without the delay has partly absorbed it (a delay widens the loop), so
  // the first shift is short: refit at the new delay and shift again until it stays.
  long delay = d0 + first_shift;
  ExtensionSpec spec = c.base;
  for (int iteration = 0; iteration < 6 && delay != d0; ++iteration) {
    spec.delay_samples = static_cast<double>(delay);
    const ExtensionFit fit = fit_extension(r, spec, FitRows::kSearch);
    double mse = 0.0;
    const long s = best_shift_of(fit.prediction, delay, mse);
    if (s == 0) break;
    delay += s;
  }
  // Joint refits around it, chosen by the simulated fit error. A resonance in the base was
  // fitted without this delay; where its phase lag stood in for it (the resonance lies off the
  // measured peak), it is found again at each delay.
  double best_rmse = std::numeric_limits<double>::infinity();
  for (long d = delay - 1; d <= delay + 1; ++d) {
    if (d < 0) continue;
    spec.delay_samples = static_cast<double>(d);
    if (c.base.dynamics) {
      spec.dynamics = c.base.dynamics;
      if (auto found = refit_resonance(r, spec, c.response)) spec.dynamics = found;
    }
    ExtensionFit fit = fit_extension(r, spec);
    if (fit.fit.rmse < best_rmse) best_rmse = fit.fit.rmse, out.fit = std::move(fit);
  }
  const auto d = std::lround(out.fit.spec.delay_samples);
  out.statistic = static_cast<double>(std::abs(d - d0));
  out.threshold = kDelayThreshold;
  out.evidence = "the output matches the baseline prediction best " +
                 std::string(first_shift >= 0 ? "delayed" : "advanced") + " by " +
                 std::to_string(std::abs(first_shift)) + " samples (rms " + num(std::sqrt(best)) +
                 " vs " + num(std::sqrt(at_zero)) + " " + r.units.output +
                 "); refitted, the best input delay is " + std::to_string(d) + " samples (" +
                 num(static_cast<double>(d) * r.dt * 1e3) + " ms)" +
                 (d0 > 0 ? " against the baseline's " + std::to_string(d0) : std::string());
  out.extension = "input delay of " + std::to_string(d) + " samples (" +
                  num(static_cast<double>(d) * r.dt * 1e3) + " ms)";
  const auto& found = out.fit.spec.dynamics;
  if (found && c.base.dynamics &&
      found->natural_frequency_hz != c.base.dynamics->natural_frequency_hz) {
    out.extension += ", the resonance found again with it at " + num(found->natural_frequency_hz) +
                     " Hz, damping " + num(found->damping_ratio);
  }
  return out;
}

}  // namespace hystbench::compensation::details
