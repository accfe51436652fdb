#pragma once
// The truth of a simulated piezo actuator: one plain struct, one nested struct per effect, each
// with an `enabled` flag. Units: input in V, displacement in µm, time in s, frequency in Hz.
// The defaults resemble a 150 V stack: about 45 µm periodic major-loop range, about 17 %
// hysteresis (loop width at mid-input over range, full 0-150 V 1 Hz cycle), mild creep,
// resonance at 3 kHz (damping 0.08), 16-bit DAC and ADC, 5 nm rms sensor noise.
// Plain data; validate() and the JSON conversions allocate and throw, so call them off the
// real-time path.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string_view>
#include <vector>

#include "hystbench/compensation/rate_estimator.hpp"

namespace hystbench::sim {

/// Shape of the slow output-offset drift.
enum class DriftShape {
  kSinusoid,    ///< amplitude_um * sin(2 pi t / period_s)
  kRandomWalk,  ///< Gaussian random walk, clamped to +-random_walk_limit_um
};

/// "sinusoid", "random_walk".
std::string_view to_string(DriftShape shape) noexcept;

/// Uniform quantiser: 2^bits codes spread over [range_min, range_max]; values outside the range
/// clamp to its ends, as a real converter's do. Units are those of the quantised signal.
struct QuantizationConfig {
  bool enabled = true;
  int bits = 16;  ///< 1..32
  double range_min = 0.0;
  double range_max = 1.0;  ///< > range_min
};

struct SimulatedActuatorConfig {
  /// Amplifier input range; the inverse and controllers may not command outside it.
  struct Input {
    double min_v = 0.0;    ///< [V]
    double max_v = 150.0;  ///< [V], > min_v
  } input;

  /// Modified PI (Kuhnen): z = center + S[PI(u) - center]. Plays with thresholds r_i and
  /// weights w_i, then one-sided dead zones (thresholds relative to the center) for the
  /// asymmetry. Disabled: a linear map through the same periodic major-loop end points.
  /// reset(u0) relaxes every play at u0, so the first rising branch from input.min_v (the
  /// virgin curve) lies below the periodic major loop, as with a freshly powered stack.
  struct Hysteresis {
    bool enabled = true;
    std::vector<double> play_thresholds_v = {0.0,  7.5,  15.0, 22.5, 30.0,
                                             37.5, 45.0, 52.5, 60.0, 67.5};  ///< increasing
    std::vector<double> play_weights_um_per_v = {0.18, 0.02, 0.02, 0.02, 0.02,
                                                 0.02, 0.02, 0.02, 0.02, 0.02};
    double play_offset_um = -6.75;  ///< puts the periodic major loop at about 0..45 µm
    std::vector<double> dead_zone_thresholds_um = {-15.0, 0.0, 12.0};  ///< increasing, has 0
    std::vector<double> dead_zone_weights = {0.15, 1.0, 0.4};          ///< dimensionless
    double dead_zone_center_um = 21.0;                                 ///< [µm]
  } hysteresis;

  /// Rate-dependent modified PI (rate-dependent paper, eq. 15-21): the cumulative play weights
  /// become W_i + c_i * du/dt (rate_law "signed", eq. 16 as written) or W_i + c_i * |du/dt|
  /// ("magnitude"). The default is signed with c_i <= 0: the loading slope falls with the rate
  /// and the unloading one rises, so the loop widens with frequency (the paper's Fig. 1) the way
  /// a lag widens it, and the output stays smooth through a reversal. |du/dt| with c_i >= 0
  /// widens it too, but the weights jump back as the rate's magnitude turns: a corner in the
  /// output at every reversal, which no stage with mass shows. Needs hysteresis.enabled. The
  /// rate is the per-sample input rate, so an input step gives a one-sample weight spike: drive
  /// it with smooth inputs.
  struct RateDependence {
    bool enabled = false;
    compensation::RateLaw rate_law = compensation::RateLaw::kSigned;
    /// c_i, one per play [µm/V per V/s]; the default changes the wide plays' share of the slope
    /// by about 10 % per kV/s (every W_i + c_i rate must stay > 0 over the law's rates).
    std::vector<double> rate_coefficients = {0.0,   -2e-6,   -4e-6,   -6e-6,   -8e-6,
                                             -1e-5, -1.2e-5, -1.4e-5, -1.6e-5, -1.8e-5};
    /// Rate the truth's law holds to, capped beyond (>= 0) [V/s]: the rates of a 19 Hz sine
    /// over 80 % of the range (7.2 kV/s) are inside.
    double max_rate_v_per_s = 10000.0;
  } rate_dependence;

  /// Creep: a bank of first-order lags of the (delayed) input added to the hysteresis output.
  /// The default adds about 2 % of the range, log-spread over 0.05..50 s.
  struct Creep {
    bool enabled = true;
    std::vector<double> time_constants_s = {0.05, 0.5, 5.0, 50.0};  ///< > 0 [s]
    std::vector<double> gains_um_per_v = {0.0015, 0.0015, 0.0015, 0.0015};
  } creep;

  /// Second-order structural dynamics with unit DC gain.
  struct Dynamics {
    bool enabled = true;
    double natural_frequency_hz = 3000.0;  ///< f_n > 0 [Hz]
    double damping_ratio = 0.08;           ///< zeta > 0
  } dynamics;

  /// Pure transport delay of the input, rounded to whole samples.
  struct Delay {
    bool enabled = false;
    double delay_s = 2e-4;  ///< [0, 1] [s]
  } delay;

  /// Gaussian sensor noise added to the measured displacement (not to true_position()).
  struct SensorNoise {
    bool enabled = true;
    double rms_um = 0.005;  ///< >= 0 [µm]
    std::uint64_t seed = 1;
  } sensor_noise;

  /// DAC of the commanded voltage [V].
  QuantizationConfig dac{true, 16, 0.0, 150.0};
  /// ADC of the measured displacement [µm].
  QuantizationConfig adc{true, 16, -10.0, 60.0};

  /// Slow thermal drift of the output offset (part of the true position).
  struct ThermalDrift {
    bool enabled = false;
    DriftShape shape = DriftShape::kSinusoid;
    double amplitude_um = 0.2;                ///< sinusoid: >= 0 [µm]
    double period_s = 600.0;                  ///< sinusoid: > 0 [s]
    double random_walk_um_per_sqrt_s = 0.01;  ///< random walk: >= 0 [µm/sqrt(s)]
    double random_walk_limit_um = 0.5;        ///< random walk: > 0 [µm]
    std::uint64_t seed = 2;
  } thermal_drift;

  /// Amplifier rails: the input is clamped to [input.min_v, input.max_v].
  struct InputSaturation {
    bool enabled = true;
  } input_saturation;

  /// Mechanical stops: the true position is clamped to [min_um, max_um].
  struct DisplacementSaturation {
    bool enabled = false;
    double min_um = -5.0;  ///< [µm]
    double max_um = 50.0;  ///< [µm], > min_um
  } displacement_saturation;
};

/// Throws std::invalid_argument naming the field (e.g. "creep.gains_um_per_v[2]: ...").
/// Only enabled effects are checked, and always input and hysteresis (a disabled hysteresis
/// still derives its linear map from them).
void validate(const SimulatedActuatorConfig& config);

/// Every field, keys as the member names ({"dynamics": {"enabled": true, ...}, ...}).
nlohmann::json to_json(const SimulatedActuatorConfig& config);
/// Starts from the defaults and overrides the keys present; then validate(). Unknown keys,
/// wrong types and invalid values throw std::invalid_argument naming the key path.
SimulatedActuatorConfig from_json(const nlohmann::json& j);

}  // namespace hystbench::sim
