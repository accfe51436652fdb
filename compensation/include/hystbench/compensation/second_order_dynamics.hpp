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
  double step(double x) noexcept {
    const double y0 = phi_[0][0] * s_[0] + phi_[0][1] * s_[1] + gam_[0] * x;
    const double y1 = phi_[1][0] * s_[0] + phi_[1][1] * s_[1] + gam_[1] * x;
    s_[0] = y0;
    s_[1] = y1;
    return y0;
  }
  /// Settled at input (= output) x0.
  void reset(double x0) noexcept;
  const DynamicsParameters& parameters() const noexcept { return p_; }
  /// The exact discretisation over one sample, state [y, ydot]: x(k+1) = Phi x(k) + Gam u(k).
  double phi(int i, int j) const noexcept { return phi_[i][j]; }
  double gam(int i) const noexcept { return gam_[i]; }

 private:
  DynamicsParameters p_;
  // x(k+1) = Phi x(k) + Gam u(k), y = x0 (position); state [y, ydot].
  double phi_[2][2]{};
  double gam_[2]{};
  double s_[2]{};
};

}  // namespace hystbench::compensation
