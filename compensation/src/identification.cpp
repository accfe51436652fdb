#include "hystbench/compensation/identification.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "details/identifier.hpp"
#include "details/validate.hpp"

namespace hystbench::compensation {

namespace {

using details::fmt;

constexpr std::size_t kMinSamples = 50;

void validate_record(std::span<const double> t, std::span<const double> u,
                     std::span<const double> y) {
  details::require(t.size() == u.size() && u.size() == y.size(),
                   "t, u and y must have the same length (t: " + std::to_string(t.size()) +
                       ", u: " + std::to_string(u.size()) + ", y: " + std::to_string(y.size()) +
                       ")");
  details::require(u.size() >= kMinSamples, "at least " + std::to_string(kMinSamples) +
                                                " samples are needed to identify a model, got " +
                                                std::to_string(u.size()));
  details::require_record(t, u, y);
}

void validate_thresholds(const FitOptions& o) {
  if (!o.play_thresholds.empty()) {
    details::require_finite(o.play_thresholds, "options.play_thresholds");
    details::require(o.play_thresholds.front() == 0.0,
                     "options.play_thresholds[0] must be 0 (else the model is not invertible)");
    details::require_strictly_increasing(o.play_thresholds, "options.play_thresholds");
  }
  if (!o.dead_zone_thresholds.empty()) {
    details::require_finite(o.dead_zone_thresholds, "options.dead_zone_thresholds");
    details::require_strictly_increasing(o.dead_zone_thresholds, "options.dead_zone_thresholds");
    details::require(
        std::count(o.dead_zone_thresholds.begin(), o.dead_zone_thresholds.end(), 0.0) == 1,
        "options.dead_zone_thresholds must contain exactly one 0");
  }
}

void validate_options(const FitOptions& o, std::size_t n) {
  details::require(
      std::isfinite(o.heldout_fraction) && o.heldout_fraction >= 0.0 && o.heldout_fraction <= 0.9,
      "options.heldout_fraction must be in [0, 0.9], got " + fmt(o.heldout_fraction));
  details::require(o.operators >= 0, "options.operators must be >= 0 (0 = automatic)");
  details::require(o.dead_zones >= -1, "options.dead_zones must be >= -1 (-1 = automatic)");
  details::require(std::isfinite(o.min_cumulative_weight) && o.min_cumulative_weight > 0.0,
                   "options.min_cumulative_weight must be > 0 (it guarantees invertibility)");
  details::require(o.delay_samples >= -1, "options.delay_samples must be >= -1 (-1 = automatic)");
  details::require(
      o.max_delay_samples >= 0 && static_cast<std::size_t>(o.max_delay_samples) < n / 4,
      "options.max_delay_samples must be in [0, N/4)");
  details::require(o.delay_samples < 0 || static_cast<std::size_t>(o.delay_samples) < n / 4,
                   "options.delay_samples must be < N/4");
  if (o.creep) {
    details::require(!o.creep_time_constants_s.empty() || o.creep_operators >= 1,
                     "options.creep_operators must be >= 1 when creep is on");
    for (const double tau : o.creep_time_constants_s) {
      details::require(std::isfinite(tau) && tau > 0.0,
                       "options.creep_time_constants_s must be positive");
    }
  }
  if (o.preisach_given_rate_law) {
    const ThresholdsRateLaw& law = *o.preisach_given_rate_law;
    const auto nonnegative = [](double v) { return std::isfinite(v) && v >= 0.0; };
    details::require(nonnegative(law.threshold_rate_s) && nonnegative(law.max_rate) &&
                         nonnegative(law.record_max_rate) && nonnegative(law.rate_filter_s) &&
                         law.exponent > 0.0 && law.exponent <= 1.0,
                     "options.preisach_given_rate_law needs a widening, caps and a filter >= 0 "
                     "and an exponent in (0, 1]");
  }
  validate_thresholds(o);
}

}  // namespace

FitResult fit_model(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                    const FitOptions& options) {
  validate_record(t, u, y);
  validate_options(options, u.size());
  return details::identification::Identifier(t, u, y, options).run();
}

FitResult fit_model_with_creep(std::span<const double> t, std::span<const double> u,
                               std::span<const double> y, FitOptions options) {
  options.creep = true;
  return fit_model(t, u, y, options);
}

ModelScore score_model(ActuatorModel model, std::span<const double> t, std::span<const double> u,
                       std::span<const double> y, double heldout_fraction,
                       std::size_t skip_samples) {
  validate_record(t, u, y);
  details::require(heldout_fraction >= 0.0 && heldout_fraction <= 0.9,
                   "heldout_fraction must be in [0, 0.9]");
  const std::size_t n = u.size();
  const std::size_t fit_end = n - static_cast<std::size_t>(std::floor(heldout_fraction * n));
  details::require(skip_samples < fit_end, "skip_samples leaves nothing to score");
  const double dt = (t.back() - t.front()) / static_cast<double>(n - 1);
  const std::vector<double> yhat = model.simulate(u, dt);
  ModelScore s;
  s.fit = error_stats(y.subspan(skip_samples, fit_end - skip_samples),
                      std::span(yhat).subspan(skip_samples, fit_end - skip_samples));
  s.heldout = error_stats(y.subspan(fit_end), std::span(yhat).subspan(fit_end));
  return s;
}

}  // namespace hystbench::compensation
