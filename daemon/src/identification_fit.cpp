#include "hystbench/daemon/identification_fit.hpp"

#include <algorithm>
#include <limits>

namespace hystbench::daemon {

namespace hc = hystbench::compensation;

namespace {
/// Held-out rms error, or the fit's without a held-out part.
double score(const hc::FitResult& f) { return f.heldout.samples > 0 ? f.heldout.rmse : f.fit.rmse; }
}  // namespace

AveragedRecord block_average(std::span<const double> u, std::span<const double> y, double dt_s,
                             std::size_t block, std::size_t shift) {
  AveragedRecord r;
  block = std::max<std::size_t>(1, block);
  const std::size_t n =
      std::min(u.size(), y.size()) > shift ? std::min(u.size(), y.size()) - shift : 0;
  r.t.reserve(n / block);
  r.u.reserve(n / block);
  r.y.reserve(n / block);
  for (std::size_t k = 0; k + block <= n; k += block) {
    double su = 0.0, sy = 0.0;
    for (std::size_t j = 0; j < block; ++j) {
      su += u[k + j];
      sy += y[k + j + shift];
    }
    r.t.push_back(static_cast<double>(r.t.size() * block) * dt_s);
    r.u.push_back(su / static_cast<double>(block));
    r.y.push_back(sy / static_cast<double>(block));
  }
  return r;
}

IdentificationFit fit_identification_record(std::span<const double> u, std::span<const double> y,
                                            double dt_s, std::size_t block, hc::FitOptions options,
                                            int max_delay_ticks) {
  options.delay_samples = 0;
  const AveragedRecord r0 = block_average(u, y, dt_s, block, 0);
  IdentificationFit out;
  out.fit = hc::fit_model(r0.t, r0.u, r0.y, options);
  if (max_delay_ticks <= 0) return out;

  // Score each delay with the order and family found without one: one least-squares fit each.
  hc::FitOptions quick = options;
  quick.kind = out.fit.model.hysteresis().kind();
  quick.operators = out.fit.operators;
  quick.dead_zones = out.fit.dead_zones;
  quick.refine_thresholds = false;
  quick.progress = nullptr;
  int best = 0;
  double best_rmse = std::numeric_limits<double>::infinity();
  for (int d = 0; d <= max_delay_ticks; ++d) {
    const AveragedRecord rd = block_average(u, y, dt_s, block, static_cast<std::size_t>(d));
    double rmse = std::numeric_limits<double>::infinity();
    try {
      rmse = score(hc::fit_model(rd.t, rd.u, rd.y, quick));
    } catch (const std::invalid_argument&) {
      // Too short once shifted: this delay cannot be scored.
    }
    out.delay_heldout_rmse.push_back(rmse);
    if (rmse < best_rmse) {
      best_rmse = rmse;
      best = d;
    }
  }
  if (best == 0) return out;
  const AveragedRecord rd = block_average(u, y, dt_s, block, static_cast<std::size_t>(best));
  hc::FitResult delayed = hc::fit_model(rd.t, rd.u, rd.y, options);
  if (!(score(delayed) < score(out.fit))) return out;
  delayed.model.set_delay(static_cast<double>(best) * dt_s);
  delayed.delay_samples = best;
  out.fit = std::move(delayed);
  out.delay_ticks = best;
  return out;
}

}  // namespace hystbench::daemon
