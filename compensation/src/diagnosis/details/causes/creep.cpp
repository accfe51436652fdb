// Candidate `creep`: the output keeps moving, in the direction of the last input change, while
// the input holds. Statistic: share of the variance of the residual signed by the last move
// that the (log) time since the last step or reversal explains, over the holds from 50 ms on
// (over all samples when the record has no holds: weak evidence). Extension: creep lags
// (CreepOperatorBank) log-spaced from max(50 ms, 5 samples) to a hundred times the record, about
// two per decade (at most ten), fitted jointly with the baseline's weights: a logarithmic creep
// goes on far beyond any record, and its lags longer than the record (near ramps of the input's
// integral) are what a drift would otherwise take for its own.
#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "diagnosis/details/candidates.hpp"

namespace hystbench::compensation::details {

namespace {

constexpr double kCreepThreshold = 0.2;
constexpr double kSettleSeconds = 0.05;
constexpr double kMinHoldSeconds = 0.5;  // in all, for the holds to count as evidence

std::vector<double> creep_time_constants(const DiagnosisRecord& r) {
  const double lo = std::max(kSettleSeconds, 5.0 * r.dt);
  const double hi = std::max(2.0 * lo, 100.0 * r.duration());
  const auto count =
      static_cast<std::size_t>(std::clamp(std::round(2.0 * std::log10(hi / lo)) + 1.0, 3.0, 10.0));
  return log_spaced_time_constants(count, lo, hi);
}

// The residual signed by the last move, profiled against the log time since it over the holds
// (all samples after a move when the record has too few); `holds`: whether the holds count.
struct HoldProfile {
  bool holds = false;
  double longest = 0.0;  ///< [s] the longest time since a move among the samples used
  std::optional<ResidualProfile> profile;  ///< none when the input never rests long enough
};

HoldProfile hold_profile(const CandidateContext& c) {
  const DiagnosisRecord& r = c.record;
  const InputEvents& ev = c.events;
  HoldProfile h;
  h.holds = ev.hold_seconds >= kMinHoldSeconds;
  std::vector<unsigned char> use(r.n, 0);
  std::vector<double> signed_residual(r.n, 0.0);
  for (std::size_t k = 0; k < r.n; ++k) {
    signed_residual[k] = c.residual[k] * ev.last_move[k];
    use[k] = ev.last_move[k] != 0 && ev.since_event_s[k] >= kSettleSeconds &&
             (!h.holds || ev.holding[k]);
    if (use[k]) h.longest = std::max(h.longest, ev.since_event_s[k]);
  }
  if (h.longest > kSettleSeconds) {
    h.profile =
        binned_profile("since_event", "time since the last step or reversal [s]", ev.since_event_s,
                       signed_residual, use, log_edges(kSettleSeconds, h.longest, 12));
  }
  return h;
}

}  // namespace

double creep_statistic(const CandidateContext& c) {
  const HoldProfile h = hold_profile(c);
  return h.profile ? h.profile->explained : 0.0;
}

CandidateOutcome test_creep(const CandidateContext& c) {
  CandidateOutcome out;
  const DiagnosisRecord& r = c.record;
  const InputEvents& ev = c.events;
  const HoldProfile h = hold_profile(c);
  if (h.profile) {
    const ResidualProfile& p = *h.profile;
    out.statistic = p.explained;
    const double moved = p.means.empty() ? 0.0 : p.means.back() - p.means.front();
    out.evidence =
        (h.holds ? "over " + std::to_string(ev.holds) + " holds (" + num(ev.hold_seconds) + " s)"
                 : std::string("the record has no holds (weak evidence): after reversals")) +
        " the residual moves " + num(moved) + " " + r.units.output +
        " in the direction of the last input change between " + num(kSettleSeconds) + " and " +
        num(h.longest) + " s; log time explains " + percent(p.explained) + " of its variance";
  } else {
    out.evidence = "the input never rests long enough to show creep";
  }
  out.threshold = kCreepThreshold;

  ExtensionSpec spec = c.base;
  spec.structure.creep_time_constants = creep_time_constants(r);
  out.fit = fit_extension(r, spec);
  const auto& tau = spec.structure.creep_time_constants;
  out.extension = "creep: " + std::to_string(tau.size()) + " lags " + num(tau.front()) + ".." +
                  num(tau.back()) + " s";
  return out;
}

}  // namespace hystbench::compensation::details
