#include "diagnosis/details/naming/on_shape.hpp"

#include <algorithm>
#include <exception>
#include <optional>
#include <string>
#include <utility>

#include "details/parallel_tasks.hpp"
#include "diagnosis/details/cancel_point.hpp"
#include "diagnosis/details/candidate_reports.hpp"
#include "diagnosis/details/naming/rules.hpp"
#include "diagnosis/details/progress.hpp"
#include "diagnosis/details/residual_profiles.hpp"

namespace hystbench::compensation::details::diagnosis {

namespace {

/// Every other candidate that carries over (the other shape aside), tested again with the shape
/// extension's fit as its baseline (its statistic read from that fit's residual), on the options'
/// threads, in candidate order; a candidate the designs cannot fit together with the shape is left
/// out.
std::vector<OnTopOfShape> beyond_shape(const Diagnosis& d, const details::DiagnosisRecord& r,
                                       const std::vector<details::ExtensionFit>& fits,
                                       const details::InputEvents& ev, Cause shape_cause,
                                       const DiagnosisOptions& options,
                                       std::vector<std::string>& notes) {
  std::size_t shape = 0;
  while (d.candidates[shape].cause != shape_cause) ++shape;
  const details::ExtensionFit& base = fits[shape];
  const std::vector<double> residual = residual_of(r, base.prediction);
  const std::vector<ResidualProfile> profiles = residual_profiles(r, residual, ev);
  const FrequencyResponse response =
      details::frequency_response(base.prediction, r.y, r.dt, d.noise_rms);
  const details::CandidateContext ctx{r,  base.spec, base,     base.prediction, residual,
                                      ev, profiles,  response, d.noise_rms};
  std::vector<Cause> causes;
  for (const CandidateReport& c : d.candidates) {
    if (!is_shape(c.cause) && c.carries_over) causes.push_back(c.cause);
  }
  // Each test reads the context alone: side by side, in candidate order (DiagnosisThreads.*).
  std::vector<std::optional<details::CandidateOutcome>> outcomes(causes.size());
  details::run_parallel(
      causes.size(),
      [&](std::size_t i) {
        const CancelScope cancellable(options);
        try {
          outcomes[i] = test_of(causes[i])(ctx);
        } catch (const DiagnosisCancelled&) {
          throw;
        } catch (const std::exception&) {
          // A combination the designs cannot fit is left out.
        }
      },
      options.threads);
  std::vector<OnTopOfShape> out;
  std::string tried;
  for (std::size_t i = 0; i < causes.size(); ++i) {
    if (!outcomes[i] || !(outcomes[i]->fit.heldout.rmse > 0.0)) continue;
    details::CandidateOutcome& o = *outcomes[i];
    const double gain = base.heldout.rmse / o.fit.heldout.rmse;
    const bool significant = o.statistic >= o.threshold;
    tried += std::string(tried.empty() ? "" : ", ") + std::string(to_string(causes[i])) + " " +
             num(gain) + (significant ? "" : " (not significant)");
    out.push_back(OnTopOfShape{causes[i], std::move(o), gain, significant});
  }
  if (!tried.empty()) {
    notes.push_back("on top of " + shape_name(shape_cause) + ", the other causes gain: " + tried);
  }
  return out;
}

}  // namespace

void test_on_shape(Diagnosis& d, const details::DiagnosisRecord& r,
                   const std::vector<details::ExtensionFit>& fits, const details::InputEvents& ev,
                   const DiagnosisOptions& options, Decision& decision) {
  const auto shape = std::find_if(decision.eligible.begin(), decision.eligible.end(),
                                  [](const CandidateReport* c) { return is_shape(c->cause); });
  if (shape == decision.eligible.end() || decision.at_floor) return;
  decision.shape = (*shape)->cause;
  report(options, 0.955, "testing the other causes on top of the loop's shape");
  decision.on_shape = beyond_shape(d, r, fits, ev, decision.shape, options, d.notes);
  for (const OnTopOfShape& o : decision.on_shape) {
    if (o.counts(options) &&
        (!decision.beyond ||
         ranks_before(o.cause, o.gain, decision.beyond->cause, decision.beyond->gain))) {
      decision.beyond = &o;
    }
  }
}

}  // namespace hystbench::compensation::details::diagnosis
