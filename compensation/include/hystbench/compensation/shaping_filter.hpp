#pragma once
// The feedback's loop shaping after its PID: notch filters at the stage's modes and a
// second-order low-pass, each a second-order section designed in continuous time and mapped by
// the bilinear transform, prewarped at its own frequency (a notch sits exactly where it is put):
//   notch     N(s) = (s^2 + 2 depth zeta w0 s + w0^2) / (s^2 + 2 zeta w0 s + w0^2)
//   low-pass  P(s) = w0^2 / (s^2 + 2 zeta w0 s + w0^2)
// zeta sets a notch's width (its -3 dB band is about 2 zeta w0 wide), depth its gain at w0.
// Every section has unit gain at DC. Construction validates and throws std::invalid_argument
// naming the field; step() and reset() are real-time safe (no allocation, fixed capacity).
#include <array>
#include <complex>
#include <cstddef>
#include <vector>

namespace hystbench::compensation {

struct Notch {
  double frequency_hz = 0.0;  ///< centre, in (0, 0.5 / dt) [Hz]
  double damping = 0.3;       ///< width: the poles' damping ratio, in (0, 2]
  double depth = 0.1;         ///< gain at the centre, in (0, 1]
};

struct SecondOrderLowPass {
  double frequency_hz = 0.0;  ///< corner, in (0, 0.5 / dt) [Hz]; 0 = none
  double damping = 0.7071;    ///< in (0, 2]
};

struct ShapingFilterSpec {
  std::vector<Notch> notches;  ///< at most ShapingFilter::kMaxNotches
  SecondOrderLowPass low_pass;
  bool empty() const noexcept { return notches.empty() && low_pass.frequency_hz <= 0.0; }
};

class ShapingFilter {
 public:
  static constexpr std::size_t kMaxNotches = 3;

  /// Identity (no section).
  ShapingFilter() = default;
  /// dt_s > 0 [s]. Throws std::invalid_argument naming the section and the field.
  ShapingFilter(const ShapingFilterSpec& spec, double dt_s);

  /// One sample through every section. Real-time safe.
  double step(double x) noexcept;
  /// Every section settled at input x0 (its output x0: unit DC gain).
  void reset(double x0 = 0.0) noexcept;
  /// The sections' response at f_hz, their discrete transfer function at z = exp(j 2 pi f dt).
  std::complex<double> response(double f_hz) const noexcept;
  /// The same at z^-1 = z_inverse (|z_inverse| = 1 for a frequency).
  std::complex<double> response_at(std::complex<double> z_inverse) const noexcept;
  std::size_t sections() const noexcept { return count_; }

 private:
  struct Section {
    double b0 = 1.0, b1 = 0.0, b2 = 0.0, a1 = 0.0, a2 = 0.0;  // a0 = 1
    double s1 = 0.0, s2 = 0.0;                                // transposed direct form II state
  };
  static Section bilinear(double w0, double dt, double n2, double n1, double n0, double d1,
                          double d0);
  std::array<Section, kMaxNotches + 1> sections_{};
  std::size_t count_ = 0;
  double dt_ = 1.0;
};

}  // namespace hystbench::compensation
