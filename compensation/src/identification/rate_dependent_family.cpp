// The rate-dependent PI family: rate laws over the modified PI's plays and dead zones (joint
// fits, the paper's rate-group regression, thresholds that widen with the rate), kept only where
// they beat the modified PI they extend.
#include <algorithm>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "details/identifier.hpp"
#include "details/rate_groups.hpp"
#include "details/validate.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "hystbench/compensation/rate_estimator.hpp"

namespace hystbench::compensation::details::identification {

namespace {

// Automatic family choice tries the rate-dependent model only when the record crosses the same
// input levels at clearly different rates (else its rate terms merely fit the loop shape of
// the one excitation and do not carry over to other signals).
constexpr double kMinRateSpread = 1.25;
// RPI rate filter time constants tried, in fit samples (RateEstimator; 0 = the per-sample
// difference): the one with the lowest held-out error is kept.
constexpr double kRateFilterSamples[] = {0.0, 2.0, 5.0, 20.0};
// Both rate laws are tried: the signed rate (the rate-dependent paper's eq. 16) and its
// magnitude; the record, by held-out error, says which its actuator follows.
std::vector<std::pair<RateLaw, double>> rate_laws_and_filters() {
  std::vector<std::pair<RateLaw, double>> out;
  for (const RateLaw law : {RateLaw::kSigned, RateLaw::kMagnitude}) {
    for (const double samples : kRateFilterSamples) out.emplace_back(law, samples);
  }
  return out;
}

}  // namespace

std::string Identifier::rpi_auto_skip() const {
  return details::half_cycle_rate_spread(r_.ud, r_.dt, r_.begin, r_.fit_end) < kMinRateSpread
             ? "the record has a single excitation rate"
             : "";
}

Candidate Identifier::search_rpi() {
  const Candidate mpi = search_mpi();
  Candidate best = rpi_over(mpi);
  // The dead zones (and plays) the modified PI chose are a poor guide on a record with rate
  // dependence: the rate-free model bends to the fast segments, and its held-out error is about
  // equal at every order, so it keeps the smallest. With the rate law each order is judged on
  // its own.
  // Judged before refinement and creep, which can reorder close candidates: run() finishes the
  // one the modified PI's order gives too and keeps the better.
  const std::vector<int> ms = dead_zone_grid();
  rpi_by_mpi_order_.reset();
  if (ms.size() > 1) {
    const int chosen = dead_zones_of(mpi.structure);
    rpi_by_mpi_order_ = best;
    for (const int m : ms) {
      if (m == chosen) continue;
      Candidate c = rpi_over(memo(ModelKind::kModifiedPi, mpi_plays(m), m));
      if (c.score() < (1.0 - kParsimony) * best.score()) best = std::move(c);
    }
    if (dead_zones_of(best.structure) == dead_zones_of(rpi_by_mpi_order_->structure)) {
      rpi_by_mpi_order_.reset();
    }
  }
  return best;
}

Candidate Identifier::rpi_over(const Candidate& mpi) {
  ModelStructure s = mpi.structure;
  s.kind = ModelKind::kRateDependentPi;
  // The rate range of the smooth parts: a step or a sharp reversal moves the input in a sample
  // or two, and its per-sample rate would otherwise set a range the weights never see again.
  s.max_rate = smooth_max_rate(r_.ud, r_.dt);
  if (!(s.max_rate > 0.0)) {
    const std::vector<double> rates = details::sample_rates(r_.ud, r_.dt);
    s.max_rate = std::max(*std::max_element(rates.begin(), rates.end()), 1e-300);
  }
  s.record_max_rate = s.max_rate;
  // The nested model: the MPI with zero rate coefficients is a feasible RPI, so the RPI the
  // search returns is never worse on held-out data than the MPI it extends.
  Candidate best = nested_rpi(mpi, s);
  // The paper's way: per-rate-group weights regressed on rate, dead zones from the MPI.
  const Design mpi_design(mpi.structure);
  const Eigen::VectorXd v =
      mpi.x.segment(mpi_design.dead_zone_column(), mpi_design.dead_zone_unknowns());
  // The rate law, its filter and its cap are structural numbers of one size of model (the same
  // unknowns): they are chosen by the fit's error over the whole fitted part, whose fast
  // segments are where they differ (the held-out end, slow reversals, can hardly tell them
  // apart). The law so chosen must then beat its nested modified PI on held-out data.
  Candidate rated, rated_heldout;  // the best by fit error, and by held-out error
  auto consider = [&](Candidate c) {
    if (!rated_heldout.model || c.score() < rated_heldout.score()) rated_heldout = c;
    if (!rated.model || c.fit.rmse < rated.fit.rmse) rated = std::move(c);
  };
  for (const auto& [law, samples] : rate_laws_and_filters()) {
    s.rate_law = law;
    s.rate_filter_s = samples * r_.dt;
    stage_progress(0.0, std::string(to_string(law)) + " rate law, rate filter " +
                            fmt(s.rate_filter_s * 1e3) + " ms");
    // The rate law may level off inside the record's rate range (the rate-dependent paper's
    // weights saturate at high rates): the cap on a grid below the record's largest smooth rate,
    // chosen by the fit's error over the whole record (one structural number; the held-out end,
    // slow reversals, cannot tell caps apart).
    for (const double fraction : kRateCapFractions) {
      ModelStructure capped = s;
      capped.max_rate = s.max_rate * fraction;
      consider(evaluate(capped, "constrained-lsq-rate-joint"));
    }
    if (law != RateLaw::kMagnitude) continue;  // the paper's groups are rates, not signs
    const auto x = details::fit_rate_groups(s, v, r_.ud, r_.y, r_.begin, r_.fit_end);
    if (!x) continue;
    Candidate g;
    g.structure = s;
    g.x = *x;
    g.model = Design(s).build(*x);
    g.method = "rate-groups-regression";
    score(g, r_);
    log_.push_back({s.kind, static_cast<int>(s.plays()), dead_zones_of(s), r_.delay, g.fit.rmse,
                    g.heldout.rmse, g.method});
    consider(std::move(g));
  }
  // The other mechanism: thresholds that widen with |du/dt|. The two laws' best fits are
  // judged against each other on held-out data.
  Candidate widened = thresholds_law_over(s);
  if (widened.model) {
    if (!rated_heldout.model || widened.score() < rated_heldout.score()) rated_heldout = widened;
    if (!rated.model || widened.score() < rated.score()) rated = std::move(widened);
  }
  if (rated.model && rated.score() < best.score()) {
    best = std::move(rated);
  } else if (rated_heldout.model && rated_heldout.score() < best.score()) {
    // The best fit did not carry over to the held-out part (a record whose fast parts are few);
    // a rate law that does still beats the modified PI it extends.
    best = std::move(rated_heldout);
  }
  return best;
}

Candidate Identifier::nested_rpi(const Candidate& mpi, const ModelStructure& s) {
  // The MPI as an RPI with zero rate coefficients: the same outputs, so the same scores.
  const auto& h = dynamic_cast<const ModifiedPiModel&>(mpi.model->hysteresis());
  Candidate c = mpi;
  c.structure.kind = ModelKind::kRateDependentPi;
  c.structure.max_rate = s.max_rate;
  c.structure.rate_filter_s = 0.0;
  ActuatorModel m(std::make_unique<RateDependentPiModel>(
      RateDependentPiParameters{h.parameters(),
                                std::vector<double>(h.parameters().play.weights.size(), 0.0),
                                s.max_rate, 0.0, s.max_rate},
      r_.dt));
  finish_nested(c, std::move(m), mpi, " (rate-free: no rate law beat the modified PI it extends)");
  return c;
}

void Identifier::check_rpi_nesting(Candidate& best) {
  if (rpi_by_mpi_order_) {
    // The order search_rpi() preferred over the modified PI's, finished alike, must still win.
    progress(0.92, "checking the dead zones against the modified PI's order");
    Candidate other = std::move(*rpi_by_mpi_order_);
    rpi_by_mpi_order_.reset();
    finish(other);
    if (other.score() < best.score()) best = std::move(other);
  }
  // Nesting: the modified PI, refined and with creep as the RPI was, is a feasible RPI (zero
  // rate coefficients); the RPI returned is never worse on held-out data.
  progress(0.93, "checking the rate law against the modified PI it extends");
  Candidate mpi = search_mpi();
  finish(mpi);
  if (mpi.score() <= best.score()) {
    best = o_.kind ? nested_rpi(mpi, best.structure) : std::move(mpi);
  }
}

}  // namespace hystbench::compensation::details::identification
