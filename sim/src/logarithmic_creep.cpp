#include "hystbench/sim/logarithmic_creep.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace hystbench::sim {

compensation::CreepParameters logarithmic_creep_bank(double gamma, double longest_s,
                                                     double reference_s) {
  if (!(std::isfinite(gamma) && gamma >= 0.0 && gamma < 1.0)) {
    throw std::invalid_argument("gamma: must be in [0, 1)");
  }
  if (!(std::isfinite(reference_s) && reference_s > 0.0)) {
    throw std::invalid_argument("reference_s: must be > 0");
  }
  if (!(std::isfinite(longest_s) && longest_s >= 10.0 * reference_s)) {
    throw std::invalid_argument("longest_s: must be at least ten times reference_s");
  }
  // Time constants three per decade, from reference_s / 30 to longest_s.
  const double first = reference_s / 30.0;
  const int count = static_cast<int>(std::ceil(3.0 * std::log10(longest_s / first))) + 1;
  std::vector<double> tau(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) {
    tau[static_cast<std::size_t>(k)] =
        first * std::pow(longest_s / first, static_cast<double>(k) / (count - 1));
  }
  // The kernel on a log grid of times, twenty per decade, from reference_s / 100 to longest_s.
  std::vector<double> times;
  for (double t = reference_s / 100.0; t <= longest_s * 1.0001; t *= std::pow(10.0, 0.05)) {
    times.push_back(t);
  }
  const auto rows = static_cast<Eigen::Index>(times.size());
  Eigen::MatrixXd a(rows, count);
  Eigen::VectorXd b(rows);
  for (Eigen::Index r = 0; r < rows; ++r) {
    const double t = times[static_cast<std::size_t>(r)];
    b(r) = std::log10(1.0 + t / reference_s);
    for (int k = 0; k < count; ++k) a(r, k) = 1.0 - std::exp(-t / tau[static_cast<std::size_t>(k)]);
  }
  // Non-negative least squares by elimination: drop the lags whose weight comes out negative and
  // solve again (the kernel is smooth, so few ever do).
  std::vector<bool> active(static_cast<std::size_t>(count), true);
  Eigen::VectorXd w = Eigen::VectorXd::Zero(count);
  for (int pass = 0; pass < count; ++pass) {
    std::vector<int> cols;
    for (int k = 0; k < count; ++k)
      if (active[static_cast<std::size_t>(k)]) cols.push_back(k);
    Eigen::MatrixXd sub(rows, static_cast<Eigen::Index>(cols.size()));
    for (std::size_t c = 0; c < cols.size(); ++c)
      sub.col(static_cast<Eigen::Index>(c)) = a.col(cols[c]);
    const Eigen::VectorXd x = sub.colPivHouseholderQr().solve(b);
    bool negative = false;
    w.setZero();
    for (std::size_t c = 0; c < cols.size(); ++c) {
      w(cols[c]) = x(static_cast<Eigen::Index>(c));
      if (x(static_cast<Eigen::Index>(c)) < 0.0) {
        active[static_cast<std::size_t>(cols[c])] = false;
        negative = true;
      }
    }
    if (!negative) break;
  }
  compensation::CreepParameters bank;
  for (int k = 0; k < count; ++k) {
    if (w(k) <= 0.0) continue;
    bank.time_constants_s.push_back(tau[static_cast<std::size_t>(k)]);
    bank.gains.push_back(gamma * w(k));
  }
  return bank;
}

}  // namespace hystbench::sim
