#include "diagnosis/details/candidate_reports.hpp"

#include <mutex>
#include <span>
#include <string>
#include <utility>

#include "details/parallel_tasks.hpp"
#include "diagnosis/details/cancel_point.hpp"
#include "diagnosis/details/progress.hpp"

namespace hystbench::compensation::details::diagnosis {

TestFunction test_of(Cause c) {
  switch (c) {
    case Cause::kAsymmetry:
      return details::test_asymmetry;
    case Cause::kLoopShape:
      return details::test_loop_shape;
    case Cause::kRateDependence:
      return details::test_rate_dependence;
    case Cause::kCreep:
      return details::test_creep;
    case Cause::kDynamics:
      return details::test_dynamics;
    case Cause::kDelay:
      return details::test_delay;
    case Cause::kDrift:
      return details::test_drift;
    case Cause::kNone:
      break;
  }
  return nullptr;
}

std::vector<details::ExtensionFit> test_candidates(Diagnosis& d,
                                                   const details::CandidateContext& ctx,
                                                   const DiagnosisOptions& options) {
  const std::span<const Cause> candidates = candidate_causes();
  // Each test reads the context alone: run side by side, their outcomes are the same as one after
  // another (DiagnosisThreads.*), and are reported in candidate order.
  std::vector<details::CandidateOutcome> outcomes(candidates.size());
  std::mutex progress_mutex;
  std::size_t started = 0;
  details::run_parallel(
      candidates.size(),
      [&](std::size_t i) {
        const CancelScope cancellable(options);
        {
          const std::lock_guard lock(progress_mutex);
          report(options, 0.25 + 0.7 * static_cast<double>(started++) / candidates.size(),
                 "testing " + std::string(to_string(candidates[i])));
        }
        outcomes[i] = test_of(candidates[i])(ctx);
      },
      options.threads);
  std::vector<details::ExtensionFit> fits;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    details::CandidateOutcome& o = outcomes[i];
    fits.push_back(o.fit);
    CandidateReport rep;
    rep.cause = candidates[i];
    rep.statistic = o.statistic;
    rep.threshold = o.threshold;
    rep.significant = o.statistic >= o.threshold;
    rep.evidence = std::move(o.evidence);
    rep.extension = std::move(o.extension);
    rep.model = std::move(o.fit.model);
    rep.fit = o.fit.fit;
    rep.heldout = o.fit.heldout;
    rep.gain = rep.heldout.rmse > 0.0 ? d.baseline_heldout.rmse / rep.heldout.rmse : 0.0;
    rep.drift = std::move(o.fit.drift);
    rep.prediction = std::move(o.fit.prediction);
    d.candidates.push_back(std::move(rep));
  }
  return fits;
}

}  // namespace hystbench::compensation::details::diagnosis
