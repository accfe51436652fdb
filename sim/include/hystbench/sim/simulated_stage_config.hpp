#pragma once
// The truth of a simulated stage of several axes (XY scanner, tip-tilt mirror): one simulated
// actuator per axis, each with its own hysteresis, creep, modes and sensor, and a coupling
// between them: the stroke of axis j reaches axis i's displacement with the DC gain
// gains[i][j] through a mode the axes share (SimulatedStage). Units: V in, µm out, Hz.
// The default (xy()) is a two-axis stage whose axes differ in hysteresis, creep and modes and
// couple at -20 dB (x to y) and -25 dB (y to x) through a shared mode at 1.5 kHz.
// Plain data; validate() and the JSON conversions allocate and throw: off the real-time path.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "hystbench/sim/simulated_actuator_config.hpp"

namespace hystbench::sim {

/// Axes a stage may have: [1, kMaxStageAxes].
inline constexpr std::size_t kMaxStageAxes = 6;

/// An axis name: 1 to 16 of a-z, 0-9 and _ ("x", "tip"), as the log's columns and the request
/// keys name axes. Every place that takes axis names (a stage, a driver of several) checks it.
bool is_axis_name(std::string_view name) noexcept;

struct StageAxisConfig {
  std::string name;  ///< [a-z0-9_], 1..16 characters, unique in the stage ("x", "tip")
  SimulatedActuatorConfig actuator;
};

struct StageCouplingConfig {
  bool enabled = true;
  /// gains[i][j] (i != j): the share of axis j's stroke (its displacement before its own modes)
  /// that reaches axis i's displacement at DC [µm/µm], |.| <= 0.5; the diagonal is 0. Empty:
  /// no coupling. -20 dB is 0.1.
  std::vector<std::vector<double>> gains;
  /// The mode every cross path passes through: unit DC gain, resonant at shared_mode_hz.
  double shared_mode_hz = 1500.0;      ///< > 0 [Hz]
  double shared_damping_ratio = 0.08;  ///< > 0
};

struct SimulatedStageConfig {
  /// Axes x and y: x as SimulatedActuatorConfig's defaults; y with narrower, higher-centred
  /// relays, more creep and lower modes; coupled x to y at 0.1 (-20 dB) and y to x at 0.056
  /// (-25 dB) through a mode at 1.5 kHz, damping 0.08. Sensor noise and drift seeds differ.
  static SimulatedStageConfig xy();

  std::vector<StageAxisConfig> axes;
  StageCouplingConfig coupling;
};

/// Throws std::invalid_argument naming the field ("axes[1].name: ...", "coupling.gains[0][1]:
/// ..."); each axis's actuator as sim::validate, its errors prefixed with "axes[i].actuator.".
void validate(const SimulatedStageConfig& config);

/// {"axes": [{"name": "x", "actuator": {...}}, ...], "coupling": {...}}.
nlohmann::json to_json(const SimulatedStageConfig& config);
/// Without "axes": xy()'s axes. Each axis's "actuator" starts from SimulatedActuatorConfig's
/// defaults (sim::from_json); where it sets no seed, axis i's sensor noise seed is 1 + 2 i and
/// its drift seed 2 + 2 i, so no two axes share their noise. Without "coupling": none for axes
/// given, xy()'s for xy()'s axes; its keys override the defaults. Unknown keys, wrong types and
/// invalid values throw std::invalid_argument naming the key path; then validate().
SimulatedStageConfig stage_from_json(const nlohmann::json& j);

}  // namespace hystbench::sim
