#include "hystbench/sim/preisach_hysteresis.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace hystbench::sim {

namespace {

void require(bool ok, const char* prefix, const char* field, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string(prefix) + field + ": " + what);
}

/// Relay density at (alpha, beta), alpha >= beta, up to its scale.
double density(const PreisachParameters& p, double alpha, double beta) {
  const double hc = 0.5 * (alpha - beta);
  if (hc <= 0.0) return 0.0;
  const double hb = 0.5 * (alpha + beta);
  const double lc = std::log(hc / p.coercive_median_v) / p.coercive_spread;
  const double zb = (hb - p.bias_mean_v) / p.bias_std_v;
  return std::exp(-0.5 * (lc * lc + zb * zb)) / hc;
}

}  // namespace

void validate(const PreisachParameters& p, const char* prefix) {
  require(std::isfinite(p.u_min_v), prefix, "u_min_v", "must be a finite number");
  require(std::isfinite(p.u_max_v) && p.u_max_v > p.u_min_v, prefix, "u_max_v",
          "must be greater than u_min_v");
  require(std::isfinite(p.coercive_median_v) && p.coercive_median_v > 0.0, prefix,
          "coercive_median_v", "must be > 0");
  require(std::isfinite(p.coercive_spread) && p.coercive_spread > 0.0, prefix, "coercive_spread",
          "must be > 0");
  require(std::isfinite(p.bias_mean_v), prefix, "bias_mean_v", "must be a finite number");
  require(std::isfinite(p.bias_std_v) && p.bias_std_v > 0.0, prefix, "bias_std_v", "must be > 0");
  require(std::isfinite(p.switching_um) && p.switching_um > 0.0, prefix, "switching_um",
          "must be > 0");
  require(p.grid_points >= 33 && p.grid_points <= 4097, prefix, "grid_points",
          "must be in [33, 4097]");
}

PreisachHysteresis::PreisachHysteresis(const PreisachParameters& p)
    : p_(p), m_(static_cast<std::size_t>(p.grid_points)) {
  validate(p_);
  h_ = (p_.u_max_v - p_.u_min_v) / static_cast<double>(m_ - 1);
  // K(i, j): the column alpha_i integrated over beta from beta_j up to the diagonal; then
  // E(i, j) = E(i - 1, j) + the strip between alpha_{i-1} and alpha_i (trapezoids both ways).
  table_.assign(m_ * m_, 0.0);
  std::vector<double> k_prev(m_, 0.0), k_now(m_, 0.0), column(m_, 0.0);
  for (std::size_t i = 0; i < m_; ++i) {
    const double alpha = p_.u_min_v + static_cast<double>(i) * h_;
    for (std::size_t j = 0; j <= i; ++j) {
      column[j] = density(p_, alpha, p_.u_min_v + static_cast<double>(j) * h_);
    }
    k_now[i] = 0.0;
    for (std::size_t j = i; j-- > 0;)
      k_now[j] = k_now[j + 1] + 0.5 * h_ * (column[j] + column[j + 1]);
    for (std::size_t j = 0; j < i; ++j) {
      table_[i * m_ + j] = table_[(i - 1) * m_ + j] + 0.5 * h_ * (k_prev[j] + k_now[j]);
    }
    std::swap(k_prev, k_now);
  }
  const double total = table_[(m_ - 1) * m_];
  if (!(total > 0.0)) {
    throw std::invalid_argument(
        "hysteresis: the relay density has no weight inside the input range (bias_mean_v and "
        "coercive_median_v put every relay outside it)");
  }
  for (double& e : table_) e *= p_.switching_um / total;
  points_.assign(kMemoryCapacity + 1, 0.0);
  sums_.assign(kMemoryCapacity + 1, 0.0);
  reset(p_.u_min_v);
}

double PreisachHysteresis::clamp_input(double u) const noexcept {
  return std::clamp(u, p_.u_min_v, p_.u_max_v);
}

double PreisachHysteresis::everett(double alpha, double beta) const noexcept {
  if (!(alpha > beta)) return 0.0;
  const double last = static_cast<double>(m_ - 1);
  const double x = std::clamp((alpha - p_.u_min_v) / h_, 0.0, last);
  const double y = std::clamp((beta - p_.u_min_v) / h_, 0.0, last);
  const auto i = std::min(static_cast<std::size_t>(x), m_ - 2);
  const auto j = std::min(static_cast<std::size_t>(y), m_ - 2);
  const double fx = x - static_cast<double>(i);
  const double fy = y - static_cast<double>(j);
  if (i == j) {
    // A cell on the diagonal: linear on its lower triangle, whose corners on the diagonal are 0,
    // so E(u, u) = 0 exactly and the output is continuous through every reversal.
    return std::max(fx - fy, 0.0) * table(i + 1, j);
  }
  return (1.0 - fx) * ((1.0 - fy) * table(i, j) + fy * table(i, j + 1)) +
         fx * ((1.0 - fy) * table(i + 1, j) + fy * table(i + 1, j + 1));
}

void PreisachHysteresis::push(double point) noexcept {
  if (n_ == kMemoryCapacity + 1) {
    // Full: forget the innermost minor loop (the last two reversal points), which the input has
    // been inside ever since; its relays keep the state the remaining memory gives them.
    n_ -= 2;
    ++overflows_;
  }
  points_[n_] = point;
  sums_[n_] = sums_[n_ - 1] + branch(points_[n_ - 1], point);
  ++n_;
}

double PreisachHysteresis::step(double u) noexcept {
  if (!std::isfinite(u)) return y_;
  u = clamp_input(u);
  bool rising = (n_ - 1) % 2 == 0;  // the last reversal point is a minimum
  if (rising && u < u_) {
    push(u_);
    rising = false;
  } else if (!rising && u > u_) {
    push(u_);
    rising = true;
  }
  // Wiping out: passing an earlier extremum of the same kind erases it and the reversal after it.
  if (rising) {
    while (n_ >= 3 && u >= points_[n_ - 2]) n_ -= 2;
  } else {
    while (n_ >= 3 && u <= points_[n_ - 2]) n_ -= 2;
    if (n_ == 2 && u <= points_[0]) n_ = 1;  // down to u_min: every relay down
  }
  u_ = u;
  y_ = sums_[n_ - 1] + branch(points_[n_ - 1], u_);
  return y_;
}

void PreisachHysteresis::reset(double u0) noexcept {
  n_ = 1;
  points_[0] = p_.u_min_v;
  sums_[0] = 0.0;
  u_ = p_.u_min_v;
  y_ = 0.0;
  if (!std::isfinite(u0)) u0 = p_.u_min_v;
  u0 = clamp_input(u0);
  // A decaying alternating input around u0 from the whole range down to 1e-4 of it.
  const double span = p_.u_max_v - p_.u_min_v;
  double amplitude = span;
  double sign = 1.0;
  while (amplitude > 1e-4 * span) {
    step(u0 + sign * amplitude);
    sign = -sign;
    amplitude *= 0.8;
  }
  step(u0);
}

}  // namespace hystbench::sim
