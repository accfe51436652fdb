#pragma once
// The drive that measures a stage's frequency response in place (compensation's
// frequency_response.hpp estimates it): a sweep to the drive's top and bottom (the hysteresis
// memory wiped, as every run starts), then at each condition a ramp to its operating point, a
// short hold, and a multisine around it: `transient_periods` periods that settle, then
// `periods` that are averaged. The multisine excites about `lines` DFT lines of one period, log
// spaced from the first to top_fraction of the rate (every line where they are denser than
// that), with Schroeder phases (a low crest factor) and its peak at the condition's amplitude,
// less where the slew limit needs it. Its period is max(500, rate x 0.1 s) samples: 2 Hz lines
// at 1 kHz, 10 Hz at 10 kHz. The default conditions (2 % of the span at a quarter, half and
// three quarters of it, 8 % at half) take 4 s at 10 kHz and 12 s at 1 kHz.
// Then the stage while it moves: ramps across the middle of the span, alternately up and down,
// each carrying a small sine of a fiftieth of the rate over whole cycles, its peak rate half the
// ramp's so that the motion never turns; the first ramp settles, four follow (0.2 s at 10 kHz,
// 2 s at 1 kHz). A rate law acts only while the stage moves: its zero shows as one direction's
// ramps lagging the other's at the sine (compensation's moving_response.hpp).
// Deterministic: the same options give the same drive. Not real-time: allocates.
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "hystbench/compensation/moving_response.hpp"

namespace hystbench::sim {

struct ResponseCondition {
  double operating_fraction = 0.5;   ///< of the drive span, in [0, 1]
  double amplitude_fraction = 0.02;  ///< the multisine's peak, of the span, in (0, 0.5]
};

struct FrequencyResponseExcitationOptions {
  double rate_hz = 10000.0;           ///< > 0
  double u_min = 0.0, u_max = 150.0;  ///< the drive range [V], u_min < u_max
  double u_start = 0.0;               ///< the present output [V]
  double slew_v_per_s = std::numeric_limits<double>::infinity();  ///< > 0
  double precondition_s = 1.0;  ///< the sweep to u_max and u_min first [s]; 0: none
  std::vector<ResponseCondition> conditions = {
      {0.25, 0.02}, {0.5, 0.02}, {0.75, 0.02}, {0.5, 0.08}};
  std::size_t periods = 4;            ///< averaged, >= 2
  std::size_t transient_periods = 1;  ///< played first, not averaged
  std::size_t lines = 200;            ///< about this many excited lines, >= 4
  double top_fraction = 0.45;         ///< the highest line, of the rate, in (0, 0.5)
  double move_s = 0.1;                ///< the ramp to each operating point [s], >= 0
  double hold_s = 0.1;                ///< the hold after it [s], >= 0
  /// The moving part: its sine's frequency over the rate, in [0, 0.25); 0 = none.
  double moving_tone_fraction = 0.02;
  std::size_t moving_cycles =
      8;  ///< the sine's whole cycles per ramp (more if the slew limit needs), >= 2
  std::size_t moving_ramps = 4;  ///< averaged after the first, even (half of each direction), >= 2
  double moving_from = 0.25;     ///< the ramps' lower end, of the span, in [0, 1)
  double moving_to = 0.75;       ///< their upper end, of the span, in (moving_from, 1]
};

struct MovingExcitation {
  double tone_hz = 0.0;       ///< the sine's frequency [Hz] (whole cycles per ramp)
  double amplitude_v = 0.0;   ///< its peak [V]
  double ramp_v_per_s = 0.0;  ///< the ramps' rate [V/s]
  /// The averaged ramps, in order (compensation's moving_response.hpp reads them); empty: none.
  std::vector<compensation::MovingRamp> ramps;
};

struct ResponseMeasurementSegment {
  std::size_t first = 0;    ///< the first averaged sample
  std::size_t periods = 0;  ///< averaged periods from `first` on
  double operating_point_v = 0.0;
  double amplitude_v = 0.0;  ///< the multisine's peak [V]
  std::string label;         ///< e.g. "25 % of the span, 2 % peak"
};

struct FrequencyResponseExcitation {
  std::vector<double> u;           ///< the drive, one value per tick [V]
  std::size_t period = 0;          ///< the multisine's period [samples]
  std::vector<std::size_t> lines;  ///< its excited DFT lines of one period, increasing
  std::vector<ResponseMeasurementSegment> segments;  ///< one per condition, in order
  MovingExcitation moving;                           ///< after the conditions
};

/// Throws std::invalid_argument naming the option.
FrequencyResponseExcitation make_frequency_response_excitation(
    const FrequencyResponseExcitationOptions& o);

}  // namespace hystbench::sim
