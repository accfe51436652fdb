#include "diagnosis/details/report/verdict.hpp"

#include "diagnosis/details/number_text.hpp"
#include "diagnosis/details/report/reasons.hpp"

namespace hystbench::compensation::details::diagnosis {

std::string verdict_text(const Diagnosis& d, const Decision& decision,
                         const DiagnosisOptions& options, const std::string& unit) {
  const CandidateReport* best_any = decision.best_any;
  switch (decision.verdict_case()) {
    case VerdictCase::kAtNoiseFloor:
      return "none: the baseline's held-out rms error " + num(d.baseline_heldout.rmse) + " " +
             unit + " is at the noise floor (noise rms " + num(d.noise_rms) + " " + unit +
             "); there is nothing left to explain";
    case VerdictCase::kNothingEligible:
      return "none: no candidate lowers the held-out error by " + num(options.min_gain) +
             "x with a significant statistic (best: " + std::string(to_string(best_any->cause)) +
             ", gain " + num(best_any->gain) + (best_any->significant ? "" : ", not significant") +
             "); the baseline explains the data as far as these effects go";
    case VerdictCase::kBeyondTheShape: {
      const OnTopOfShape* beyond = decision.beyond;
      const CandidateReport& shape_report = *d.candidate(decision.shape);
      return std::string(to_string(beyond->cause)) + ": " + beyond->outcome.evidence + ". " +
             beyond->outcome.extension + ", on top of " + shape_name(decision.shape) + " (" +
             shape_report.extension + ", gain " + num(shape_report.gain) +
             "), lowers the held-out rms error from " + num(shape_report.heldout.rmse) + " to " +
             num(beyond->outcome.fit.heldout.rmse) + " " + unit + " (gain " + num(beyond->gain) +
             "; " + num(d.baseline_heldout.rmse / beyond->outcome.fit.heldout.rmse) +
             " over the baseline)";
    }
    case VerdictCase::kLargestGain:
      break;
  }
  const CandidateReport& w = *decision.eligible.front();
  std::string verdict = std::string(to_string(w.cause)) + ": " + w.evidence + ". " + w.extension +
                        " lowers the held-out rms error from " + num(d.baseline_heldout.rmse) +
                        " to " + num(w.heldout.rmse) + " " + unit + " (gain " + num(w.gain) + ")";
  if (!w.left_out.empty()) {
    verdict +=
        ", and carries over to every record left out whole (gain " + left_out_summary(w) + ")";
  }
  return verdict;
}

std::string also_named_text(const Diagnosis& d, Cause shape, const std::string& unit) {
  std::string text = ". Also named, each adding more than the noise allows (" +
                     num(d.noise_allowance_rms) + " " + unit + " rms) to the causes before it: ";
  for (std::size_t i = 1; i < d.causes.size(); ++i) {
    const NamedCause& n = d.causes[i];
    // The shape, last, is judged on top of the first cause alone.
    const std::string to = is_shape(n.cause) && i > 1
                               ? std::string(to_string(d.causes.front().cause))
                               : std::string("those");
    text += (i > 1 ? ", " : "") + std::string(to_string(n.cause)) + " (gain " + num(n.gain) +
            (n.against == shape_name(shape) ? " over the shape" : "") + ", " + num(n.added_gain) +
            " added to ";
    text += to;
    text += ", " + num(n.added_rms) + " " + unit + " rms)";
  }
  return text;
}

}  // namespace hystbench::compensation::details::diagnosis
