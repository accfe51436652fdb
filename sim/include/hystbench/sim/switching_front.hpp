#pragma once
// Rate dependence of domain switching: the relays of a Preisach model switch at the input the
// switching front has reached, and the front moves at a speed that grows with a power n of how
// far the input is past it (a domain wall's speed against its overdrive):
//   du_s/dt = k sign(u - u_s) |u - u_s|^n,   k = (1 kV/s) / lag^n.
// Behind a steady ramp of rate r the front lags by lag * (r / 1 kV/s)^(1/n).
// - n = 1: viscous wall motion (Bertotti's dynamic Preisach model): the front is a first-order
//   lag of the input, time constant lag / (1 kV/s).
// - n = 2 (the default of the simulator): the lag grows with the square root of the rate, as the
//   loop area of piezoceramics grows with about the 1/3..1/2 power of the frequency; it is not a
//   delay (lag linear in the rate), a linear filter, or weights or thresholds linear in du/dt.
// At a reversal the front's speed passes through zero, so the output stays smooth. For an input
// held over a sample period the solution is exact: e(t) = e0 exp(-k t) for n = 1, else
// e(t) = (e0^(1-n) + (n - 1) k t)^(-1/(n-1)).
// Units: V, s. Real-time safe step()/reset().
#include <cmath>

namespace hystbench::sim {

class SwitchingFront {
 public:
  /// lag_v: the front's lag behind a 1 kV/s ramp [V] (> 0); exponent n in [1, 4]; dt_s: sample
  /// period [s] (> 0). Throws std::invalid_argument naming the argument otherwise.
  SwitchingFront(double lag_v, double exponent, double dt_s);

  /// The input u [V] held for one sample period; returns the front at its end [V].
  double step(double u) noexcept {
    const double e = std::abs(front_ - u);
    double left = 0.0;
    if (e > 0.0) {
      if (exponent_ == 1.0) {
        left = e * decay_;
      } else if (exponent_ == 2.0) {
        left = e / (1.0 + k_dt_ * e);
      } else {
        left = std::pow(std::pow(e, 1.0 - exponent_) + (exponent_ - 1.0) * k_dt_,
                        -1.0 / (exponent_ - 1.0));
      }
    }
    front_ = front_ > u ? u + left : u - left;
    return front_;
  }
  /// At rest at u0 [V].
  void reset(double u0) noexcept { front_ = u0; }
  double front() const noexcept { return front_; }

 private:
  double exponent_;
  double k_dt_;   // k * dt
  double decay_;  // n = 1: exp(-k dt)
  double front_ = 0.0;
};

}  // namespace hystbench::sim
