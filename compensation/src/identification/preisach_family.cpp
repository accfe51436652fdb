// The Preisach plane as an identify family: its cells, output map and smoothness by held-out
// error (preisach_identification.hpp), and relays that widen with the rate where they predict
// the held-out part better.
#include <string>
#include <utility>
#include <vector>

#include "details/identifier.hpp"
#include "details/preisach_search.hpp"
#include "details/validate.hpp"
#include "hystbench/compensation/preisach_identification.hpp"
#include "hystbench/compensation/rate_estimator.hpp"

namespace hystbench::compensation::details::identification {

namespace {

// The Preisach plane's thresholds rate law is kept where it lowers the held-out error by this
// share: more than the parsimony margin, as it adds a mechanism (the inverse's rate prediction)
// and not only unknowns.
constexpr double kPlaneRateLawGain = 0.02;
// The Preisach plane's cells per side when the options leave the order open (its smoothness
// penalty, chosen on held-out data, keeps a short record from over-fitting them).
constexpr int kPreisachCells = 24;

}  // namespace

Candidate Identifier::search_preisach() { return plane_fit({}); }

Candidate Identifier::plane_fit(const std::vector<double>& creep_time_constants) {
  ModelStructure s = structure(ModelKind::kPreisach, 0, 0);
  s.creep_time_constants = creep_time_constants;
  s.preisach_cells = static_cast<std::size_t>(o_.operators > 0 ? o_.operators : kPreisachCells);
  s.plane_min = r_.u_lo;
  s.plane_max = r_.u_hi;
  s.min_play_slope = 0.0;  // the reversible slope may vanish: the relays rise
  s.min_dead_zone_slope = kMinMapSlope;
  const PreisachFitOptions choices;  // its smoothness weights, output maps, held-out share
  std::vector<std::size_t> zones = choices.output_zones;
  if (o_.dead_zones >= 0) zones = {static_cast<std::size_t>(o_.dead_zones)};
  const auto split =
      r_.fit_end - static_cast<std::size_t>(choices.heldout_fraction *
                                            static_cast<double>(r_.fit_end - r_.begin));
  const details::PreisachSearch found = details::search_preisach(
      s, r_.ud, r_.y, r_.begin, split, r_.fit_end, choices.smoothness, zones);
  Candidate c;
  c.structure = found.structure;
  c.x = found.x;
  const Design design(c.structure);
  c.model = design.build(c.x);
  if (c.structure.drift) c.drift = c.x[design.drift_column()];
  c.method = "bounded-lsq-preisach (smoothness " + fmt(c.structure.smoothness) + ")" +
             (creep_time_constants.empty() ? "" : "+creep");
  score(c, r_);
  log_.push_back({ModelKind::kPreisach, operators_of(c.structure), dead_zones_of(c.structure),
                  r_.delay, c.fit.rmse, c.heldout.rmse, c.method});
  if (o_.preisach_rate_law) add_plane_rate_law(c);
  return c;
}

void Identifier::add_plane_rate_law(Candidate& c) {
  ModelStructure s = c.structure;
  Candidate widened;
  if (plane_law_) {
    // Searched once already (the plane before its creep lags), or given: that law, on this plane.
    if (!*plane_law_) return;
    s.set_thresholds_law(**plane_law_);
    stage_progress(0.0, "the plane's thresholds rate law, refitted");
    widened = evaluate(s, "constrained-lsq-rate-thresholds");
  } else {
    s.max_rate = smooth_max_rate(r_.ud, r_.dt);
    if (!(s.max_rate > 0.0)) return;  // a record without smooth motion shows no rate law
    s.record_max_rate = s.max_rate;
    // The rate-dependent PI's thresholds law, fitted the same way (its widening, filter and cap
    // by the fit's error).
    widened = thresholds_law_over(s);
  }
  // Kept where it predicts the held-out part better by kPlaneRateLawGain.
  const bool kept = widened.model && widened.score() < (1.0 - kPlaneRateLawGain) * c.score();
  if (!plane_law_) {
    plane_law_.emplace();  // searched: the law found, or none
    if (kept) *plane_law_ = widened.structure.thresholds_law();
  }
  if (kept) {
    widened.method = c.method + "+rate-thresholds";
    c = std::move(widened);
  }
}

}  // namespace hystbench::compensation::details::identification
