#pragma once
// Characterises a simulated actuator's truth on its full-range major loop: range and hysteresis
// (loop width at mid-input over range), as quoted in datasheets. Not real-time: builds an
// actuator and runs it for `cycles` periods.
#include "hystbench/sim/simulated_actuator_config.hpp"

namespace hystbench::sim {

struct MajorLoopMetrics {
  double min_um = 0.0;              ///< lowest true position over the last cycle [µm]
  double max_um = 0.0;              ///< highest true position over the last cycle [µm]
  double range_um = 0.0;            ///< max_um - min_um [µm]
  double width_at_mid_um = 0.0;     ///< descending minus ascending branch at mid-input [µm]
  double hysteresis_percent = 0.0;  ///< 100 * width_at_mid_um / range_um
};

/// Drives a fresh SimulatedActuator(config, dt_s) with `cycles` (>= 2) cosine cycles
/// input_min -> input_max -> input_min at frequency_hz and measures the last one on the
/// noise-free true_position(). Throws std::invalid_argument on bad arguments or config.
MajorLoopMetrics measure_major_loop(const SimulatedActuatorConfig& config, double dt_s,
                                    double frequency_hz = 1.0, int cycles = 3);

}  // namespace hystbench::sim
