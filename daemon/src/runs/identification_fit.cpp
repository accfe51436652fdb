#include "hystbench/daemon/runs/identification_fit.hpp"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <limits>
#include <string>

namespace hystbench::daemon {

namespace hc = hystbench::compensation;

namespace {
// The modified PI that scores the delays for a Preisach fit.
constexpr int kQuickPlays = 12;
constexpr int kQuickDeadZones = 2;
/// Held-out rms error, or the fit's without a held-out part.
double score(const hc::FitResult& f) { return f.heldout.samples > 0 ? f.heldout.rmse : f.fit.rmse; }
}  // namespace

bool delayed_fit_is_better(const hc::FitResult& without, const hc::FitResult& with) {
  return score(with) < score(without) && with.fit.rmse < without.fit.rmse;
}

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

std::vector<double> align_to_outputs(std::span<const double> u, std::span<const double> y,
                                     std::span<const std::uint32_t> response) {
  const std::size_t n = std::min({u.size(), y.size(), response.size()});
  std::vector<double> out(y.begin(), y.end());
  std::vector<char> known(n, 0);
  for (std::size_t k = 0; k < n; ++k) {
    if (response[k] == kNoAnswer || response[k] > k) continue;
    out[k - response[k]] = y[k];  // a later reading of the same output wins: it is newer
    known[k - response[k]] = 1;
  }
  std::size_t prev = n;  // the last answered index; n = none yet
  std::size_t next = 0;  // the next answered index at or after k; n = none
  for (std::size_t k = 0; k < n; ++k) {
    if (known[k]) {
      prev = k;
      continue;
    }
    if (next <= k) {
      next = k + 1;
      while (next < n && !known[next]) ++next;
    }
    if (prev == n && next == n) return std::vector<double>(y.begin(), y.end());
    if (prev == n) {
      out[k] = out[next];
    } else if (next == n) {
      out[k] = out[prev];
    } else {
      const double du = u[next] - u[prev];
      const double f = du != 0.0 ? std::clamp((u[k] - u[prev]) / du, 0.0, 1.0) : 0.5;
      out[k] = out[prev] + f * (out[next] - out[prev]);
    }
  }
  return out;
}

int median_response_ticks(std::span<const std::uint32_t> response) {
  std::vector<std::uint32_t> fresh;
  for (const std::uint32_t r : response) {
    if (r != kNoAnswer) fresh.push_back(r);
  }
  if (fresh.empty()) return 0;
  const auto mid = fresh.begin() + static_cast<std::ptrdiff_t>(fresh.size() / 2);
  std::nth_element(fresh.begin(), mid, fresh.end());
  return static_cast<int>(*mid);
}

IdentificationFit fit_identification_record(std::span<const double> u, std::span<const double> y,
                                            std::span<const std::uint32_t> response, double dt_s,
                                            std::size_t block, hc::FitOptions options,
                                            int max_delay_ticks) {
  IdentificationFit out;
  std::vector<double> aligned;
  if (!response.empty()) {
    aligned = align_to_outputs(u, y, response);
    y = std::span<const double>(aligned.data(), std::min(aligned.size(), y.size()));
    out.exchange_ticks = median_response_ticks(response);
  }
  options.delay_samples = 0;
  const AveragedRecord r0 = block_average(u, y, dt_s, block, 0);
  out.fit = hc::fit_model(r0.t, r0.u, r0.y, options);
  const auto finish = [&](int fitted) {
    out.delay_ticks = out.exchange_ticks + fitted;
    out.fit.delay_samples = out.delay_ticks;
    out.fit.model.set_delay(static_cast<double>(out.delay_ticks) * dt_s);
    return out;
  };
  if (max_delay_ticks <= 0) return finish(0);

  // Score each delay with the order and family found without one: one least-squares fit each.
  hc::FitOptions quick = options;
  quick.kind = out.fit.model.hysteresis().kind();
  quick.operators = out.fit.operators;
  quick.dead_zones = out.fit.dead_zones;
  if (quick.kind == hc::ModelKind::kPreisach) {
    // A delay shows as well in a mid-size modified PI, whose fit is a tenth of the plane's.
    quick.kind = hc::ModelKind::kModifiedPi;
    quick.operators = kQuickPlays;
    quick.dead_zones = kQuickDeadZones;
  }
  quick.refine_thresholds = false;
  quick.creep = false;  // the delay is a matter of samples; creep of seconds
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
  if (best == 0) {
    out.delay_note = "no further delay: none scored a lower held-out error";
    return finish(0);
  }
  const AveragedRecord rd = block_average(u, y, dt_s, block, static_cast<std::size_t>(best));
  if (out.fit.model.hysteresis().kind() == hc::ModelKind::kPreisach) {
    // The plane's rate law as found without the delay, refitted at it: a few samples of delay
    // hardly move the rates, and the law's search is most of the plane's fit.
    options.preisach_given_rate_law = out.fit.model.hysteresis().thresholds_law();
  }
  hc::FitResult delayed = hc::fit_model(rd.t, rd.u, rd.y, options);
  const std::string figures =
      fmt::format(" (held-out {:.4g} vs {:.4g}, fit part {:.4g} vs {:.4g} um)", score(delayed),
                  score(out.fit), delayed.fit.rmse, out.fit.fit.rmse);
  if (!delayed_fit_is_better(out.fit, delayed)) {
    out.delay_note = "no further delay: the full fit at " + std::to_string(best) +
                     " ticks was not better on both held-out and fit part" + figures;
    return finish(0);
  }
  out.delay_note =
      std::to_string(best) + " further ticks: lower held-out and fit-part error" + figures;
  out.fit = std::move(delayed);
  return finish(best);
}

}  // namespace hystbench::daemon
