#pragma once
// Incremental PID (multilayer-actuator paper, eq. 22), added to a feedforward: u = u_ff + u_fb.
//   u_fb(k) = u_fb(k-1) + Kp [e(k) - e(k-1)] + Ki T e(k) + (Kd/T) [ef(k) - 2 ef(k-1) + ef(k-2)]
// with ef the error through a first-order low-pass (derivative filter), u_fb clamped to
// [output_min, output_max] and anti-windup: the integral increment is dropped while the output
// (or the stage after it, see set_saturation()) is saturated in the direction it would push.
// The output may pass a first-order low-pass (output_filter_hz): it keeps the feedback's per-tick
// changes small, so an actuator whose gain grows with |du/dt| does not see them as rate.
// Units: u_fb in the unit of whatever it is added to, per unit of error: V/µm added to a drive,
// 1 (Kp), 1/s (Ki) and s (Kd) added to a feedforward's target. step() is real-time safe.
#include <complex>
#include <cstdint>

namespace hystbench::compensation {

struct PidParameters {
  double kp = 0.0;                    ///< [V/µm]
  double ki = 0.0;                    ///< [V/(µm s)]
  double kd = 0.0;                    ///< [V s/µm]
  double derivative_filter_hz = 0.0;  ///< 0 = unfiltered derivative
  double output_min = -1e300;         ///< clamp of u_fb [V]
  double output_max = 1e300;
  double output_filter_hz = 0.0;  ///< low-pass of u_fb; 0 = none; below the Nyquist frequency
};

class PidController {
 public:
  /// Throws std::invalid_argument for NaN gains, dt <= 0 or output_min > output_max.
  PidController(PidParameters p, double dt_s);

  /// Advances one sample with error e = y_ref - y; returns u_fb.
  double step(double error) noexcept;
  /// Tells the controller the stage after it clamped the total output: +1 high, -1 low, 0 none.
  void set_saturation(int direction) noexcept { external_saturation_ = direction; }
  /// Clears the history; the output restarts at `initial_output` (clamped).
  void reset(double initial_output = 0.0) noexcept;

  double output() const noexcept { return out_; }
  /// True while u_fb sits at output_min or output_max (before the output filter).
  bool saturated() const noexcept { return u_ >= p_.output_max || u_ <= p_.output_min; }
  const PidParameters& parameters() const noexcept { return p_; }
  /// The linear response u_fb / e at f_hz (no clamp, no saturation): its discrete transfer
  /// function at z = exp(j 2 pi f dt).
  std::complex<double> response(double f_hz) const noexcept;
  /// The same at z^-1 = z_inverse (|z_inverse| = 1 for a frequency).
  std::complex<double> response_at(std::complex<double> z_inverse) const noexcept;

 private:
  PidParameters p_;
  double dt_;
  double alpha_ = 1.0;  // derivative filter coefficient
  double u_ = 0.0;      // the incremental PID's state
  double out_ = 0.0;    // u_ through the output filter
  double beta_ = 1.0;
  double e1_ = 0.0;
  double ef_ = 0.0, ef1_ = 0.0, ef2_ = 0.0;
  int external_saturation_ = 0;
  std::uint64_t samples_ = 0;
};

}  // namespace hystbench::compensation
