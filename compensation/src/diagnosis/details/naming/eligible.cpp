#include "diagnosis/details/naming/eligible.hpp"

#include <algorithm>
#include <string>

#include "diagnosis/details/report/reasons.hpp"

namespace hystbench::compensation::details::diagnosis {

std::vector<const CandidateReport*> eligible_candidates(Diagnosis& d, const Decision& decision,
                                                        const DiagnosisOptions& options) {
  std::vector<const CandidateReport*> eligible;
  for (CandidateReport& c : d.candidates) {
    const double gain = c.heldout.rmse > 0.0 ? decision.reference / c.heldout.rmse : 0.0;
    if (!c.significant) {
      c.not_named =
          "its statistic " + num(c.statistic) + " is below its threshold " + num(c.threshold);
    } else if (gain < options.min_gain) {
      c.not_named = "its held-out gain " + num(gain) + " is below " + num(options.min_gain);
    } else if (c.carries_over) {
      eligible.push_back(&c);
    } else {
      c.not_named =
          "it does not carry over to the records left out whole (gain " + left_out_summary(c) + ")";
      d.notes.push_back(std::string(to_string(c.cause)) + " does not carry over: it gains " +
                        num(c.gain) +
                        "x on the held-out blocks, but fitted on the other records it "
                        "predicts each record left out whole at gain " +
                        left_out_summary(c) + "; not named");
    }
    if (decision.at_floor) c.not_named = "the baseline's held-out error is at the noise floor";
  }
  std::sort(eligible.begin(), eligible.end(),
            [](const CandidateReport* a, const CandidateReport* b) { return a->gain > b->gain; });
  return eligible;
}

}  // namespace hystbench::compensation::details::diagnosis
