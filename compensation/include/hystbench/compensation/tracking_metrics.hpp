#pragma once
// Figures of a tracking run: error statistics, the hysteresis left in y against y_ref, and how y
// answers the reference's steps.
#include <cstddef>
#include <span>

namespace hystbench::compensation {

/// Loop width of y against the reference, as the papers measure it: at each reference level
/// (100 levels over the middle 90 % of the reference span) the mean y on falling passes minus
/// the mean y on rising passes; the largest absolute difference, in % of the y range.
/// Returns 0 when the reference never both rises and falls through a level.
double hysteresis_percent(std::span<const double> y_ref, std::span<const double> y);

/// The same width in output units.
double hysteresis_width(std::span<const double> y_ref, std::span<const double> y);

/// How many samples y lags y_ref, to a fraction of one: the shift of the reference that best
/// explains the error in least squares, to first order (y - y_ref - mean against the reference's
/// slope per sample; positive: y lags). On a sine over whole periods it is the fundamental's phase
/// error over its angular frequency per sample; the loop's shape, whose error is in phase with
/// the reference or in its harmonics, does not move it. 0 when y_ref does not move. Allocates
/// nothing; O(n).
double output_lag_samples(std::span<const double> y_ref, std::span<const double> y);

/// How y answered the steps of y_ref: its moves of at least min_step from one level it holds to
/// the next (a jump, or a shaped move over several samples). Per step its overshoot beyond the
/// new level (a fraction of the step; 0 when y never passes it) and its settling time: from the
/// move's first sample to the first one after which y stays within `band` x the step of the new
/// level until the next move or the end (a step whose y is still outside then is not settled).
/// Figures over every step; all zero without a step.
struct StepFigures {
  std::size_t steps = 0;
  double mean_size = 0.0;       ///< mean |step| [output unit]
  double max_settling_s = 0.0;  ///< the longest settling time [s]
  double mean_settling_s = 0.0;
  double max_overshoot = 0.0;  ///< the largest overshoot, a fraction of its step
  double mean_overshoot = 0.0;
  bool settled = true;  ///< every step settled before the next (or the end)
};
StepFigures step_figures(std::span<const double> y_ref, std::span<const double> y, double dt_s,
                         double min_step, double band = 0.01);

}  // namespace hystbench::compensation
