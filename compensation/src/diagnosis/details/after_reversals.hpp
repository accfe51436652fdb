#pragma once
// A prediction's error right after the input's reversals (diagnosis internals): where a delay
// and a rate law, both lagging a ramp, predict differently. For d samples after a reversal a
// delay of d samples carries the output on in the old direction; a rate law's widened
// thresholds hold every play, so it holds the output at its turning value. Not real-time.
#include <cstddef>
#include <span>

#include "details/diagnosis_signals.hpp"
#include "diagnosis/details/record.hpp"

namespace hystbench::compensation::details {

struct WindowError {
  double rms = 0.0;         ///< rms of y - prediction over the window samples [output unit]
  std::size_t samples = 0;  ///< held-out samples in the windows
};

/// The held-out samples 1..window after every reversal of the input (steps left out): rms of
/// y - prediction there. `prediction` covers the whole record; window >= 1.
WindowError after_reversals_error(const DiagnosisRecord& r, const InputEvents& ev,
                                  std::span<const double> prediction, std::size_t window);

}  // namespace hystbench::compensation::details
