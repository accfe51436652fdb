// The classical PI family: its order by held-out error, and the classical-PI paper's
// triangular-matrix method on one ascending branch.
#include <algorithm>
#include <functional>
#include <stdexcept>
#include <string>

#include "details/identifier.hpp"
#include "details/validate.hpp"

namespace hystbench::compensation::details::identification {

Candidate Identifier::search_pi() {
  const int n = pick(operator_grid(0), [&](int n) { return memo(ModelKind::kPi, n, 0).score(); });
  return memo(ModelKind::kPi, n, 0);
}

}  // namespace hystbench::compensation::details::identification

namespace hystbench::compensation {

namespace {

using details::fmt;

}  // namespace

PiParameters identify_pi_triangular(std::span<const double> u_branch,
                                    std::span<const double> y_branch, int operators) {
  details::require_same_size(u_branch.size(), y_branch.size(), "u_branch", "y_branch");
  details::require(u_branch.size() >= 2, "the branch needs at least 2 samples");
  details::require(operators >= 1, "operators must be >= 1");
  details::require_finite(u_branch, "u_branch");
  details::require_finite(y_branch, "y_branch");
  const auto down = std::adjacent_find(u_branch.begin(), u_branch.end(), std::greater<double>());
  if (down != u_branch.end()) {
    const auto k = static_cast<std::size_t>(down - u_branch.begin()) + 1;
    throw std::invalid_argument("u_branch must be non-decreasing (an ascending branch): u_branch[" +
                                std::to_string(k) + "] = " + fmt(u_branch[k]) + " < u_branch[" +
                                std::to_string(k - 1) + "] = " + fmt(u_branch[k - 1]));
  }
  const double u0 = u_branch.front();
  const double span = u_branch.back() - u0;
  details::require(span > 0.0, "u_branch spans no input range");
  const auto n = static_cast<std::size_t>(operators);
  const double h = span / static_cast<double>(n);  // band-width step: bw_i = 2 r_i = i h
  // Output rise at the band edges Delta_k = k h (k = 1..n), linearly interpolated.
  auto rise_at = [&](double du) {
    const double target = u0 + du;
    const auto it = std::lower_bound(u_branch.begin(), u_branch.end(), target);
    if (it == u_branch.end()) return y_branch.back() - y_branch.front();
    const auto k = static_cast<std::size_t>(it - u_branch.begin());
    if (k == 0 || u_branch[k] == target) return y_branch[k] - y_branch.front();
    const double f = (target - u_branch[k - 1]) / (u_branch[k] - u_branch[k - 1]);
    return y_branch[k - 1] + f * (y_branch[k] - y_branch[k - 1]) - y_branch.front();
  };
  // Eq. 1: y_k = sum_{i<k} (bw_k - bw_i) w_i = sum_{i<k} (k - i) h w_i: forward substitution.
  PiParameters p;
  p.thresholds = uniform_thresholds(n, 0.5 * span);
  p.weights.assign(n, 0.0);
  for (std::size_t k = 1; k <= n; ++k) {
    double rest = rise_at(static_cast<double>(k) * h);
    for (std::size_t i = 0; i + 1 < k; ++i) rest -= static_cast<double>(k - i) * h * p.weights[i];
    p.weights[k - 1] = rest / h;
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) sum += p.weights[i] * (u0 + p.thresholds[i]);
  p.offset = y_branch.front() - sum;
  return p;
}

}  // namespace hystbench::compensation
