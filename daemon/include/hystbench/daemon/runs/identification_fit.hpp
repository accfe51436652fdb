#pragma once
// The bench's identification fit: the loop's full-rate record (output u [V], measurement y [µm],
// one sample per tick) is block-averaged down to the fit rate and fitted, with the measurement
// delay in whole ticks. Two parts:
//   - the driver's exchange latency, known per reading (Measurement::response_ticks): y is
//     aligned to the output each reading answers, so a latency that jitters (a thread-mode
//     Modbus exchange late now and then) leaves no trace in the record;
//   - any further delay (plant, transport), chosen on the full-rate record before averaging: a
//     1-2 tick delay is a fraction of a fit sample after averaging, which no fitted delay can
//     represent and the hysteresis absorbs as extra loop width instead.
// The model's delay is the sum: what the bench sees from write() to read().
// Not real-time: allocates and runs the fits (each tick of delay tried costs one fixed-order
// least-squares fit; the chosen delay one full fit).
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/identification.hpp"
#include "hystbench/daemon/loop/run_program.hpp"

namespace hystbench::daemon {

/// The record block-averaged by `block` ticks with y advanced by `shift` ticks (u[k] paired
/// with y[k + shift]); t starts at 0, one averaged sample every block * dt_s.
struct AveragedRecord {
  std::vector<double> t, u, y;
};
AveragedRecord block_average(std::span<const double> u, std::span<const double> y, double dt_s,
                             std::size_t block, std::size_t shift);

/// No fresh reading in that tick.
inline constexpr std::uint32_t kNoAnswer = RunRecords::kNoFreshReading;

/// y aligned to the output it answers: a fresh reading at k with response r is the answer to
/// u[k - r]. Outputs whose answer never came (stale ticks, an answer overtaken by the next one)
/// are interpolated in u between the nearest answered neighbours (exact across a step, linear
/// on a ramp); the ends hold. Returns y as it is when no reading is fresh.
std::vector<double> align_to_outputs(std::span<const double> u, std::span<const double> y,
                                     std::span<const std::uint32_t> response);

/// The median response_ticks of the fresh readings (0 without any).
int median_response_ticks(std::span<const std::uint32_t> response);

struct IdentificationFit {
  compensation::FitResult fit;  ///< the model carries delay_ticks (set_delay(ticks * dt_s))
  /// The model's input delay [ticks]: exchange_ticks plus the delay fitted on the aligned record.
  int delay_ticks = 0;
  /// The driver's median exchange latency [ticks] (the readings' response_ticks).
  int exchange_ticks = 0;
  /// Held-out rms error [µm] of the fixed-order fit at each further delay tried, index = ticks.
  std::vector<double> delay_heldout_rmse;
  /// How the delay was chosen, in words (for the identify report).
  std::string delay_note;
};

/// True when a fit at a longer delay is better than the one without: lower held-out AND lower
/// fit-part rms error. A delay adds no unknown, so the fit part (nine tenths of the record) must
/// agree; the held-out tenth alone scores near-equal delays by chance.
bool delayed_fit_is_better(const compensation::FitResult& without,
                           const compensation::FitResult& with);

/// Fits `options` (its delay_samples is ignored) to the record averaged by `block`: y aligned
/// by `response` (empty: every reading answers its own tick), then the further delay in ticks
/// 0..max_delay_ticks with the lowest held-out error, kept only when the full fit at that delay
/// beats the one without (delayed_fit_is_better); a Preisach plane's rate law found without the
/// delay is refitted at it, not searched for again. Throws std::invalid_argument as
/// compensation::fit_model does.
IdentificationFit fit_identification_record(std::span<const double> u, std::span<const double> y,
                                            std::span<const std::uint32_t> response, double dt_s,
                                            std::size_t block, compensation::FitOptions options,
                                            int max_delay_ticks);

}  // namespace hystbench::daemon
