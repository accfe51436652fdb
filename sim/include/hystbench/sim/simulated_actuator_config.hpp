#pragma once
// The truth of a simulated piezo actuator: one plain struct, one nested struct per effect, each
// with an `enabled` flag. Units: input in V, displacement in µm, time in s, frequency in Hz.
// The defaults resemble a 150 V stack, in physics that no model family of the bench contains
// (docs/simulator.md): Preisach hysteresis with a continuous relay density (a periodic major loop
// over about 0..45 µm with a saturating top; its measured range and width: docs/measurements.md),
// logarithmic creep of 1 % per decade, modes at 3 and 8 kHz, a 5 kHz sensor, 16-bit DAC and ADC,
// 5 nm rms sensor noise.
// Plain data; validate() and the JSON conversions allocate and throw, so call them off the
// real-time path.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string_view>
#include <vector>

#include "hystbench/compensation/rate_estimator.hpp"
#include "hystbench/sim/preisach_hysteresis.hpp"

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

/// What the hysteresis is: a Preisach model (the default; no model family contains it) or the
/// modified PI the bench fits (for tests that check exact recovery of a known model).
enum class HysteresisKind { kPreisach, kModifiedPi };
/// How the hysteresis depends on the input rate: Preisach relays behind a switching front
/// (SwitchingFront), Preisach relays whose thresholds widen with |du/dt| (RateWidenedPlay), or
/// play weights linear in du/dt (the rate-dependent modified PI's own law).
enum class RateMechanism { kSwitchingFront, kPlayWeights, kSwitchingThresholds };
/// How the output creeps: logarithmically in time after a change of the displacement (the
/// default), or as a few first-order lags of the input (the model families' creep operator).
enum class CreepLaw { kLogarithmic, kInputLags };

/// "preisach", "modified_pi"; "switching_front", "play_weights", "switching_thresholds";
/// "logarithmic", "input_lags".
std::string_view to_string(HysteresisKind kind) noexcept;
std::string_view to_string(RateMechanism mechanism) noexcept;
std::string_view to_string(CreepLaw law) noexcept;

struct SimulatedActuatorConfig {
  /// The modified-PI truth every model family can represent (kind modified_pi, play-weight rate
  /// law, creep lags of the input, one mode, no sensor filter): the actuator of the models
  /// themselves, for tests that recover a known model exactly. Otherwise as the defaults.
  static SimulatedActuatorConfig modified_pi_truth();

  /// Amplifier input range; the inverse and controllers may not command outside it.
  struct Input {
    double min_v = 0.0;    ///< [V]
    double max_v = 150.0;  ///< [V], > min_v
  } input;

  /// The static hysteresis map. Disabled: a linear map through the same periodic major-loop end
  /// points. reset(u0) relaxes it at u0, so the first rising branch from input.min_v (the
  /// virgin curve) lies below the periodic major loop, as with a freshly powered stack.
  struct Hysteresis {
    bool enabled = true;
    HysteresisKind kind = HysteresisKind::kPreisach;

    // --- kind preisach: y = offset + reversible (u - min_v) + Preisach[u_s] (PreisachHysteresis)
    // with u_s the input, or the switching front with rate dependence on. The relays cover
    // [input.min_v, input.max_v]; their density is lognormal in the half-width h_c and normal in
    // the centre h_b. The centres sit low in the range, so few relays are left to switch near the
    // top: the ascending branch saturates there and the loop is asymmetric.
    double coercive_median_v = 18.0;    ///< median relay half-width [V], > 0
    double coercive_spread = 0.55;      ///< std of ln(h_c), > 0
    double bias_mean_v = 55.0;          ///< mean relay centre [V]
    double bias_std_v = 45.0;           ///< spread of the relay centres [V], > 0
    double switching_um = 18.0;         ///< every relay down to every relay up [µm], > 0
    double reversible_um_per_v = 0.18;  ///< lattice strain, no hysteresis [µm/V], >= 0
    double offset_um = 0.0;             ///< output at input.min_v, relaxed [µm]
    int grid_points = 513;              ///< Everett table points per axis, [33, 4097]

    // --- kind modified_pi (Kuhnen): z = center + S[PI(u) - center]. Plays with thresholds r_i and
    // weights w_i, then one-sided dead zones (thresholds relative to the center) for asymmetry.
    std::vector<double> play_thresholds_v = {0.0,  7.5,  15.0, 22.5, 30.0,
                                             37.5, 45.0, 52.5, 60.0, 67.5};  ///< increasing
    std::vector<double> play_weights_um_per_v = {0.18, 0.02, 0.02, 0.02, 0.02,
                                                 0.02, 0.02, 0.02, 0.02, 0.02};
    double play_offset_um = -6.75;  ///< puts the periodic major loop at about 0..45 µm
    std::vector<double> dead_zone_thresholds_um = {-15.0, 0.0, 12.0};  ///< increasing, has 0
    std::vector<double> dead_zone_weights = {0.15, 1.0, 0.4};          ///< dimensionless
    double dead_zone_center_um = 21.0;                                 ///< [µm]
  } hysteresis;

  /// Rate dependence. Needs hysteresis.enabled.
  /// - mechanism switching_front (kind preisach): the relays switch at a front that moves at a
  ///   speed growing with the square of the input's overdrive past it (SwitchingFront): the loop
  ///   widens with the square root of the rate; the reversible strain does not lag.
  /// - mechanism switching_thresholds (kind preisach): every relay's switching thresholds widen
  ///   by threshold_rate_s * |du/dt| (low-passed with threshold_filter_s; RateWidenedPlay): the
  ///   loop widens in proportion to the rate and its tips stay where the input reverses.
  /// - mechanism play_weights (kind modified_pi; rate-dependent paper, eq. 15-21): the cumulative
  ///   play weights become W_i + c_i * du/dt (rate_law "signed", eq. 16 as written) or
  ///   W_i + c_i * |du/dt| ("magnitude"). The default is signed with c_i <= 0: the loading slope
  ///   falls with the rate and the unloading one rises, so the loop widens with frequency. The
  ///   rate is the per-sample input rate, so an input step gives a one-sample weight spike.
  struct RateDependence {
    bool enabled = false;
    RateMechanism mechanism = RateMechanism::kSwitchingFront;
    /// switching_front: the front's lag behind a 1 kV/s ramp [V], > 0. The default widens the
    /// full-range loop with frequency (by how much: docs/measurements.md, "Rate dependence on").
    double switching_lag_v = 2.5;
    /// switching_front: n of the front's speed |u - u_s|^n, [1, 4]; 2: the lag grows with the
    /// square root of the rate; 1: a first-order lag (SwitchingFront).
    double switching_exponent = 2.0;
    /// switching_thresholds: each threshold's widening per unit of rate [s] (V per V/s), >= 0.
    /// The default widens them by 3.6 V at 19 Hz over the full range (9 kV/s).
    double threshold_rate_s = 0.4e-3;
    /// switching_thresholds: the rate's low-pass time constant [s], >= 0.
    double threshold_filter_s = 0.5e-3;
    compensation::RateLaw rate_law = compensation::RateLaw::kSigned;
    /// play_weights: c_i, one per play [µm/V per V/s]; the default changes the wide plays' share
    /// of the slope by about 10 % per kV/s (every W_i + c_i rate must stay > 0 over the rates).
    std::vector<double> rate_coefficients = {0.0,   -2e-6,   -4e-6,   -6e-6,   -8e-6,
                                             -1e-5, -1.2e-5, -1.4e-5, -1.6e-5, -1.8e-5};
    /// play_weights: rate the law holds to, capped beyond (>= 0) [V/s].
    double max_rate_v_per_s = 10000.0;
  } rate_dependence;

  /// Creep.
  /// - law logarithmic: after a change of the displacement the output keeps moving by
  ///   fraction_per_decade of it per decade of time (y0 (1 + gamma log10(1 + t / 0.1 s)), as
  ///   stage vendors state it) until longest_s (logarithmic_creep.hpp).
  /// - law input_lags: a bank of first-order lags of the (delayed) input added to the hysteresis
  ///   output (compensation::CreepOperatorBank, the models' creep operator).
  struct Creep {
    bool enabled = true;
    CreepLaw law = CreepLaw::kLogarithmic;
    double fraction_per_decade = 0.01;  ///< gamma, [0, 0.1]
    double longest_s = 1.0e5;           ///< creep levels off beyond it [s], [10, 1e7]
    std::vector<double> time_constants_s = {0.05, 0.5, 5.0, 50.0};          ///< input_lags: > 0 [s]
    std::vector<double> gains_um_per_v = {0.0015, 0.0015, 0.0015, 0.0015};  ///< input_lags
  } creep;

  /// Structural dynamics: second-order modes whose gains sum to one (unit DC gain), each
  /// discretised exactly (ModalDynamics). The default: the stack's first longitudinal mode and a
  /// weaker, lightly damped mode of the load above it.
  struct Dynamics {
    bool enabled = true;
    std::vector<double> natural_frequencies_hz = {3000.0, 8000.0};  ///< each > 0 [Hz]
    std::vector<double> damping_ratios = {0.06, 0.03};              ///< each > 0
    std::vector<double> mode_gains = {0.88, 0.12};                  ///< sum to 1
  } dynamics;

  /// The displacement sensor's own bandwidth: a second-order low-pass of the measured position
  /// (not of true_position()), before the noise and the ADC.
  struct SensorFilter {
    bool enabled = true;
    double cutoff_hz = 5000.0;      ///< > 0 [Hz]
    double damping_ratio = 0.7071;  ///< > 0 (0.7071: Butterworth)
  } sensor_filter;

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

/// The Preisach relays of a kind-preisach hysteresis over the input range.
PreisachParameters preisach_parameters(const SimulatedActuatorConfig& config);

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
