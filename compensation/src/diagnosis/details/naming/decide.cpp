#include "diagnosis/details/naming/decide.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "diagnosis/details/naming/decision.hpp"
#include "diagnosis/details/naming/eligible.hpp"
#include "diagnosis/details/naming/name_causes.hpp"
#include "diagnosis/details/naming/on_shape.hpp"
#include "diagnosis/details/naming/rules.hpp"
#include "diagnosis/details/progress.hpp"
#include "diagnosis/details/report/notes.hpp"
#include "diagnosis/details/report/verdict.hpp"

namespace hystbench::compensation::details::diagnosis {

namespace {

// Below this share of the output's power coherent with the prediction (and above the noise
// floor), something not in the record drives the output: noted.
constexpr double kMinCoherentShare = 0.5;

// The decision up to the first cause: the reference the gains are judged against, the noise
// floor and allowance, the eligible candidates in the order the eligible-order rules leave, the
// other causes on top of the shape, and the largest gain of all.
void weigh_candidates(Diagnosis& d, Decision& decision, const DecisionInputs& in,
                      const DiagnosisOptions& options) {
  decision.reference = d.baseline_heldout.rmse;
  if (d.refit_heldout) decision.reference = std::min(decision.reference, d.refit_heldout->rmse);
  const double floor = options.noise_floor_factor * d.noise_rms;
  decision.at_floor = d.baseline_heldout.rmse <= floor;
  d.noise_allowance_rms =
      std::sqrt(options.noise_floor_factor * options.noise_floor_factor - 1.0) * d.noise_rms;
  decision.eligible = eligible_candidates(d, decision, options);
  apply_eligible_order_rules(d, decision, {in.r, in.ev});
  test_on_shape(d, in.r, in.fits, in.ev, options, decision);
  decision.best_any = &*std::max_element(
      d.candidates.begin(), d.candidates.end(),
      [](const CandidateReport& a, const CandidateReport& b) { return a.gain < b.gain; });
}

}  // namespace

void decide(Diagnosis& d, const DecisionInputs& in, const DiagnosisOptions& options) {
  report(options, 0.95, "deciding");
  Decision decision;
  weigh_candidates(d, decision, in, options);
  const std::string unit = in.r.units.output;
  d.cause = decision.named_cause();
  d.verdict = verdict_text(d, decision, options, unit);
  note_unclean_verdict(d, decision, options);
  if (!decision.at_floor && d.coherent_share < kMinCoherentShare) {
    note_incoherent_output(d, in.r, unit);
  }
  note_record(d, in.r, in.ev, options);

  if (d.cause == Cause::kNone) {
    extend_by_nothing(d);
    return;
  }
  const std::string reference_name = decision.reference < d.baseline_heldout.rmse
                                         ? "the given model refitted here"
                                         : "the baseline";
  name_causes_and_extend(d, {in.r, in.fits, in.ev, in.ref.profiles, in.ref.response, options,
                             decision.reference, reference_name, decision.on_shape, decision.beyond,
                             in.reference_delay_samples, decision.shape});
  if (d.causes.size() > 1) d.verdict += also_named_text(d, decision.shape, unit);
  note_ambiguity(d, decision);
}

}  // namespace hystbench::compensation::details::diagnosis
