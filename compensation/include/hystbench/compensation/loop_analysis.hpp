#pragma once
// The feedback loop on a measured frequency response: L(f) = C(f) z^-1 P(f), the controller C
// (feedback_controller.hpp) answering each reading on the tick after it, P the response the
// feedback sees (feedback_plant.hpp). From L on the response's lines:
//   - stability by the Nyquist criterion for a stable plant: the winding of 1 + L from the
//     lowest line (where an integral loop starts at -90 degrees) to the Nyquist frequency, the
//     plant held at its last measured line beyond it; the lines are subdivided so that the
//     curve's chords stay short;
//   - the gain margin: -20 log10 |L| where L crosses the negative real axis, the smallest of
//     those crossings (one left of -1 counts as a negative margin);
//   - the phase margin: 180 + arg L where |L| crosses 1, the smallest; the crossover is the
//     lowest of those crossings;
//   - the peak of |S| = 1 / |1 + L|; the error-rejection bandwidth, where |S| first rises to
//     -3 dB (below it the loop takes out more than a third of an error), and where it first
//     rises to -20 dB (below it, nine tenths); the closed-loop bandwidth, where
//     |T| = |L / (1 + L)| first falls below -3 dB.
// Pure maths; allocates: not real-time.
#include <complex>
#include <limits>
#include <span>
#include <vector>

#include "hystbench/compensation/feedback_controller.hpp"
#include "hystbench/compensation/measured_response.hpp"

namespace hystbench::compensation {

struct LoopTargets {
  double gain_margin_db = 6.0;       ///< at least
  double phase_margin_deg = 45.0;    ///< at least
  double peak_sensitivity_db = 6.0;  ///< at most
};

struct LoopMargins {
  bool stable = false;
  int unstable_poles = 0;  ///< of the closed loop, from the winding (0 when stable)
  double gain_margin_db = std::numeric_limits<double>::infinity();  ///< inf: no crossing
  double gain_margin_hz = 0.0;                                      ///< 0: none
  double phase_margin_deg = std::numeric_limits<double>::infinity();
  double crossover_hz = 0.0;  ///< the lowest |L| = 1 [Hz]; 0: |L| never reaches 1
  double peak_sensitivity_db = 0.0;
  double peak_sensitivity_hz = 0.0;
  double bandwidth_hz = 0.0;            ///< |T| first below -3 dB [Hz]; 0: never above it
  double rejection_bandwidth_hz = 0.0;  ///< |S| first at -3 dB [Hz]; 0: above it everywhere
  double tenfold_rejection_hz = 0.0;    ///< |S| first at -20 dB [Hz]; 0: above it everywhere
};

/// Whether m is stable and meets every target.
bool meets(const LoopMargins& m, const LoopTargets& targets) noexcept;

/// L at each of plant's lines, and at the Nyquist frequency last (the plant held there). With
/// `controller_response`, C at the same frequencies goes there too.
std::vector<std::complex<double>> loop_response(
    const MeasuredResponse& plant, const FeedbackController& controller, double dt_s,
    std::vector<std::complex<double>>* controller_response = nullptr);

/// The margins of the loop whose response at plant's lines is loop_response(plant, c, dt);
/// `integrator`: C has a pole at z = 1 (ki > 0).
LoopMargins loop_margins(const MeasuredResponse& plant, std::span<const std::complex<double>> loop,
                         bool integrator, double dt_s);

/// Both in one: the margins of controller c on plant.
LoopMargins loop_margins(const MeasuredResponse& plant, const FeedbackController& c, double dt_s);

}  // namespace hystbench::compensation
