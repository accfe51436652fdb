#pragma once
// Linear creep operators: first-order lags of the input with log-spaced time constants,
//   x_k(n) = a_k x_k(n-1) + (1 - a_k) u(n),  a_k = exp(-dt / tau_k),   y_creep = sum_k g_k x_k.
// Added to the hysteresis output, a bank of lags makes the output keep moving, about
// logarithmically in time, after the input holds. Exact discretisation for a held input.
// Real-time safe step()/peek().
#include <cstdint>
#include <span>
#include <vector>

namespace hystbench::compensation {

struct CreepParameters {
  std::vector<double> time_constants_s;  ///< tau_k > 0 [s]
  std::vector<double> gains;             ///< g_k [output unit / input unit]
};

/// n time constants log-spaced on [tau_min, tau_max] seconds.
std::vector<double> log_spaced_time_constants(std::size_t n, double tau_min_s, double tau_max_s);

class CreepOperatorBank {
 public:
  CreepOperatorBank() = default;
  /// Throws std::invalid_argument naming the field on bad input.
  explicit CreepOperatorBank(CreepParameters p, double dt_s = 1e-3);

  double step(double u) noexcept;
  double peek(double u) const noexcept;
  /// Every lag settled at u0.
  void reset(double u0) noexcept;
  /// The lags as `steps` step(u) calls would leave them, in closed form (each moves the fraction
  /// 1 - a_k^steps of the way to u). Real-time safe.
  void hold(double u, std::uint64_t steps) noexcept;
  void set_sample_period(double dt_s);
  bool empty() const noexcept { return p_.gains.empty(); }

  const CreepParameters& parameters() const noexcept { return p_; }
  std::span<const double> state() const noexcept { return x_; }
  /// Per lag, a_k = exp(-dt / tau_k) at the sample period set.
  std::span<const double> coefficients() const noexcept { return a_; }

 private:
  CreepParameters p_;
  std::vector<double> a_;
  std::vector<double> x_;
};

}  // namespace hystbench::compensation
