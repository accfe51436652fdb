#include "diagnosis/details/residual_profiles.hpp"

#include <algorithm>
#include <string>

namespace hystbench::compensation::details::diagnosis {

namespace {

// Bins of the residual profiles.
constexpr std::size_t kTimeBins = 32, kLevelBins = 24, kRateBins = 24, kSinceBins = 16;

}  // namespace

std::vector<double> residual_of(const details::DiagnosisRecord& r,
                                std::span<const double> prediction) {
  std::vector<double> e(r.n);
  for (std::size_t k = 0; k < r.n; ++k) e[k] = r.y[k] - prediction[k];
  return e;
}

std::vector<ResidualProfile> residual_profiles(const details::DiagnosisRecord& r,
                                               std::span<const double> e,
                                               const details::InputEvents& ev) {
  std::vector<ResidualProfile> out;
  std::vector<unsigned char> scored(r.n);
  for (std::size_t k = 0; k < r.n; ++k) scored[k] = r.part[k] != details::kSkippedPart;
  out.push_back(details::binned_profile("time", "time [s]", r.t, e, scored,
                                        details::linear_edges(r.t.front(), r.t.back(), kTimeBins)));
  out.push_back(details::binned_profile("input", "input [" + r.units.input + "]", r.u, e, scored,
                                        details::linear_edges(r.u_lo, r.u_hi, kLevelBins)));
  std::vector<double> direction(r.n);
  std::vector<unsigned char> moving(r.n), smooth(r.n), after(r.n);
  std::vector<double> signed_e(r.n);
  double longest = 0.0;
  for (std::size_t k = 0; k < r.n; ++k) {
    direction[k] = ev.direction[k];
    moving[k] = scored[k] && ev.direction[k] != 0;
    smooth[k] = moving[k] && !ev.step[k] && !(k + 1 < r.n && ev.step[k + 1]);
    after[k] = scored[k] && ev.last_move[k] != 0 && ev.since_event_s[k] > 0.0;
    signed_e[k] = e[k] * ev.last_move[k];
    if (after[k]) longest = std::max(longest, ev.since_event_s[k]);
  }
  out.push_back(details::binned_profile("direction", "direction (-1 falling, +1 rising)", direction,
                                        e, moving, {-1.5, 0.0, 1.5}));
  out.push_back(details::binned_profile("rate", "input rate [" + r.units.input + "/s]", ev.rate, e,
                                        smooth,
                                        details::quantile_edges(ev.rate, smooth, kRateBins)));
  const double first = r.dt;
  out.push_back(details::binned_profile(
      "since_event",
      "time since the last reversal or step [s] (residual signed by the last input change)",
      ev.since_event_s, signed_e, after,
      details::log_edges(first, std::max(2.0 * first, longest), kSinceBins)));
  return out;
}

}  // namespace hystbench::compensation::details::diagnosis
