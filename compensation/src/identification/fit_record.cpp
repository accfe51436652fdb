#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "details/identification_record.hpp"
#include "details/record_startup.hpp"
#include "details/validate.hpp"

namespace hystbench::compensation::details::identification {

namespace {

// Fewest fitted samples left after the skipped start and the held-out part.
constexpr std::size_t kMinFitRows = 20;

}  // namespace

void Record::set_delay(int d) {
  delay = d;
  ud.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    ud[k] = k >= static_cast<std::size_t>(d) ? u[k - static_cast<std::size_t>(d)] : u[0];
  }
  // Over the skipped start too: it is simulated, and its extremes set the plays' states.
  const auto [ulo, uhi] = std::minmax_element(ud.begin(), ud.begin() + fit_end);
  u_lo = *ulo, u_hi = *uhi;
}

Record make_record(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                   const FitOptions& o) {
  Record r;
  r.t = t, r.u = u, r.y = y;
  r.n = u.size();
  r.dt = (t.back() - t.front()) / static_cast<double>(r.n - 1);
  const auto heldout = static_cast<std::size_t>(std::floor(o.heldout_fraction * r.n));
  r.fit_end = r.n - heldout;
  r.begin = o.skip_samples ? *o.skip_samples
                           : details::startup_samples(u.first(r.fit_end), r.fit_end / 4);
  details::require(r.begin + kMinFitRows <= r.fit_end,
                   "too few samples left to fit: " + std::to_string(r.n) + " samples minus " +
                       std::to_string(r.begin) + " skipped and " + std::to_string(heldout) +
                       " held out leaves fewer than " + std::to_string(kMinFitRows));
  const auto [ylo, yhi] = std::minmax_element(y.begin() + r.begin, y.begin() + r.fit_end);
  r.y_lo = *ylo, r.y_hi = *yhi;
  r.drift_t0_s = 0.5 * static_cast<double>(r.begin + r.fit_end) * r.dt;
  details::require(r.y_hi > r.y_lo, "output y is constant over the fitted part (" + fmt(r.y_lo) +
                                        "): nothing to identify");
  r.set_delay(0);
  details::require(r.u_hi > r.u_lo, "input u is constant over the fitted part (" + fmt(r.u_lo) +
                                        "): a constant input does not excite any hysteresis");
  return r;
}

void score(Candidate& c, const Record& r) {
  const Invertibility inv = c.model->hysteresis().invertibility();
  if (!inv.invertible) {
    c.fit.rmse = c.heldout.rmse = std::numeric_limits<double>::infinity();
    c.method += " (rejected, not invertible: " + inv.reason + ")";
    return;
  }
  std::vector<double> yhat = c.model->simulate(r.ud, r.dt);
  details::add_drift(c.structure, c.drift, yhat);
  const auto y = r.y;
  c.fit = error_stats(y.subspan(r.begin, r.fit_end - r.begin),
                      std::span(yhat).subspan(r.begin, r.fit_end - r.begin));
  c.heldout = error_stats(y.subspan(r.fit_end), std::span(yhat).subspan(r.fit_end));
}

}  // namespace hystbench::compensation::details::identification
