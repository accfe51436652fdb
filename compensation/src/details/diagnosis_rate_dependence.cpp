// Candidate `rate_dependence`: the loop widens with the input rate (and, unlike dynamics, does
// not ring). Statistic: share of the baseline residual variance explained by the signed input
// rate (holds and steps left out). It can only be told from the loop shape when the record
// crosses the same levels at clearly different rates. Extension: the rate-dependent PI on the
// baseline's plays (and dead zones), cumulative weights linear in du/dt or |du/dt|, or
// thresholds widening with |du/dt| (the best fit), up to the 99.9th percentile of the record's
// rates.
#include <algorithm>
#include <cmath>
#include <limits>

#include "details/diagnosis_candidates.hpp"
#include "details/rate_groups.hpp"

namespace hystbench::compensation::details {

namespace {

constexpr double kThreshold = 0.15;
constexpr double kMinRateSpread = 1.25;  // as the identification's automatic family choice
constexpr double kRateQuantile = 0.999;
// The thresholds law: widening at max_rate as fractions of the input span, and rate filters in
// samples.
constexpr double kWideningFractions[] = {0.005, 0.01, 0.02, 0.04, 0.08, 0.16};
constexpr double kWideningFilterSamples[] = {0.0, 3.0};

}  // namespace

CandidateOutcome test_rate_dependence(const CandidateContext& c) {
  CandidateOutcome out;
  const DiagnosisRecord& r = c.record;
  const ResidualProfile& rate = c.profile("rate");
  const double spread = half_cycle_rate_spread(r.u, r.dt, 0, r.n);
  out.statistic = spread >= kMinRateSpread ? rate.explained : 0.0;
  out.threshold = kThreshold;
  if (rate.means.empty()) {
    out.evidence = "the input never moves smoothly enough to profile the rate";
  } else {
    out.evidence = "the signed input rate explains " + percent(rate.explained) +
                   " of the residual variance (mean residual " + num(rate.means.front()) + " " +
                   r.units.output + " at the fastest falling rate, " + num(rate.means.back()) +
                   " at the fastest rising); half-cycle rates spread " + num(spread) + "x";
    if (spread < kMinRateSpread) {
      out.evidence += " - too little to tell rate dependence from the loop shape";
    }
  }

  std::vector<double> rates = sample_rates(r.u, r.dt);
  const auto q = rates.begin() +
                 static_cast<std::ptrdiff_t>(kRateQuantile * static_cast<double>(rates.size() - 1));
  std::nth_element(rates.begin(), q, rates.end());
  ExtensionSpec spec = c.base;
  ModelStructure& s = spec.structure;
  const bool had_dead_zones = s.has_dead_zones();
  s.kind = ModelKind::kRateDependentPi;
  if (!had_dead_zones) {
    s.dead_zone_thresholds = {0.0};
    s.center = 0.5 * (r.y_lo + r.y_hi);
  }
  s.max_rate = *q > 0.0 ? *q : 1.0 / r.dt;
  // Both laws, as the identification: the signed rate (the paper's eq. 16) and its magnitude,
  // the one that fits the record better (the same unknowns, so on the fit error).
  for (const RateLaw law : {RateLaw::kSigned, RateLaw::kMagnitude}) {
    s.rate_law = law;
    ExtensionFit f = fit_extension(r, spec);
    if (law == RateLaw::kSigned || f.fit.rmse < out.fit.fit.rmse) out.fit = std::move(f);
  }
  // The other mechanism: thresholds that widen with |du/dt|, the widening searched on a grid
  // of the input span at max_rate (and the rate filter) by the regression's residual on the
  // search rows, the best and its neighbours refitted on every row and simulated. It has
  // fewer unknowns than the weight laws, so the fit error chooses fairly between them.
  ExtensionSpec widened = spec;
  ModelStructure& w = widened.structure;
  w.rate_law = RateLaw::kThresholds;
  const double span = r.u_hi - r.u_lo;
  double best_search = std::numeric_limits<double>::infinity();
  ExtensionSpec best_widened = widened;
  for (const double samples : kWideningFilterSamples) {
    // Not capped inside the record (as the identification): a step's rate holds the switching.
    const std::vector<double> filtered = sample_rates(r.u, r.dt, samples * r.dt);
    w.max_rate = std::max(s.max_rate, *std::max_element(filtered.begin(), filtered.end()));
    w.record_max_rate = w.max_rate;
    for (const double fraction : kWideningFractions) {
      w.rate_filter_s = samples * r.dt;
      w.threshold_rate_s = fraction * span / s.max_rate;
      // Ranked by the regression's residual, as the dynamics search: no simulation per point.
      const double mse = fit_extension(r, widened, FitRows::kSearch, false).regression_mse;
      if (mse < best_search) best_search = mse, best_widened = widened;
    }
  }
  for (const double step : {1.0, std::sqrt(2.0), 1.0 / std::sqrt(2.0)}) {
    ExtensionSpec t = best_widened;
    t.structure.threshold_rate_s *= step;
    ExtensionFit f = fit_extension(r, t);
    if (f.fit.rmse < out.fit.fit.rmse) out.fit = std::move(f);
  }
  const ModelStructure& chosen = out.fit.spec.structure;
  out.extension = "rate-dependent PI on " + std::to_string(s.plays()) + " plays, ";
  if (chosen.rate_law == RateLaw::kThresholds) {
    out.extension += "thresholds widening by " + num(chosen.threshold_rate_s * 1e3) + " " +
                     r.units.input + " per " + r.units.input + "/ms of |du/dt|";
  } else {
    out.extension += std::string("weights linear in ") +
                     (chosen.rate_law == RateLaw::kSigned ? "du/dt" : "|du/dt|") + " up to " +
                     num(s.max_rate) + " " + r.units.input + "/s";
  }
  return out;
}

}  // namespace hystbench::compensation::details
