#include "hystbench/compensation/creep_operator_bank.hpp"

#include <cmath>

#include "details/validate.hpp"

namespace hystbench::compensation {

std::vector<double> log_spaced_time_constants(std::size_t n, double tau_min_s, double tau_max_s) {
  details::require(tau_min_s > 0.0 && tau_max_s >= tau_min_s,
                   "creep time constants need 0 < tau_min <= tau_max");
  std::vector<double> tau(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double f = n > 1 ? static_cast<double>(k) / static_cast<double>(n - 1) : 0.0;
    tau[k] = tau_min_s * std::pow(tau_max_s / tau_min_s, f);
  }
  return tau;
}

CreepOperatorBank::CreepOperatorBank(CreepParameters p, double dt_s) : p_(std::move(p)) {
  details::require_same_size(p_.time_constants_s.size(), p_.gains.size(), "creep.time_constants_s",
                             "creep.gains");
  details::require_finite(p_.time_constants_s, "creep.time_constants_s");
  details::require_finite(p_.gains, "creep.gains");
  for (std::size_t k = 0; k < p_.time_constants_s.size(); ++k) {
    details::require(p_.time_constants_s[k] > 0.0,
                     "creep.time_constants_s[" + std::to_string(k) + "] must be > 0");
  }
  x_.assign(p_.gains.size(), 0.0);
  set_sample_period(dt_s);
}

void CreepOperatorBank::set_sample_period(double dt_s) {
  details::require(std::isfinite(dt_s) && dt_s > 0.0, "sample period must be > 0");
  a_.resize(p_.time_constants_s.size());
  for (std::size_t k = 0; k < a_.size(); ++k) a_[k] = std::exp(-dt_s / p_.time_constants_s[k]);
}

double CreepOperatorBank::step(double u) noexcept {
  double y = 0.0;
  for (std::size_t k = 0; k < x_.size(); ++k) {
    x_[k] = a_[k] * x_[k] + (1.0 - a_[k]) * u;
    y += p_.gains[k] * x_[k];
  }
  return y;
}

double CreepOperatorBank::peek(double u) const noexcept {
  double y = 0.0;
  for (std::size_t k = 0; k < x_.size(); ++k)
    y += p_.gains[k] * (a_[k] * x_[k] + (1.0 - a_[k]) * u);
  return y;
}

void CreepOperatorBank::reset(double u0) noexcept {
  for (auto& x : x_) x = u0;
}

void CreepOperatorBank::hold(double u, std::uint64_t steps) noexcept {
  const auto n = static_cast<double>(steps);
  for (std::size_t k = 0; k < x_.size(); ++k) x_[k] = u + (x_[k] - u) * std::pow(a_[k], n);
}

}  // namespace hystbench::compensation
