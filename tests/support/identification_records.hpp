#pragma once
// Records for the identification tests, sampled at kRecordDt [s]: a rich excitation with nested
// minor loops, its sample times, a hysteresis model's response to it, relative errors of fitted
// parameters, the options of a fit of fixed structure and a modified PI to recover.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "support/random_models.hpp"

namespace hystbench::testing {

inline constexpr double kRecordDt = 1e-3;  ///< [s]

/// Decaying-amplitude sine (1 Hz) plus a faster component whose reversals make nested minor
/// loops; `chirp` > 0 sweeps the frequency so that the same levels are crossed at several rates.
inline std::vector<double> rich_excitation(std::size_t n, double lo, double hi,
                                           double chirp = 0.0) {
  std::vector<double> u(n);
  const double mid = 0.5 * (lo + hi);
  const double half = 0.5 * (hi - lo);
  const double duration = static_cast<double>(n) * kRecordDt;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * kRecordDt;
    const double envelope = 1.0 - 0.8 * t / duration;
    const double phase = 2.0 * std::numbers::pi * (t + 0.5 * chirp * t * t / duration);
    u[k] = mid + half * envelope * (0.75 * std::sin(phase) + 0.25 * std::sin(4.3 * phase));
  }
  return u;
}

/// Sample times of n samples from 0 [s].
inline std::vector<double> times(std::size_t n) {
  std::vector<double> t(n);
  for (std::size_t k = 0; k < n; ++k) t[k] = static_cast<double>(k) * kRecordDt;
  return t;
}

/// The model's response to u, reset (relaxed) at u's first sample.
inline std::vector<double> simulate(compensation::HysteresisModel& model,
                                    const std::vector<double>& u) {
  model.reset(u.front());
  return model.simulate(u);
}

/// Largest difference relative to the largest |want| (expects equal lengths).
inline double relative_error(const std::vector<double>& got, const std::vector<double>& want) {
  EXPECT_EQ(got.size(), want.size());
  double err = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < std::min(got.size(), want.size()); ++i) {
    err = std::max(err, std::abs(got[i] - want[i]));
    scale = std::max(scale, std::abs(want[i]));
  }
  return scale > 0.0 ? err / scale : err;
}

inline double relative_error(double got, double want) {
  return std::abs(got - want) / std::max(std::abs(want), 1.0);
}

/// A fit of `kind` with neither threshold refinement nor a delay search.
inline compensation::FitOptions fixed_options(compensation::ModelKind kind) {
  compensation::FitOptions o;
  o.kind = kind;
  o.refine_thresholds = false;
  o.delay_samples = 0;
  return o;
}

/// A modified PI whose forward dead zone has w_0 = 1 (the normalisation the error model uses),
/// thresholds inside the PI output range about `center`.
inline compensation::ModifiedPiParameters known_mpi(std::mt19937_64& rng,
                                                    const std::vector<double>& u) {
  compensation::ModifiedPiParameters p;
  p.play = random_pi(rng, 8, 10.0);
  compensation::PiModel pi(p.play);
  const std::vector<double> out = simulate(pi, u);
  const auto [lo, hi] = std::minmax_element(out.begin(), out.end());
  p.center = 0.5 * (*lo + *hi) + 0.1 * (*hi - *lo);
  const double h = 0.5 * (*hi - *lo);
  p.dead_zone.thresholds = {-0.6 * h, -0.3 * h, 0.0, 0.25 * h, 0.55 * h};
  p.dead_zone.weights = {0.4, -0.4, 1.0, -0.3, 0.8};  // cumulative 1.0 | 0.6, 1.0 | 0.7, 1.5
  return p;
}

}  // namespace hystbench::testing
