#pragma once
// The delay and second-order dynamics that a record's responses to its input steps show. Over
// a window around a step the static part of any hysteresis model is a jump at the step's sample,
// so the output there is a + b x(t) + c t, with x the input through the delay and the dynamics:
// the timing is fitted there apart from the loop's shape, which on the rest of a record a delay
// partly stands for (both lag the output behind du/dt), and to a fraction of a sample, which a
// fast reference's feedforward needs (a tenth of a sample is 1.8 degrees at 500 Hz and 10 kHz).
// Not real-time: allocates.
#include <cstddef>
#include <optional>
#include <span>

namespace hystbench::compensation {

struct StepTiming {
  double natural_frequency_hz = 0.0;  ///< > 0
  double damping_ratio = 0.0;         ///< 0.003 .. 1
  double delay_samples = 0.0;         ///< >= 0, a fraction of a sample included
  double rms = 0.0;                   ///< residual rms over the windows [output unit]
  std::size_t steps = 0;              ///< windows fitted
};

/// u, y sampled every dt_s > 0 (same length). The windows: every input step (a one-sample jump
/// of more than 1 % of the input's span and three times the neighbouring increments) with the
/// input held from 5 samples before it to at least 20 after, each up to 30 ms or, for a slow
/// mode, 12 periods of start's frequency / 4. Fits the delay within +-2.5 samples of start's,
/// the natural frequency from a quarter of start's to 0.45 of the sample rate, any damping.
/// std::nullopt when there is no such step.
std::optional<StepTiming> fit_step_timing(std::span<const double> u, std::span<const double> y,
                                          double dt_s, const StepTiming& start);

}  // namespace hystbench::compensation
