// Candidate `rate_dependence`: the loop widens with the input rate (and, unlike dynamics, does
// not ring). Statistic: share of the baseline residual variance explained by the signed input
// rate (holds and steps left out). It can only be told from the loop shape when the record
// crosses the same levels at clearly different rates. Extension: the rate-dependent PI on the
// baseline's plays (and dead zones), cumulative weights linear in du/dt or |du/dt|, or
// thresholds widening with |du/dt| (the best fit), up to the 99.9th percentile of the record's
// rates; on a Preisach baseline, the plane's relays widening with |du/dt| (the thresholds law,
// preisach_model.hpp). On top of a delay the diagnosis named, the thresholds law is also tried on a
// sample less; on top of a mode on its peak, where the law falls just short of being named, the
// mode is projected again beside it.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "details/rate_groups.hpp"
#include "diagnosis/details/candidates.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"

namespace hystbench::compensation::details {

namespace {

// The statistic is a weak witness: behind a loop shape the baseline misses, records with a rate
// effect and records without one (a delay above all) overlap in how much of the residual the rate
// explains (docs/measurements.md, Diagnosis). It only keeps a record whose residual the rate does
// not order at all from the contest; the held-out gain and the carry-over decide
// (DiagnosisHiddenEffect.NamesRateDependenceBehindASwitchingFront names the weak cases).
constexpr double kRateDependenceThreshold = 0.1;
constexpr double kMinRateSpread = 1.25;  // as the identification's automatic family choice
constexpr double kRateQuantile = 0.999;
// The thresholds law: widening at max_rate as fractions of the input span, and rate filters in
// samples.
constexpr double kWideningFractions[] = {0.005, 0.01, 0.02, 0.04, 0.08, 0.16};
constexpr double kWideningFilterSamples[] = {0.0, 3.0};
// Powers of the rate the widening grows with: linear (the identification's), and the square root.
constexpr double kWideningExponents[] = {1.0, 0.5};
// Added to a joint model with a mode, a law gaining at least this (and short of the gain needed)
// has the mode projected again beside it; below it the law is not in the record, and the
// projection's hundred trial fits are not spent.
constexpr double kMinGainToProject = 1.02;

// The other mechanism: thresholds that widen with |du/dt| (or its square root), the widening
// searched on a grid of the input span at max_rate (and the rate filter) by the regression's
// residual on the search rows; returns the best point, whose neighbours the caller refits on every
// row and simulates. It has fewer unknowns than the weight laws, so the fit error chooses fairly
// between them. `spec`: the rate-dependent structure with max_rate the smooth rates' quantile.
ExtensionSpec best_thresholds_law(const DiagnosisRecord& r, const ExtensionSpec& spec) {
  const ModelStructure& s = spec.structure;
  ExtensionSpec widened = spec;
  ModelStructure& w = widened.structure;
  w.rate_law = RateLaw::kThresholds;
  const double span = r.u_hi - r.u_lo;
  double best_search = std::numeric_limits<double>::infinity();
  ExtensionSpec best_widened = widened;
  const std::vector<double> held = held_search_target(r, spec);
  for (const double samples : kWideningFilterSamples) {
    // Linear: not capped inside the record (as the identification), a step's rate holds the
    // switching. The square root capped at the smooth rates: after a step its filtered rate
    // decays at half the filter's pace, a tail that would stand in for creep.
    const std::vector<double> filtered = sample_rates(r.u, r.dt, samples * r.dt);
    const double uncapped =
        std::max(s.max_rate, *std::max_element(filtered.begin(), filtered.end()));
    w.rate_filter_s = samples * r.dt;
    w.record_max_rate = uncapped;
    for (const double exponent : kWideningExponents) {
      w.threshold_rate_exponent = exponent;
      w.max_rate = exponent == 1.0 ? uncapped : s.max_rate;
      for (const double fraction : kWideningFractions) {
        // The widening at s.max_rate is `fraction` of the span.
        w.threshold_rate_s = fraction * span / s.max_rate;
        // Ranked by the regression's residual, as the dynamics search: no simulation per point.
        const double mse = search_mse(r, widened, held);
        if (mse < best_search) best_search = mse, best_widened = widened;
      }
    }
  }
  return best_widened;
}

// The grid's best widening and its neighbours (x sqrt 2 either way), each refitted on every row and
// simulated: the one of least fit error.
ExtensionFit refined_thresholds_law(const DiagnosisRecord& r, const ExtensionSpec& grid_best) {
  std::optional<ExtensionFit> best;
  for (const double step : {1.0, std::sqrt(2.0), 1.0 / std::sqrt(2.0)}) {
    ExtensionSpec t = grid_best;
    t.structure.threshold_rate_s *= step;
    ExtensionFit f = fit_extension(r, t);
    if (!best || f.fit.rmse < best->fit.rmse) best = std::move(f);
  }
  return std::move(*best);
}

// The plane's law, in the input unit; s: the structure with the smooth rates' max.
std::string describe_plane_rate_law(const ModelStructure& chosen, const ModelStructure& s,
                                    const std::string& unit) {
  std::string text = "the Preisach plane's relays widening with |du/dt|";
  if (chosen.threshold_rate_exponent != 1.0) {
    text += '^';
    text += num(chosen.threshold_rate_exponent);
  }
  const double widening = threshold_widening(
      chosen.threshold_rate_s, chosen.threshold_rate_exponent, chosen.max_rate, s.max_rate);
  text += ", by " + num(widening) + " " + unit + " at " + num(s.max_rate) + " " + unit + "/s";
  return text;
}

// What the chosen rate law adds, in the input unit; s: the structure with the smooth rates' max.
std::string describe_rate_law(const ModelStructure& chosen, const ModelStructure& s,
                              const std::string& unit) {
  std::string text = "rate-dependent PI on " + std::to_string(s.plays()) + " plays, ";
  if (chosen.rate_law == RateLaw::kThresholds && chosen.threshold_rate_exponent != 1.0) {
    return text + "thresholds widening with |du/dt|^" + num(chosen.threshold_rate_exponent) +
           ", by " +
           num(threshold_widening(chosen.threshold_rate_s, chosen.threshold_rate_exponent,
                                  chosen.max_rate, s.max_rate)) +
           " " + unit + " at " + num(s.max_rate) + " " + unit + "/s";
  }
  if (chosen.rate_law == RateLaw::kThresholds) {
    return text + "thresholds widening by " + num(chosen.threshold_rate_s * 1e3) + " " + unit +
           " per " + unit + "/ms of |du/dt|";
  }
  return text + "weights linear in " + (chosen.rate_law == RateLaw::kSigned ? "du/dt" : "|du/dt|") +
         " up to " + num(s.max_rate) + " " + unit + "/s";
}

// The statistic (0 where the half-cycle rates spread too little), its threshold and the
// evidence line, into out.
void read_rate_statistic(const CandidateContext& c, CandidateOutcome& out) {
  const DiagnosisRecord& r = c.record;
  const ResidualProfile& rate = c.profile("rate");
  const double spread = half_cycle_rate_spread(r.u, r.dt, 0, r.n);
  out.statistic = spread >= kMinRateSpread ? rate.explained : 0.0;
  out.threshold = kRateDependenceThreshold;
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
}

}  // namespace

CandidateOutcome test_rate_dependence(const CandidateContext& c) {
  CandidateOutcome out;
  const DiagnosisRecord& r = c.record;
  read_rate_statistic(c, out);

  ExtensionSpec spec = c.base;
  ModelStructure& s = spec.structure;
  if (s.kind == ModelKind::kPreisach && s.rate_law == RateLaw::kThresholds &&
      s.threshold_rate_s > 0.0) {
    out.fit = c.base_fit;
    out.extension = "none: the Preisach plane's relays already widen with |du/dt|";
    return out;
  }
  std::vector<double> rates = sample_rates(r.u, r.dt);
  const auto q = rates.begin() +
                 static_cast<std::ptrdiff_t>(kRateQuantile * static_cast<double>(rates.size() - 1));
  std::nth_element(rates.begin(), q, rates.end());
  if (s.kind == ModelKind::kPreisach) {
    // The plane's relays have no play weights: only the thresholds law, its relays widening.
    s.max_rate = *q > 0.0 ? *q : 1.0 / r.dt;
    out.fit = refined_thresholds_law(r, best_thresholds_law(r, spec));
    out.extension = describe_plane_rate_law(out.fit.spec.structure, s, r.units.input);
    return out;
  }
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
  // A delay named before was found without the law, and may have taken some of the widening's
  // lag: the thresholds law is tried on a sample less too
  // (DiagnosisSeveralCauses.NamesAWideningLawWhoseLagTheDelayTook). Not below the reference's own
  // delay (an identified model's): a law on less than the record's delay stands in for it
  // (BenchFeedforwardTest.IdentifyAddsTheDelayAndResonanceAndTracksFiveHundredHertz).
  std::vector<ExtensionSpec> delays{spec};
  if (c.reference_delay_samples >= 0.0 && spec.delay_samples >= c.reference_delay_samples + 1.0) {
    delays.push_back(spec);
    delays.back().delay_samples -= 1.0;
  }
  for (const ExtensionSpec& delayed : delays) {
    ExtensionFit f = refined_thresholds_law(r, best_thresholds_law(r, delayed));
    if (f.fit.rmse < out.fit.fit.rmse) out.fit = std::move(f);
  }
  // On top of a mode on its peak, the law just short of being named: the mode was fitted without
  // it, and its phase may stand in for some of the widening; projected again beside the law
  // (DiagnosisSeveralCauses.NamesAWideningLawBesideALightlyDampedMode).
  const double added = c.base_fit.heldout.rmse / out.fit.heldout.rmse;
  if (out.fit.spec.dynamics && added >= kMinGainToProject && added < c.added_gain_needed) {
    ExtensionSpec moded = out.fit.spec;
    if (auto found = project_resonance(r, moded, c.response)) {
      moded.dynamics = found;
      ExtensionFit f = fit_extension(r, moded);
      if (f.fit.rmse < out.fit.fit.rmse) out.fit = std::move(f);
    }
  }
  out.extension = describe_rate_law(out.fit.spec.structure, s, r.units.input);
  if (out.fit.spec.delay_samples < spec.delay_samples) {
    out.extension += ", the delay found again with it at " + num(out.fit.spec.delay_samples) +
                     " samples (" + num(spec.delay_samples) + " without the law)";
  }
  return out;
}

}  // namespace hystbench::compensation::details
