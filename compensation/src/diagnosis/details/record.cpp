#include "diagnosis/details/record.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>

#include "details/diagnosis_signals.hpp"
#include "details/record_startup.hpp"
#include "details/validate.hpp"

namespace hystbench::compensation::details {

namespace {

constexpr std::size_t kMinSamples = 400;
constexpr std::size_t kMaxSearchRows = 60000;

}  // namespace

DataSplit make_split(std::span<const double> u, int blocks, int heldout_every) {
  const std::size_t n = u.size();
  const auto nb = static_cast<std::size_t>(blocks);
  const auto every = static_cast<std::size_t>(heldout_every);
  const std::size_t len = n / nb;
  auto begin_of = [&](std::size_t b) { return b * len; };
  auto end_of = [&](std::size_t b) { return b + 1 == nb ? n : (b + 1) * len; };

  // Steps per block: effects that show only right after sharp input changes (ringing, a delay
  // at a step) are invisible to a held-out part without steps.
  std::vector<std::size_t> steps_in(nb, 0);
  std::size_t steps = 0;
  for (const std::size_t k : find_steps(u)) {
    ++steps_in[std::min(nb - 1, k / len)];
    ++steps;
  }
  std::vector<unsigned char> held(nb, 0);
  for (std::size_t b = 0; b < nb; ++b) held[b] = b % every == every / 2;
  // Aim at a fair share of the steps in the held-out part (at least one when there are two or
  // more, never more than half) by moving held-out blocks by one position.
  const std::size_t target =
      steps >= 2 ? std::min(steps / 2, std::max<std::size_t>(1, (steps + every / 2) / every)) : 0;
  std::size_t held_steps = 0;
  for (std::size_t b = 0; b < nb; ++b) held_steps += held[b] ? steps_in[b] : 0;
  auto free_slot = [&](std::size_t from, std::size_t to) {
    if (to == 0 || to >= nb || held[to]) return false;
    for (const std::size_t m : {to - 1, to + 1}) {
      if (m != from && m < nb && held[m]) return false;
    }
    return true;
  };
  for (std::size_t b = 0; b < nb && held_steps < target; ++b) {
    if (!held[b] || steps_in[b] > 0) continue;
    for (const std::size_t to : {b - 1, b + 1}) {
      if (b == 0 || !free_slot(b, to) || steps_in[to] == 0) continue;
      if (held_steps + steps_in[to] > steps / 2) continue;
      held[b] = 0, held[to] = 1;
      held_steps += steps_in[to];
      break;
    }
  }
  DataSplit s;
  s.samples = n;
  s.blocks = nb;
  for (std::size_t b = 0; b < nb; ++b) {
    if (!held[b]) continue;
    s.heldout.emplace_back(begin_of(b), end_of(b));
    s.heldout_samples += end_of(b) - begin_of(b);
  }
  s.fit_samples = n - s.heldout_samples;
  return s;
}

DiagnosisRecord make_diagnosis_record(std::span<const double> t, std::span<const double> u,
                                      std::span<const double> y, const DiagnosisOptions& o,
                                      std::span<const std::size_t> record_starts) {
  require(t.size() == u.size() && u.size() == y.size(),
          "t, u and y must have the same length (t: " + std::to_string(t.size()) +
              ", u: " + std::to_string(u.size()) + ", y: " + std::to_string(y.size()) + ")");
  require(u.size() >= kMinSamples, "too few samples: the diagnosis needs at least " +
                                       std::to_string(kMinSamples) +
                                       " (it fits on three quarters and scores on the rest), got " +
                                       std::to_string(u.size()));
  require(o.blocks >= 4 && o.blocks <= 64, "options.blocks must be in [4, 64]");
  require(o.heldout_every >= 2 && o.heldout_every <= o.blocks / 2,
          "options.heldout_every must be in [2, blocks / 2]");
  require(std::isfinite(o.min_gain) && o.min_gain > 1.0, "options.min_gain must be > 1");
  require(std::isfinite(o.noise_floor_factor) && o.noise_floor_factor >= 1.0,
          "options.noise_floor_factor must be >= 1");
  require_record(t, u, y);
  DiagnosisRecord r;
  r.t = t, r.u = u, r.y = y;
  r.n = u.size();
  r.dt = (t.back() - t.front()) / static_cast<double>(r.n - 1);
  r.units = o.units;
  const auto [ulo, uhi] = std::minmax_element(u.begin(), u.end());
  r.u_lo = *ulo, r.u_hi = *uhi;
  r.split = make_split(u, o.blocks, o.heldout_every);
  r.heldout_every = static_cast<std::size_t>(o.heldout_every);
  r.part.assign(r.n, kFitPart);
  for (const auto& [b, e] : r.split.heldout) {
    std::fill(r.part.begin() + static_cast<std::ptrdiff_t>(b),
              r.part.begin() + static_cast<std::ptrdiff_t>(e), kHeldoutPart);
  }
  std::vector<std::size_t> starts{0};
  for (const std::size_t s : record_starts) {
    if (s > starts.back() && s < r.n) starts.push_back(s);
  }
  r.split.records = starts.size();
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const std::size_t end = i + 1 < starts.size() ? starts[i + 1] : r.n;
    // Until the input has reached both its extremes the state of the device depends on a
    // history the record does not hold (a bench's identify record settles and preconditions
    // first): neither fitted nor scored, up to a quarter of the record, as identification does.
    const std::size_t skip =
        startup_samples(u.subspan(starts[i], end - starts[i]), (end - starts[i]) / 4);
    if (skip > 0) r.split.skipped_ranges.emplace_back(starts[i], starts[i] + skip);
    for (std::size_t k = starts[i]; k < starts[i] + skip; ++k) {
      if (r.part[k] == kFitPart) {
        r.part[k] = kSkippedPart, ++r.split.skipped, --r.split.fit_samples;
      } else if (r.part[k] == kHeldoutPart) {
        r.part[k] = kSkippedPart, ++r.split.skipped, --r.split.heldout_samples;
      }
    }
  }
  r.y_lo = std::numeric_limits<double>::infinity();
  r.y_hi = -r.y_lo;
  for (std::size_t k = 0; k < r.n; ++k) {
    if (!r.fit_row(k)) continue;
    r.y_lo = std::min(r.y_lo, y[k]);
    r.y_hi = std::max(r.y_hi, y[k]);
  }
  require(r.y_hi > r.y_lo, "output y is constant (" + fmt(r.y_lo) + "): nothing to diagnose");
  r.search_stride =
      std::max<std::size_t>(1, (r.split.fit_samples + kMaxSearchRows - 1) / kMaxSearchRows);
  return r;
}

SplitErrors split_errors(const DiagnosisRecord& r, std::span<const double> prediction) {
  // error_stats() per contiguous run of one part, combined.
  struct Sum {
    double sq = 0.0, max_abs = 0.0, lo = std::numeric_limits<double>::infinity(),
           hi = -std::numeric_limits<double>::infinity();
    std::size_t samples = 0;
  } sums[2];
  std::size_t begin = 0;
  while (begin < r.n) {
    const unsigned char part = r.part[begin];
    std::size_t end = begin;
    while (end < r.n && r.part[end] == part) ++end;
    if (part == kSkippedPart) {
      begin = end;
      continue;
    }
    const auto measured = r.y.subspan(begin, end - begin);
    const ErrorStats s = error_stats(measured, prediction.subspan(begin, end - begin));
    const auto [lo, hi] = std::minmax_element(measured.begin(), measured.end());
    Sum& sum = sums[part];
    sum.sq += s.rmse * s.rmse * static_cast<double>(s.samples);
    sum.max_abs = std::max(sum.max_abs, s.max_abs);
    sum.lo = std::min(sum.lo, *lo);
    sum.hi = std::max(sum.hi, *hi);
    sum.samples += s.samples;
    begin = end;
  }
  auto stats = [](const Sum& s) {
    ErrorStats e;
    e.samples = s.samples;
    if (s.samples == 0) return e;
    e.rmse = std::sqrt(s.sq / static_cast<double>(s.samples));
    e.max_abs = s.max_abs;
    e.range = s.hi - s.lo;
    return e;
  };
  return {stats(sums[0]), stats(sums[1])};
}

}  // namespace hystbench::compensation::details
