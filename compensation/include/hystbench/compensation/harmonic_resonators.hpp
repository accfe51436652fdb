#pragma once
// Resonators at a periodic reference's harmonics, beside the feedback loop (the internal-model
// principle). Each integrates the error's phasor at its frequency w_k and answers with it:
//   a_k(n) = a_k(n-1) + mu_k e(n) exp(-j w_k n),   v(n) = sum_k Re{ c_k a_k(n) exp(j w_k n) },
// the linear filter R_k(z) = (mu_k / 2) [c_k / (1 - e^{j w_k} z^-1) + conj(c_k) / (1 - e^{-j w_k}
// z^-1)], whose poles sit on the unit circle at +/- w_k: closed, the loop takes that harmonic out
// entirely; between harmonics its gain falls as mu_k over the distance. With c_k = 1 / G_k, G_k
// what v does to the error at w_k (the plant with the loop around it closed: z^-1 P S), the
// harmonic decays by about (1 - mu_k / 2) each tick (2 / mu_k ticks); with G_k's phase off by
// less than 90 degrees it still decays, slower by that angle's cosine. Each resonator's amplitude
// |c_k a_k| stays within amplitude_limit; set_frozen() stops the integration (anti-windup).
// Construction validates and allocates; step(), set_frozen() and reset() are real-time safe.
#include <complex>
#include <cstddef>
#include <limits>
#include <vector>

namespace hystbench::compensation {

struct HarmonicResonator {
  double frequency_hz = 0.0;            ///< w_k / (2 pi), in (0, 0.5 / dt) [Hz]
  std::complex<double> gain{1.0, 0.0};  ///< c_k, finite and nonzero
  double adaptation = 0.01;             ///< mu, in (0, 0.5] per tick
};

struct HarmonicResonatorsSpec {
  std::vector<HarmonicResonator> resonators;  ///< none: the filter outputs 0
  /// Each resonator's amplitude |c_k a_k|, at most [output unit]; > 0.
  double amplitude_limit = std::numeric_limits<double>::infinity();
  bool empty() const noexcept { return resonators.empty(); }
};

/// R_k(z) of one resonator at z^-1 = z_inverse, for a loop of period dt_s [s].
std::complex<double> resonator_response(const HarmonicResonator& r, double dt_s,
                                        std::complex<double> z_inverse) noexcept;

class HarmonicResonators {
 public:
  /// None: outputs 0.
  HarmonicResonators() = default;
  /// dt_s > 0 [s]. Throws std::invalid_argument naming the field.
  HarmonicResonators(const HarmonicResonatorsSpec& spec, double dt_s);

  /// One sample: the error in, the resonators' sum out. NaN holds the output.
  double step(double error) noexcept;
  /// While frozen the resonators hold their amplitudes (the drive at a bound).
  void set_frozen(bool frozen) noexcept { frozen_ = frozen; }
  /// Every amplitude back to 0 and the phase to that of tick 0.
  void reset() noexcept;
  /// R(z) at z^-1 = z_inverse (infinite at a resonator's own frequency).
  std::complex<double> response_at(std::complex<double> z_inverse) const noexcept;
  const HarmonicResonatorsSpec& spec() const noexcept { return spec_; }
  bool empty() const noexcept { return spec_.empty(); }

 private:
  struct State {
    std::complex<double> step;       // e^{j w dt}
    std::complex<double> phase;      // e^{j w n}
    std::complex<double> amplitude;  // a
  };
  HarmonicResonatorsSpec spec_;
  double dt_ = 1e-4;
  std::vector<State> states_;
  double out_ = 0.0;
  bool frozen_ = false;
  std::size_t ticks_ = 0;
};

}  // namespace hystbench::compensation
