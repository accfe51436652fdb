#include "diagnosis/details/candidate_reports.hpp"

#include <span>
#include <string>
#include <utility>

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
  std::vector<details::ExtensionFit> fits;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const Cause c = candidates[i];
    report(options, 0.25 + 0.7 * static_cast<double>(i) / candidates.size(),
           "testing " + std::string(to_string(c)));
    details::CandidateOutcome o = test_of(c)(ctx);
    fits.push_back(o.fit);
    CandidateReport rep;
    rep.cause = c;
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
