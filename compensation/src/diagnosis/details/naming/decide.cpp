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
#include "diagnosis/details/report/reasons.hpp"

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
  prefer_the_plays_shape(d, decision);
  order_rate_and_delay(d, decision, in.r, in.ev);
  test_on_shape(d, in.r, in.fits, in.ev, options, decision);
  decision.best_any = &*std::max_element(
      d.candidates.begin(), d.candidates.end(),
      [](const CandidateReport& a, const CandidateReport& b) { return a.gain < b.gain; });
}

// d.cause and the verdict: none at the noise floor or without an eligible candidate, else the
// cause named beyond the shape, else the eligible one of the largest gain.
void decide_cause(Diagnosis& d, const Decision& decision, const DiagnosisOptions& options,
                  const std::string& unit) {
  const CandidateReport* best_any = decision.best_any;
  if (decision.at_floor) {
    d.cause = Cause::kNone;
    d.verdict = "none: the baseline's held-out rms error " + num(d.baseline_heldout.rmse) + " " +
                unit + " is at the noise floor (noise rms " + num(d.noise_rms) + " " + unit +
                "); there is nothing left to explain";
  } else if (decision.eligible.empty()) {
    d.cause = Cause::kNone;
    d.verdict = "none: no candidate lowers the held-out error by " + num(options.min_gain) +
                "x with a significant statistic (best: " + std::string(to_string(best_any->cause)) +
                ", gain " + num(best_any->gain) +
                (best_any->significant ? "" : ", not significant") +
                "); the baseline explains the data as far as these effects go";
  } else if (decision.beyond) {
    const OnTopOfShape* beyond = decision.beyond;
    const CandidateReport& shape_report = *d.candidate(decision.shape);
    d.cause = beyond->cause;
    d.verdict = std::string(to_string(beyond->cause)) + ": " + beyond->outcome.evidence + ". " +
                beyond->outcome.extension + ", on top of " + shape_name(decision.shape) + " (" +
                shape_report.extension + ", gain " + num(shape_report.gain) +
                "), lowers the held-out rms error from " + num(shape_report.heldout.rmse) + " to " +
                num(beyond->outcome.fit.heldout.rmse) + " " + unit + " (gain " + num(beyond->gain) +
                "; " + num(d.baseline_heldout.rmse / beyond->outcome.fit.heldout.rmse) +
                " over the baseline)";
  } else {
    const CandidateReport& w = *decision.eligible.front();
    d.cause = w.cause;
    d.verdict = std::string(to_string(w.cause)) + ": " + w.evidence + ". " + w.extension +
                " lowers the held-out rms error from " + num(d.baseline_heldout.rmse) + " to " +
                num(w.heldout.rmse) + " " + unit + " (gain " + num(w.gain) + ")";
    if (!w.left_out.empty()) {
      d.verdict +=
          ", and carries over to every record left out whole (gain " + left_out_summary(w) + ")";
    }
  }
}

}  // namespace

void decide(Diagnosis& d, const DecisionInputs& in, const DiagnosisOptions& options) {
  report(options, 0.95, "deciding");
  Decision decision;
  weigh_candidates(d, decision, in, options);
  const std::string unit = in.r.units.output;
  decide_cause(d, decision, options, unit);
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
  note_ambiguity(d, decision);
}

}  // namespace hystbench::compensation::details::diagnosis
