#pragma once
// The bench's identification fit: the loop's full-rate record (output u [V], measurement y [µm],
// one sample per tick) is block-averaged down to the fit rate and fitted, with a whole-tick input
// delay chosen on the full-rate record. The delay must be taken out before averaging: a 1-2
// tick delay (a thread-mode Modbus exchange, a CAN feedback frame) is a fraction of a fit
// sample after averaging, which no fitted delay can represent and the hysteresis absorbs as
// extra loop width instead.
// Not real-time: allocates and runs the fits (each tick of delay tried costs one fixed-order
// least-squares fit; the chosen delay one full fit).
#include <cstddef>
#include <span>
#include <vector>

#include "hystbench/compensation/identification.hpp"

namespace hystbench::daemon {

/// The record block-averaged by `block` ticks with y advanced by `shift` ticks (u[k] paired
/// with y[k + shift]); t starts at 0, one averaged sample every block * dt_s.
struct AveragedRecord {
  std::vector<double> t, u, y;
};
AveragedRecord block_average(std::span<const double> u, std::span<const double> y, double dt_s,
                             std::size_t block, std::size_t shift);

struct IdentificationFit {
  compensation::FitResult fit;  ///< the model carries the delay (set_delay(ticks * dt_s))
  int delay_ticks = 0;
  /// Held-out rms error [µm] of the fixed-order fit at each delay tried, index = ticks.
  std::vector<double> delay_heldout_rmse;
};

/// Fits `options` (its delay_samples is ignored) to the record averaged by `block`, with the
/// input delay in ticks 0..max_delay_ticks that gives the lowest held-out error. A delay is
/// kept only when the full fit at that delay beats the one without.
/// Throws std::invalid_argument as compensation::fit_model does.
IdentificationFit fit_identification_record(std::span<const double> u, std::span<const double> y,
                                            double dt_s, std::size_t block,
                                            compensation::FitOptions options, int max_delay_ticks);

}  // namespace hystbench::daemon
