// Candidate `drift`: a slow change of the output that the input does not explain. Statistic:
// share of the baseline residual variance explained by time (32 equal bins). Extension: the
// baseline structure fitted together with a drift piecewise linear in time (a knot every
// held-out period, 1/8 of the record by default, so every held-out block lies between two
// knots fitted on its neighbours and the drift cannot follow the input's slow structure). The drift
// is not extrapolated: the extended model is the hysteresis fitted with the drift removed; the
// held-out error includes the drift interpolated across the held-out blocks.
#include <algorithm>
#include <cmath>

#include "diagnosis/details/candidates.hpp"

namespace hystbench::compensation::details {

namespace {

constexpr double kDriftThreshold = 0.2;

}  // namespace

CandidateOutcome test_drift(const CandidateContext& c) {
  CandidateOutcome out;
  const DiagnosisRecord& r = c.record;
  const ResidualProfile& time = c.profile("time");
  out.statistic = time.explained;
  out.threshold = kDriftThreshold;

  ExtensionSpec spec = c.base;
  spec.drift = true;
  out.fit = fit_extension(r, spec);
  const auto [lo, hi] = std::minmax_element(out.fit.drift.begin(), out.fit.drift.end());
  out.evidence = "time explains " + percent(time.explained) +
                 " of the residual variance; the fitted drift spans " + num(*hi - *lo) + " " +
                 r.units.output + " over " + num(r.duration()) + " s";
  out.extension = "drift removed from the fit: piecewise linear, knots every " +
                  num(static_cast<double>(r.drift_knot_samples()) * r.dt) +
                  " s (not extrapolated; the saved model has no drift)";
  return out;
}

}  // namespace hystbench::compensation::details
