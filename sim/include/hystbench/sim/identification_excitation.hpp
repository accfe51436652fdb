#pragma once
// The standard identification excitation: one input record that covers what the diagnosis and
// the identification need, in this order (default about 34 s):
//   settle       (only with settle_s > 0) a hold at mid-range: creep lags approach the level
//                the record works around, whatever ran before
//   precondition (only with precondition_s > 0) one sweep from there to range_max and down to
//                range_min at one rate: wipes the hysteresis memory, so every record starts
//                in the same state (the descending major-loop branch at range_min)
//   major_loop   full-range cycles from range_min (without a precondition sweep the first is
//                the virgin loading curve of a relaxed actuator)
//   minor_loops  nested loops of linearly decaying amplitude, all turning at range_min
//                (multilayer paper, eq. 12 shape)
//   rate_<f>hz   cycles at each rate frequency (default 0.5, 2 and 10 Hz)
//   reversals    constant-rate ramps with sharp reversals at scattered turning points
//   hold_<k>     steps held long enough to see creep (and the step response)
// With the default options every segment but the holds starts and ends at range_min, so the
// segments join without jumps up to the holds, and the record ends at range_min.
// reversals_last swaps the last two (holds, then reversals from range_min).
// Not real-time: allocates.
#include <cstddef>
#include <string>
#include <vector>

namespace hystbench::sim {

struct ExcitationSegment {
  std::string name;
  std::size_t begin = 0;  ///< first sample
  std::size_t end = 0;    ///< one past the last sample
};

struct Excitation {
  double dt_s = 0.0;
  std::vector<double> samples;              ///< input [range unit], one per dt_s
  std::vector<ExcitationSegment> segments;  ///< contiguous, in time order, cover every sample

  /// The segment named `name`, or nullptr.
  const ExcitationSegment* find(const std::string& name) const noexcept;
};

struct IdentificationExcitationOptions {
  /// Duration of the precondition sweep [s]; 0 = none. A fit should simulate but not score it,
  /// nor the settle hold.
  double precondition_s = 0.0;           ///< >= 0
  double settle_s = 0.0;                 ///< hold at mid-range before the sweep [s], >= 0
  double major_loop_frequency_hz = 0.5;  ///< > 0
  int major_loop_cycles = 2;             ///< >= 1
  double minor_loop_frequency_hz = 1.0;  ///< loops per second, > 0
  int minor_loops = 8;                   ///< >= 0
  /// Rate segments: each is `rate_cycles` cycles over `rate_span_fraction` of the range.
  std::vector<double> rate_frequencies_hz = {0.5, 2.0, 10.0};
  std::vector<int> rate_cycles = {2, 4, 10};  ///< one per frequency, >= 1
  double rate_span_fraction = 0.8;            ///< (0, 1]
  /// Reversals: turning points as fractions of the range, visited at constant rate.
  std::vector<double> reversal_points = {0.8, 0.3, 0.9, 0.5, 0.7, 0.2, 1.0, 0.6, 0.0};
  double reversal_rate_fraction_per_s = 2.0;  ///< ramp speed, range fractions per second, > 0
  /// Holds: levels as fractions of the range, each held hold_s.
  std::vector<double> hold_levels = {0.5, 1.0, 0.25, 0.0};
  double hold_s = 2.5;  ///< > 0
  /// Reversals after the holds: the record then ends with sharp reversals (the loop's shape)
  /// instead of creep holds, so a fit holding out its end judges the shape a tracking run sees.
  bool reversals_last = false;
  /// Fewest samples per period of the fastest cycle; a coarser dt_s throws.
  int min_samples_per_period = 20;
};

/// Throws std::invalid_argument naming the argument or option on bad input.
Excitation identification_excitation(double range_min, double range_max, double dt_s,
                                     const IdentificationExcitationOptions& options = {});

}  // namespace hystbench::sim
