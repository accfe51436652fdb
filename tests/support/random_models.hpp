#pragma once
// Randomised invertible PI-family models and rich input signals for property tests.
#include <algorithm>
#include <memory>
#include <random>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/pi_model.hpp"

namespace hystbench::testing {

/// Random PI with n plays on an input span [0, span]: thresholds 0 = r_0 < ... < r_{n-1} < span/2
/// (random spacing), cumulative weights W_i drawn positive so the model is invertible, while
/// individual weights may be negative.
inline compensation::PiParameters random_pi(std::mt19937_64& rng, int n, double span) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> gaps(n);
  for (auto& g : gaps) g = 0.2 + unit(rng);
  double total = 0.0;
  for (double g : gaps) total += g;
  compensation::PiParameters p;
  double r = 0.0;
  for (int i = 0; i < n; ++i) {
    p.thresholds.push_back(r);
    r += gaps[i] / total * 0.5 * span;
  }
  double prev = 0.0;
  for (int i = 0; i < n; ++i) {
    const double cumulative = 0.05 + 1.5 * unit(rng);  // W_i > 0
    p.weights.push_back(cumulative - prev);
    prev = cumulative;
  }
  p.offset = (unit(rng) - 0.5) * 10.0;
  return p;
}

/// Random invertible modified PI: PI as above followed by m dead zones per side about `center`.
inline compensation::ModifiedPiParameters random_mpi(std::mt19937_64& rng, int n, int m,
                                                     double span) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  compensation::ModifiedPiParameters p;
  p.play = random_pi(rng, n, span);
  p.center = (unit(rng) - 0.5) * 4.0;
  // Dead-zone thresholds spread over about the PI output's half range on each side.
  const double reach = 0.4 * span;
  std::vector<double> d(2 * m + 1, 0.0);
  for (int j = 1; j <= m; ++j) {
    d[m + j] = reach * j / (m + 0.5) * (0.8 + 0.4 * unit(rng));
    d[m - j] = -reach * j / (m + 0.5) * (0.8 + 0.4 * unit(rng));
  }
  std::sort(d.begin(), d.end());
  std::vector<double> w(2 * m + 1, 0.0);
  w[m] = 0.5 + unit(rng);
  double cum = w[m];
  for (int j = m + 1; j <= 2 * m; ++j) {
    const double next = 0.1 + 1.5 * unit(rng);
    w[j] = next - cum;
    cum = next;
  }
  cum = w[m];
  for (int j = m - 1; j >= 0; --j) {
    const double next = 0.1 + 1.5 * unit(rng);
    w[j] = next - cum;
    cum = next;
  }
  p.dead_zone = {d, w};
  return p;
}

/// A random_mpi actuator model on the input range [0, span], configured at the sample period dt.
inline compensation::ActuatorModel random_mpi_actuator(std::mt19937_64& rng, int n, int m,
                                                       double span, double dt) {
  compensation::ActuatorModel model(
      std::make_unique<compensation::ModifiedPiModel>(random_mpi(rng, n, m, span)));
  model.input_min = 0.0;
  model.input_max = span;
  model.configure(dt);
  return model;
}

/// A signal in [lo, hi] with random reversals, nested minor loops and occasional jumps.
inline std::vector<double> random_reversal_signal(std::mt19937_64& rng, std::size_t samples,
                                                  double lo, double hi) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> u;
  u.reserve(samples);
  double x = lo + 0.5 * (hi - lo);
  while (u.size() < samples) {
    const double target = lo + (hi - lo) * unit(rng);
    const std::size_t len = 1 + static_cast<std::size_t>(200 * unit(rng));
    const double start = x;
    for (std::size_t k = 1; k <= len && u.size() < samples; ++k) {
      x = start + (target - start) * static_cast<double>(k) / static_cast<double>(len);
      u.push_back(x);
    }
  }
  return u;
}

}  // namespace hystbench::testing
