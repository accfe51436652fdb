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

}  // namespace hystbench::compensation
