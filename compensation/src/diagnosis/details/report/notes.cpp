#include "diagnosis/details/report/notes.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "diagnosis/details/number_text.hpp"
#include "diagnosis/details/reference.hpp"

namespace hystbench::compensation::details::diagnosis {

namespace {

constexpr double kOneLoopBand = 0.03;  // of the input span: a reversal this close is at the end

// Notes when every reversal of the input is at its extremes: the record shows one loop only.
void note_single_loop(Diagnosis& d, const details::DiagnosisRecord& r,
                      const details::InputEvents& ev) {
  const auto [lo, hi] = std::minmax_element(r.u.begin(), r.u.end());
  const double band = kOneLoopBand * (*hi - *lo);
  std::size_t reversals = 0, inner = 0;
  for (const std::size_t k : ev.event_samples) {
    if (ev.step[k]) continue;
    ++reversals;
    if (r.u[k] > *lo + band && r.u[k] < *hi - band) ++inner;
  }
  if (reversals >= 4 && inner == 0) {
    d.notes.push_back("every reversal of the input is at its extremes (" + num(*lo) + " and " +
                      num(*hi) + " " + r.units.input +
                      "): the record shows one loop and no minor loops, so a model fitted on "
                      "it may not hold for smaller loops or other excitations; check it on "
                      "another record (hystbench simulate, or diagnose --model)");
  }
}

}  // namespace

void note_unclean_verdict(Diagnosis& d, const Decision& decision, const DiagnosisOptions& options) {
  if (d.cause != Cause::kNone && !decision.beyond) {
    const CandidateReport& named = *d.candidate(d.cause);
    for (const CandidateReport& c : d.candidates) {
      if (!c.significant && c.gain > named.gain * 1.05 && c.gain >= options.min_gain) {
        d.notes.push_back("not clean: " + std::string(to_string(c.cause)) +
                          " lowers the held-out error more (gain " + num(c.gain) +
                          ") but its statistic is not significant (" + c.evidence + ")");
      }
    }
  }
  if (d.cause == Cause::kNone && !decision.at_floor) {
    const CandidateReport* best_any = decision.best_any;
    d.notes.push_back("not clean: the baseline's held-out error is " +
                      num(d.baseline_heldout.rmse / d.noise_rms) +
                      "x the noise, but no single candidate explains the rest (best gain " +
                      num(best_any->gain) + ", " + std::string(to_string(best_any->cause)) +
                      (best_any->significant ? "" : ", statistic not significant") + ")");
  }
}

void note_incoherent_output(Diagnosis& d, const details::DiagnosisRecord& r,
                            const std::string& unit) {
  double mean = 0.0, square = 0.0;
  for (const double v : r.y) mean += v, square += v * v;
  mean /= static_cast<double>(r.n);
  const double variance = square / static_cast<double>(r.n) - mean * mean;
  const double noise_share = variance > 0.0 ? d.noise_rms * d.noise_rms / variance : 0.0;
  // The incoherent power stays in the error of any model driven by this input alone (of any
  // linear filter of the prediction, exactly; of other models, about).
  const double floor_rms = std::sqrt(std::max(0.0, (1.0 - d.coherent_share) * variance));
  d.notes.push_back(
      "not clean: only " + num(100.0 * d.coherent_share) +
      " % of the output's power is coherent with this input's prediction, and noise makes " +
      num(100.0 * noise_share) +
      " %: the rest comes from something not in this record (another input driving this "
      "output, as in a multi-axis stage, or a disturbance), which no single-input model or "
      "candidate here explains; such a model could lower the error to about " +
      num(floor_rms) + " " + unit + " at best (gain " +
      num(floor_rms > 0.0 ? d.baseline_heldout.rmse / floor_rms : 0.0) +
      "); where the record holds the other inputs, name them all (--u-column u1,u2,...) and "
      "diagnose measures their coupling");
}

void note_record(Diagnosis& d, const details::DiagnosisRecord& r, const details::InputEvents& ev,
                 const DiagnosisOptions& options) {
  if (given_model_stale(d, options)) {
    d.notes.push_back(
        "the given model's parameters do not match this record: the same structure "
        "refitted here lowers the held-out error " +
        num(d.baseline_heldout.rmse / d.refit_heldout->rmse) +
        "x; candidates are tested on the refit's residual and named only for what "
        "they gain beyond that refit");
  }
  if (ev.hold_seconds < 0.5) {
    d.notes.push_back("the input never holds: creep and drift can only be seen indirectly");
  }
  note_single_loop(d, r, ev);
  if (ev.steps == 0) {
    d.notes.push_back(
        "no input steps: dynamics and delay show only through the fast parts of "
        "the excitation");
  }
}

void note_ambiguity(Diagnosis& d, const Decision& decision) {
  const std::vector<const CandidateReport*>& eligible = decision.eligible;
  for (std::size_t i = 1; i < eligible.size() && !decision.beyond; ++i) {
    if (!eligible[i]->named && eligible[i]->gain >= kAmbiguity * eligible.front()->gain) {
      d.notes.push_back("not clean: " + std::string(to_string(eligible[i]->cause)) +
                        " explains the data about as well (gain " + num(eligible[i]->gain) +
                        " against " + num(eligible.front()->gain) + ")");
    }
  }
}

}  // namespace hystbench::compensation::details::diagnosis
