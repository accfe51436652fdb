#include "details/diagnosis_signals.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <unsupported/Eigen/FFT>
#include <utility>

namespace hystbench::compensation::details {

namespace {

constexpr double kReversalBand = 0.005;  // of the input span
constexpr double kHoldBand = 0.001;      // of the input span
constexpr double kMinHoldSeconds = 0.1;
constexpr double kStepFraction = 0.01;  // of the input span
constexpr double kStepContrast = 3.0;   // against the neighbouring increments
constexpr double kMinCoherence = 0.5;
constexpr double kMinSignalToNoise = 10.0;

// du/dt over about 1 ms (at least one sample) [u/s]; 0 at the first sample.
std::vector<double> input_rate(std::span<const double> u, double dt) {
  const std::size_t n = u.size();
  std::vector<double> rate(n, 0.0);
  const auto m = static_cast<std::size_t>(std::max(1.0, std::round(1e-3 / dt)));
  for (std::size_t k = 1; k < n; ++k) {
    const std::size_t back = std::min(k, m);
    rate[k] = (u[k] - u[k - back]) / (static_cast<double>(back) * dt);
  }
  return rate;
}

/// The input's turning points and steps: each sample's direction of movement, and the events.
struct TurningPoints {
  std::vector<signed char> dir;  ///< +1 rising, -1 falling, 0 before the first move
  /// (sample, reference level) in sample order: the input before a step, at a turning point.
  std::vector<std::pair<std::size_t, double>> events;
};

// Turning points with a dead band of `band` [u] and the steps of ev.step as events; counts the
// turning points into ev.reversals.
TurningPoints find_turning_points(std::span<const double> u, double band, InputEvents& ev) {
  const std::size_t n = u.size();
  TurningPoints tp;
  tp.dir.assign(n, 0);
  int state = 0;
  double ext = u[0];
  std::size_t ext_k = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (ev.step[k]) tp.events.emplace_back(k, u[k - 1]);
    if (state == 0) {
      if (u[k] > u[0] + band) state = 1, ext = u[k], ext_k = k;
      if (u[k] < u[0] - band) state = -1, ext = u[k], ext_k = k;
    } else if (state == 1) {
      if (u[k] >= ext) {
        ext = u[k], ext_k = k;
      } else if (u[k] < ext - band) {
        if (!ev.step[k]) tp.events.emplace_back(ext_k, u[ext_k]);
        ++ev.reversals;
        state = -1, ext = u[k], ext_k = k;
      }
    } else {
      if (u[k] <= ext) {
        ext = u[k], ext_k = k;
      } else if (u[k] > ext + band) {
        if (!ev.step[k]) tp.events.emplace_back(ext_k, u[ext_k]);
        ++ev.reversals;
        state = 1, ext = u[k], ext_k = k;
      }
    }
    tp.dir[k] = static_cast<signed char>(state);
  }
  std::sort(tp.events.begin(), tp.events.end());
  return tp;
}

// Holds: runs within `hold_band` [u] lasting at least kMinHoldSeconds, into ev.holding, ev.holds
// and ev.hold_seconds.
void mark_holds(std::span<const double> u, double dt, double hold_band, InputEvents& ev) {
  const std::size_t n = u.size();
  ev.holding.assign(n, 0);
  const auto min_hold = static_cast<std::size_t>(std::max(5.0, std::ceil(kMinHoldSeconds / dt)));
  std::size_t start = 0;
  for (std::size_t k = 1; k <= n; ++k) {
    if (k < n && std::abs(u[k] - u[start]) <= hold_band) continue;
    if (k - start >= min_hold) {
      std::fill(ev.holding.begin() + static_cast<std::ptrdiff_t>(start),
                ev.holding.begin() + static_cast<std::ptrdiff_t>(k), 1);
      ++ev.holds;
      ev.hold_seconds += static_cast<double>(k - start) * dt;
    }
    start = k;
  }
}

// Each sample's direction (0 while holding), sign of the last move and time since the last
// event, and the event samples; needs ev.holding.
void mark_since_events(std::span<const double> u, double dt, double hold_band,
                       const TurningPoints& turns, InputEvents& ev) {
  const std::size_t n = u.size();
  const auto& events = turns.events;
  ev.direction.assign(n, 0);
  ev.last_move.assign(n, 0);
  ev.since_event_s.assign(n, 0.0);
  std::size_t next = 0;
  std::size_t last = 0;
  double reference = u[0];
  bool any = false;
  for (std::size_t k = 0; k < n; ++k) {
    while (next < events.size() && events[next].first <= k) {
      last = events[next].first, reference = events[next].second, any = true;
      ++next;
    }
    ev.since_event_s[k] = static_cast<double>(k - last) * dt;
    ev.direction[k] = ev.holding[k] ? 0 : turns.dir[k];
    const double moved = u[k] - reference;
    if (any) ev.last_move[k] = std::abs(moved) > hold_band ? (moved > 0 ? 1 : -1) : turns.dir[k];
  }
  for (const auto& e : events) ev.event_samples.push_back(e.first);
  ev.event_samples.erase(std::unique(ev.event_samples.begin(), ev.event_samples.end()),
                         ev.event_samples.end());
}

}  // namespace

double median(std::vector<double> v, double if_empty) {
  if (v.empty()) return if_empty;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

std::vector<std::size_t> find_steps(std::span<const double> u) {
  std::vector<std::size_t> steps;
  if (u.size() < 2) return steps;
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  const double span = *hi - *lo;
  for (std::size_t k = 1; k < u.size(); ++k) {
    const double du = std::abs(u[k] - u[k - 1]);
    const double before = k >= 2 ? std::abs(u[k - 1] - u[k - 2]) : 0.0;
    const double after = k + 1 < u.size() ? std::abs(u[k + 1] - u[k]) : 0.0;
    if (du > kStepFraction * span && du > kStepContrast * std::max(before, after)) {
      steps.push_back(k);
    }
  }
  return steps;
}

InputEvents find_input_events(std::span<const double> u, double dt) {
  const std::size_t n = u.size();
  InputEvents ev;
  const auto [lo_it, hi_it] = std::minmax_element(u.begin(), u.end());
  const double span = *hi_it - *lo_it;
  const double band = kReversalBand * span;
  const double hold_band = kHoldBand * span;

  ev.rate = input_rate(u, dt);

  ev.step.assign(n, 0);
  for (const std::size_t k : find_steps(u)) {
    ev.step[k] = 1;
    ++ev.steps;
  }

  const TurningPoints turns = find_turning_points(u, band, ev);
  mark_holds(u, dt, hold_band, ev);
  mark_since_events(u, dt, hold_band, turns, ev);
  return ev;
}

double noise_rms(std::span<const double> e) {
  if (e.size() < 3) return 0.0;
  std::vector<double> d(e.size() - 2);
  for (std::size_t k = 1; k + 1 < e.size(); ++k) d[k - 1] = e[k + 1] - 2.0 * e[k] + e[k - 1];
  const double med = median(d, 0.0);
  for (double& v : d) v = std::abs(v - med);
  // MAD -> sigma for a Gaussian; the second difference of white noise has variance 6 sigma^2.
  return 1.4826 * median(std::move(d), 0.0) / std::sqrt(6.0);
}

std::size_t input_period(std::span<const double> u) {
  const std::size_t n = u.size();
  if (n < 64) return 0;
  // Coarse search on block means (at most 2^16 of them, one FFT), refined at full rate.
  const std::size_t m = (n + 65535) / 65536;
  const std::size_t nc = n / m;
  std::vector<double> coarse(nc, 0.0);
  for (std::size_t i = 0; i < nc; ++i) {
    for (std::size_t j = 0; j < m; ++j) coarse[i] += u[i * m + j];
    coarse[i] /= static_cast<double>(m);
  }
  double mean = 0.0;
  for (const double v : coarse) mean += v;
  mean /= static_cast<double>(nc);
  std::size_t len = 1;
  while (len < 2 * nc) len *= 2;
  std::vector<double> x(len, 0.0);
  for (std::size_t k = 0; k < nc; ++k) x[k] = coarse[k] - mean;
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> X;
  fft.fwd(X, x);
  for (auto& c : X) c = std::norm(c);
  std::vector<double> acf;
  fft.inv(acf, X);
  if (!(acf[0] > 0.0)) return 0;
  // Unbiased, normalised: r(l) = sum_k x(k) x(k+l) / (n - l) / variance.
  auto r = [&](std::size_t l) {
    return acf[l] * static_cast<double>(nc) / (static_cast<double>(nc - l) * acf[0]);
  };
  const std::size_t max_lag = nc / 2;
  std::size_t l = 1;
  while (l <= max_lag && r(l) > 0.5) ++l;
  std::size_t lag = 0;
  for (; l <= max_lag; ++l) {
    if (r(l) >= 0.95 && r(l) >= r(l - 1) && (l + 1 > max_lag || r(l) >= r(l + 1))) {
      lag = l;
      break;
    }
  }
  if (lag == 0) return 0;
  // Full rate: the lag within one block either side with the smallest mean square difference.
  auto mean_square_difference = [&](std::size_t p) {
    double sum = 0.0;
    for (std::size_t k = 0; k + p < n; ++k) sum += (u[k + p] - u[k]) * (u[k + p] - u[k]);
    return sum / static_cast<double>(n - p);
  };
  std::size_t best = 0;
  double best_difference = std::numeric_limits<double>::infinity();
  for (std::size_t p = lag * m - std::min(lag * m - 1, m); p <= std::min(n / 2, lag * m + m); ++p) {
    const double d = mean_square_difference(p);
    if (d < best_difference) best = p, best_difference = d;
  }
  double full_mean = 0.0, full_square = 0.0;
  for (const double v : u) full_mean += v, full_square += v * v;
  full_mean /= static_cast<double>(n);
  const double variance = full_square / static_cast<double>(n) - full_mean * full_mean;
  return best_difference <= 0.02 * 0.02 * variance ? best : 0;
}

double periodic_noise_rms(std::span<const double> y, std::size_t period) {
  if (period == 0 || y.size() < period + 3) return 0.0;
  std::vector<double> d(y.size() - period);
  for (std::size_t k = 0; k < d.size(); ++k) d[k] = y[k + period] - y[k];
  // The period difference carries the noise of two samples.
  return noise_rms(d) / std::sqrt(2.0);
}

std::vector<double> linear_edges(double lo, double hi, std::size_t bins) {
  std::vector<double> e(bins + 1);
  for (std::size_t i = 0; i <= bins; ++i) {
    e[i] = lo + (hi - lo) * static_cast<double>(i) / static_cast<double>(bins);
  }
  return e;
}

std::vector<double> log_edges(double lo, double hi, std::size_t bins) {
  std::vector<double> e(bins + 1);
  for (std::size_t i = 0; i <= bins; ++i) {
    e[i] = lo * std::pow(hi / lo, static_cast<double>(i) / static_cast<double>(bins));
  }
  return e;
}

std::vector<double> quantile_edges(std::span<const double> x, std::span<const unsigned char> use,
                                   std::size_t bins) {
  std::vector<double> v;
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (use.empty() || use[k]) v.push_back(x[k]);
  }
  if (v.empty()) return {0.0, 1.0};
  std::sort(v.begin(), v.end());
  std::vector<double> e;
  for (std::size_t i = 0; i <= bins; ++i) {
    const auto j = std::min(v.size() - 1, i * (v.size() - 1) / bins);
    if (e.empty() || v[j] > e.back()) e.push_back(v[j]);
  }
  if (e.size() < 2) e.push_back(e.back() + 1.0);
  return e;
}

ResidualProfile binned_profile(std::string variable, std::string label, std::span<const double> x,
                               std::span<const double> value, std::span<const unsigned char> use,
                               const std::vector<double>& edges) {
  ResidualProfile p;
  p.variable = std::move(variable);
  p.label = std::move(label);
  const std::size_t bins = edges.size() - 1;
  std::vector<double> sum(bins, 0.0);
  std::vector<std::size_t> count(bins, 0);
  double total = 0.0, total_sq = 0.0;
  std::size_t used = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (!use.empty() && !use[k]) continue;
    const auto it = std::upper_bound(edges.begin() + 1, edges.end() - 1, x[k]);
    const auto b = static_cast<std::size_t>(it - (edges.begin() + 1));
    sum[b] += value[k];
    ++count[b];
    total += value[k];
    total_sq += value[k] * value[k];
    ++used;
  }
  if (used == 0) return p;
  const double mean = total / static_cast<double>(used);
  const double variance = total_sq - static_cast<double>(used) * mean * mean;
  double between = 0.0;
  for (std::size_t b = 0; b < bins; ++b) {
    if (count[b] == 0) continue;
    const double m = sum[b] / static_cast<double>(count[b]);
    p.centers.push_back(0.5 * (edges[b] + edges[b + 1]));
    p.means.push_back(m);
    p.counts.push_back(count[b]);
    between += static_cast<double>(count[b]) * (m - mean) * (m - mean);
  }
  p.explained = variance > 0.0 ? std::clamp(between / variance, 0.0, 1.0) : 0.0;
  return p;
}

FrequencyResponse frequency_response(std::span<const double> input, std::span<const double> output,
                                     double dt, double noise_rms) {
  FrequencyResponse fr;
  const std::size_t n = std::min(input.size(), output.size());
  std::size_t len = 256;
  while (len * 2 <= 16384 && len * 2 * 8 <= n) len *= 2;
  if (len > n) return fr;
  const std::size_t hop = len / 2;
  std::vector<double> window(len);
  for (std::size_t i = 0; i < len; ++i) {
    window[i] = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) /
                                     static_cast<double>(len));
  }
  const std::size_t bins = len / 2;
  double window_power = 0.0;
  for (const double w : window) window_power += w * w;
  std::size_t segments = 0;
  std::vector<double> pxx(bins, 0.0), pyy(bins, 0.0);
  std::vector<std::complex<double>> pyx(bins, 0.0);
  Eigen::FFT<double> fft;
  std::vector<double> xs(len), ys(len);
  std::vector<std::complex<double>> X, Y;
  for (std::size_t begin = 0; begin + len <= n; begin += hop) {
    double mx = 0.0, my = 0.0;
    for (std::size_t i = 0; i < len; ++i) mx += input[begin + i], my += output[begin + i];
    mx /= static_cast<double>(len), my /= static_cast<double>(len);
    for (std::size_t i = 0; i < len; ++i) {
      xs[i] = (input[begin + i] - mx) * window[i];
      ys[i] = (output[begin + i] - my) * window[i];
    }
    fft.fwd(X, xs);
    fft.fwd(Y, ys);
    ++segments;
    for (std::size_t i = 1; i < bins; ++i) {
      pxx[i] += std::norm(X[i]);
      pyy[i] += std::norm(Y[i]);
      pyx[i] += Y[i] * std::conj(X[i]);
    }
  }
  for (std::size_t i = 1; i < bins; ++i) {
    if (!(pxx[i] > 0.0) || !(pyy[i] > 0.0)) continue;
    const std::complex<double> h = pyx[i] / pxx[i];
    fr.frequency_hz.push_back(static_cast<double>(i) / (static_cast<double>(len) * dt));
    fr.gain.push_back(std::abs(h));
    fr.phase_rad.push_back(std::arg(h));
    fr.coherence.push_back(std::norm(pyx[i]) / (pxx[i] * pyy[i]));
    const double scale = 2.0 * dt / (window_power * static_cast<double>(segments));
    fr.input_psd.push_back(scale * pxx[i]);
    fr.output_psd.push_back(scale * pyy[i]);
    const double noise_psd = 2.0 * noise_rms * noise_rms * dt;
    fr.informative.push_back(fr.coherence.back() >= kMinCoherence &&
                             fr.input_psd.back() >= noise_psd &&
                             fr.output_psd.back() >= kMinSignalToNoise * noise_psd);
  }
  return fr;
}

}  // namespace hystbench::compensation::details
