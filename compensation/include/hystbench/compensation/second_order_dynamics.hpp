#pragma once
// Linear second-order dynamics with unit DC gain (multilayer-actuator paper, eq. 9-11):
//   G(s) = wn^2 / (s^2 + 2 zeta wn s + wn^2),  discretised exactly for a zero-order-held input.
// Real-time safe step().
namespace hystbench::compensation {

struct DynamicsParameters {
  double natural_frequency_hz = 1000.0;  ///< f_n > 0 [Hz]
  double damping_ratio = 0.05;           ///< zeta > 0
  /// Roll-off of this model's inversion in the feedforward (DynamicsInversion) [Hz], >= 0;
  /// 0 = the bench's default. Not used by the dynamics themselves.
  double feedforward_bandwidth_hz = 0.0;
};

class SecondOrderDynamics {
 public:
  /// Throws std::invalid_argument for f_n <= 0, zeta <= 0, dt <= 0 or NaN.
  SecondOrderDynamics(DynamicsParameters p, double dt_s);

  /// Holds x for one sample period; returns the output at the end of that period.
  double step(double x) noexcept;
  /// Settled at input (= output) x0.
  void reset(double x0) noexcept;
  const DynamicsParameters& parameters() const noexcept { return p_; }

 private:
  DynamicsParameters p_;
  // x(k+1) = Phi x(k) + Gam u(k), y = x0 (position); state [y, ydot].
  double phi_[2][2]{};
  double gam_[2]{};
  double s_[2]{};
};

}  // namespace hystbench::compensation
