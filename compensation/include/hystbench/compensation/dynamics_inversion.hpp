#pragma once
// Inversion of a model's input delay and second-order dynamics for a reference known ahead of
// time (inversion-based feedforward, Croft, Shan and Devasia 2001): the static target the
// hysteresis inverse must produce at sample k is
//   v(k) = r(t) + (2 zeta / wn) r'(t) + r''(t) / wn^2,   t = t_k + lead,
// with lead = the delay (any fraction of a sample included), less half a sample when the model has
// dynamics (they are discretised for a zero-order-held input and report the position at the end of
// the sample), and r', r'' central differences over +-h. h = max(dt, 1 / (pi f_b)) rolls the
// inversion off above the bandwidth f_b (their gain falls as sinc and sinc^2 beyond it), so noise
// and unmodelled modes are not amplified and a step reference gives a bounded target. What is
// inverted: the delay (by preview) and the dynamics (by the reference's derivatives); hysteresis,
// creep and rate dependence are the static inverse's (make_inverse) part. target() is real-time
// safe; the caller samples the reference at the three times.
#include <string>

#include "hystbench/compensation/actuator_model.hpp"

namespace hystbench::compensation {

class DynamicsInversion {
 public:
  /// dt_s > 0 the loop period. The roll-off: the model's own
  /// dynamics.feedforward_bandwidth_hz when set, else bandwidth_hz when > 0 (the bench's
  /// [loop] feedforward_bandwidth_hz), else min(loop rate / 4, 2 x the natural frequency).
  /// Throws std::invalid_argument for dt_s <= 0.
  DynamicsInversion(const ActuatorModel& model, double dt_s, double bandwidth_hz = 0.0);

  /// True when the model has a delay or dynamics to invert.
  bool active() const noexcept { return delay_samples_ > 0.0 || dynamics_; }
  /// Where to sample the reference, relative to the tick's time [s]: at lead - h, lead, lead + h.
  double lead_s() const noexcept { return lead_s_; }
  double step_s() const noexcept { return h_s_; }
  /// Samples of preview the inversion needs (ceil((lead + h) / dt)).
  int preview_samples() const noexcept { return preview_; }
  double bandwidth_hz() const noexcept { return bandwidth_hz_; }

  /// The static target from the reference at t + lead - h, t + lead, t + lead + h.
  double target(double r_before, double r_at, double r_after) const noexcept {
    if (!dynamics_) return r_at;
    const double d1 = (r_after - r_before) * inv_2h_;
    const double d2 = (r_after - 2.0 * r_at + r_before) * inv_h2_;
    return r_at + c1_ * d1 + c2_ * d2;
  }

  /// "delay 2 samples (preview), dynamics 3000 Hz / 0.08 (reference derivatives, rolled off
  /// above 2500 Hz)" or "nothing (a static model)".
  std::string describe() const;

 private:
  double dt_;
  double lead_s_ = 0.0;
  double h_s_ = 0.0;
  double bandwidth_hz_ = 0.0;
  bool dynamics_ = false;
  double c1_ = 0.0, c2_ = 0.0;          // 2 zeta / wn, 1 / wn^2
  double inv_2h_ = 0.0, inv_h2_ = 0.0;  // 1 / 2h, 1 / h^2
  int preview_ = 0;
  double delay_samples_ = 0.0;
  DynamicsParameters p_;
};

}  // namespace hystbench::compensation
