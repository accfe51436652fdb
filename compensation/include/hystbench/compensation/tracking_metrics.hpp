#pragma once
// Figures of a tracking run: error statistics and the hysteresis left in y against y_ref.
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

}  // namespace hystbench::compensation
