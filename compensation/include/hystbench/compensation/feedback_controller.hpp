#pragma once
// The bench's feedback: an optional low-frequency boost of the error, the incremental PID
// (pid_controller.hpp), then its loop shaping (shaping_filter.hpp: notches at the modes, a
// low-pass), and beside them resonators at a periodic reference's harmonics, if any
// (harmonic_resonators.hpp):
//   v = F(z) PID(z) B(z) e + R(z) e,   e = y_ref - y,   B(s) = (s + w_b) / (s + w_b / gain)
// B lifts the loop's gain below w_b by up to `gain` (an integral loop's |S| then falls as f^2
// below it) and is 1 well above it; before the PID, so that its anti-windup holds the whole
// integral.
// Behind a feedforward v corrects the feedforward's target [output unit] (compensator.hpp), so
// the gains are per unit of error: kp [1], ki [1/s], kd [s]. Anti-windup acts on the PID's
// integral and holds the resonators (the stage after the shaping clamps through
// set_saturation()).
// Construction validates and throws std::invalid_argument; step() and reset() are real-time safe.
#include <complex>

#include "hystbench/compensation/harmonic_resonators.hpp"
#include "hystbench/compensation/pid_controller.hpp"
#include "hystbench/compensation/shaping_filter.hpp"

namespace hystbench::compensation {

struct LowFrequencyBoost {
  double frequency_hz = 0.0;  ///< w_b / (2 pi), in (0, 0.5 / dt) [Hz]; 0 = none
  double gain = 10.0;         ///< the boost at DC, > 1
};

struct FeedbackLaw {
  LowFrequencyBoost boost;
  PidParameters pid;
  ShapingFilterSpec shaping;
  HarmonicResonatorsSpec harmonics;  ///< none unless a periodic reference's run adds them
};

class FeedbackController {
 public:
  FeedbackController(const FeedbackLaw& law, double dt_s);

  /// One sample: the error of the last completed tick in, v out. NaN holds the output.
  double step(double error) noexcept;
  /// +1 high, -1 low, 0 none: the stage after the controller clamped (anti-windup).
  void set_saturation(int direction) noexcept {
    pid_.set_saturation(direction);
    resonators_.set_frozen(direction != 0);
  }
  /// Restarts from v = 0 (PID and shaping settled there).
  void reset() noexcept;
  /// The resonators alone from rest: what they integrated up to now (a start from rest, which
  /// does not repeat) no longer drives them.
  void restart_harmonics() noexcept { resonators_.reset(); }
  double output() const noexcept { return out_; }
  /// The PID's output at its clamp (before the shaping).
  bool saturated() const noexcept { return pid_.saturated(); }
  /// v / e at f_hz, linear (no clamp): boost, PID, shaping and resonators, at
  /// z = exp(j 2 pi f dt).
  std::complex<double> response(double f_hz) const noexcept;
  /// The same at z^-1 = z_inverse (|z_inverse| = 1 for a frequency).
  std::complex<double> response_at(std::complex<double> z_inverse) const noexcept;
  const FeedbackLaw& law() const noexcept { return law_; }

 private:
  FeedbackLaw law_;
  double dt_;
  // The boost's first-order section, bilinear: y = b0 x + b1 x1 - a1 y1.
  double b0_ = 1.0, b1_ = 0.0, a1_ = 0.0, x1_ = 0.0, y1_ = 0.0;
  PidController pid_;
  ShapingFilter shaping_;
  HarmonicResonators resonators_;
  double out_ = 0.0;
};

}  // namespace hystbench::compensation
