#include "diagnosis/details/naming/rules.hpp"

#include <algorithm>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "diagnosis/details/after_reversals.hpp"
#include "diagnosis/details/residual_profiles.hpp"

namespace hystbench::compensation::details::diagnosis {

namespace {

// Fewest held-out samples after the input's reversals that can tell a delay from a rate law.
constexpr std::size_t kMinReversalSamples = 10;

}  // namespace

bool ranks_before(Cause a, double gain_a, Cause b, double gain_b) {
  for (const Cause later : {Cause::kDrift, Cause::kRateDependence}) {
    if (a == Cause::kCreep && b == later) return true;
    if (a == later && b == Cause::kCreep) return false;
  }
  return gain_a > gain_b;
}

double retest_statistic(Cause cause, const details::CandidateContext& c) {
  if (cause == Cause::kAsymmetry) return c.profile("input").explained;
  return cause == Cause::kCreep ? details::creep_statistic(c) : c.profile("time").explained;
}

void prefer_the_plays_shape(Diagnosis& d, Decision& decision) {
  if (!plane_outdone(d)) return;
  auto& eligible = decision.eligible;
  const auto plane = std::find_if(eligible.begin(), eligible.end(), [](const CandidateReport* r) {
    return r->cause == Cause::kLoopShape;
  });
  if (plane == eligible.end()) return;
  CandidateReport& c = d.candidates[index_of(d, Cause::kLoopShape)];
  c.not_named = "the play family's own shape (asymmetry, held-out rms " +
                num(d.candidate(Cause::kAsymmetry)->heldout.rmse) +
                ") holds the loop about as well (" + num(c.heldout.rmse) +
                "); the plane must gain " + num(kPlaneOverPlays) + "x over it";
  eligible.erase(plane);
}

void order_rate_and_delay(Diagnosis& d, Decision& decision, const details::DiagnosisRecord& r,
                          const details::InputEvents& ev) {
  std::vector<const CandidateReport*>& eligible = decision.eligible;
  if (eligible.size() < 2 || eligible[0]->cause != Cause::kRateDependence ||
      eligible[1]->cause != Cause::kDelay || eligible[1]->gain < kAmbiguity * eligible[0]->gain) {
    return;
  }
  const CandidateReport& law = *eligible[0];
  const CandidateReport& delay = *eligible[1];
  const std::size_t window = std::max<std::size_t>(1, delay.model.delay_samples());
  const details::WindowError law_error =
      details::after_reversals_error(r, ev, law.prediction, window);
  const details::WindowError delay_error =
      details::after_reversals_error(r, ev, delay.prediction, window);
  if (law_error.samples < kMinReversalSamples) return;
  const bool delay_first =
      delay_error.rms < law_error.rms &&
      quadrature_difference(law_error.rms, delay_error.rms) >= d.noise_allowance_rms;
  const std::string unit = r.units.output;
  d.notes.push_back(
      "rate_dependence and delay gain about as much (" + num(law.gain) + " and " + num(delay.gain) +
      "); they differ after the input's reversals, where a delay carries the "
      "output on in the old direction and a rate law holds it: over the " +
      std::to_string(window) + (window == 1 ? " sample" : " samples") + " after each (" +
      std::to_string(law_error.samples) + " held out), the delay predicts them to " +
      num(delay_error.rms) + " " + unit + " rms, the rate law to " + num(law_error.rms) + " " +
      unit + (delay_first ? ": the delay is named first" : ": the rate law stays first"));
  if (delay_first) std::swap(eligible[0], eligible[1]);
}

void find_delay_again(const Diagnosis& d, const Naming& x, Joint& joint) {
  const std::vector<double> residual = residual_of(x.r, joint.fit.prediction);
  try {
    details::CandidateOutcome o = details::test_delay(on_joint(d, x, joint, residual, x.profiles));
    if (o.statistic < o.threshold || !(o.fit.heldout.rmse < joint.fit.heldout.rmse)) return;
    joint.fit = std::move(o.fit);
    joint.added.push_back(o.extension + ", found again on top of the loop's shape");
  } catch (const std::exception&) {
    // The delay found first stays.
  }
}

}  // namespace hystbench::compensation::details::diagnosis
