#include "hystbench/sim/simulated_actuator_config.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "details/field_checks.hpp"
#include "hystbench/sim/preisach_hysteresis.hpp"

namespace hystbench::sim {

namespace {

// Every message starts with the field path: "<field>: <what is wrong>".
// Inside the unnamed namespace, so that a unity batch's other files' helpers of the same name
// overload these instead of hiding them.
using details::require;
using details::require_positive;

void require_finite(double value, const std::string& field) {
  require(std::isfinite(value), field, "must be a finite number");
}

void require_non_negative(double value, const std::string& field) {
  require(std::isfinite(value) && value >= 0.0, field, "must be >= 0");
}

std::string element(const std::string& field, std::size_t i) {
  return field + "[" + std::to_string(i) + "]";
}

void require_finite(const std::vector<double>& values, const std::string& field) {
  for (std::size_t i = 0; i < values.size(); ++i) require_finite(values[i], element(field, i));
}

void require_strictly_increasing(const std::vector<double>& values, const std::string& field) {
  for (std::size_t i = 1; i < values.size(); ++i) {
    require(values[i] > values[i - 1], element(field, i),
            "must be greater than " + element(field, i - 1) + " (strictly increasing)");
  }
}

void require_same_length(const std::vector<double>& values, const std::string& field,
                         std::size_t expected, const std::string& reference) {
  require(values.size() == expected, field,
          "has " + std::to_string(values.size()) + " entries, " + reference + " has " +
              std::to_string(expected));
}

void require_range(double min, double max, const std::string& min_field,
                   const std::string& max_field) {
  require_finite(min, min_field);
  require_finite(max, max_field);
  require(max > min, max_field, "must be greater than " + min_field);
}

void validate_modified_pi(const SimulatedActuatorConfig::Hysteresis& h) {
  const std::string thresholds = "hysteresis.play_thresholds_v";
  const std::string weights = "hysteresis.play_weights_um_per_v";
  require(!h.play_thresholds_v.empty(), thresholds, "must not be empty");
  require_same_length(h.play_weights_um_per_v, weights, h.play_thresholds_v.size(), thresholds);
  require_finite(h.play_thresholds_v, thresholds);
  require_finite(h.play_weights_um_per_v, weights);
  require(h.play_thresholds_v.front() >= 0.0, element(thresholds, 0), "must be >= 0");
  require_strictly_increasing(h.play_thresholds_v, thresholds);
  require_finite(h.play_offset_um, "hysteresis.play_offset_um");

  const std::string dz_thresholds = "hysteresis.dead_zone_thresholds_um";
  const std::string dz_weights = "hysteresis.dead_zone_weights";
  require_same_length(h.dead_zone_weights, dz_weights, h.dead_zone_thresholds_um.size(),
                      dz_thresholds);
  require_finite(h.dead_zone_thresholds_um, dz_thresholds);
  require_finite(h.dead_zone_weights, dz_weights);
  require_strictly_increasing(h.dead_zone_thresholds_um, dz_thresholds);
  const auto& d = h.dead_zone_thresholds_um;
  require(std::find(d.begin(), d.end(), 0.0) != d.end(), dz_thresholds,
          "must contain 0 (the identity dead zone)");
  require_finite(h.dead_zone_center_um, "hysteresis.dead_zone_center_um");
}

void validate_hysteresis(const SimulatedActuatorConfig& c) {
  const auto& h = c.hysteresis;
  if (h.kind == HysteresisKind::kModifiedPi) {
    validate_modified_pi(h);
    return;
  }
  validate(preisach_parameters(c), "hysteresis.");
  require_non_negative(h.reversible_um_per_v, "hysteresis.reversible_um_per_v");
  require_finite(h.offset_um, "hysteresis.offset_um");
}

void validate_rate_dependence(const SimulatedActuatorConfig& c) {
  const auto& r = c.rate_dependence;
  require(c.hysteresis.enabled, "rate_dependence.enabled", "needs hysteresis.enabled");
  if (r.mechanism == RateMechanism::kSwitchingFront) {
    require(c.hysteresis.kind == HysteresisKind::kPreisach, "rate_dependence.mechanism",
            "\"switching_front\" needs hysteresis.kind = \"preisach\" (\"play_weights\" is the "
            "modified PI's law)");
    require_positive(r.switching_lag_v, "rate_dependence.switching_lag_v");
    require(std::isfinite(r.switching_exponent) && r.switching_exponent >= 1.0 &&
                r.switching_exponent <= 4.0,
            "rate_dependence.switching_exponent", "must be in [1, 4]");
    return;
  }
  if (r.mechanism == RateMechanism::kSwitchingThresholds) {
    require(c.hysteresis.kind == HysteresisKind::kPreisach, "rate_dependence.mechanism",
            "\"switching_thresholds\" needs hysteresis.kind = \"preisach\" (\"play_weights\" is "
            "the modified PI's law)");
    require_non_negative(r.threshold_rate_s, "rate_dependence.threshold_rate_s");
    require_non_negative(r.threshold_filter_s, "rate_dependence.threshold_filter_s");
    return;
  }
  require(r.rate_law != compensation::RateLaw::kThresholds, "rate_dependence.rate_law",
          "\"thresholds\" is not a law of play weights (mechanism \"switching_thresholds\" "
          "widens the thresholds)");
  require(c.hysteresis.kind == HysteresisKind::kModifiedPi, "rate_dependence.mechanism",
          "\"play_weights\" needs hysteresis.kind = \"modified_pi\" (\"switching_front\" is the "
          "Preisach model's)");
  require_same_length(r.rate_coefficients, "rate_dependence.rate_coefficients",
                      c.hysteresis.play_thresholds_v.size(), "hysteresis.play_thresholds_v");
  require_finite(r.rate_coefficients, "rate_dependence.rate_coefficients");
  require_non_negative(r.max_rate_v_per_s, "rate_dependence.max_rate_v_per_s");
  // The loading curve keeps rising at every rate the law sees: W_i + c_i rate > 0 on
  // [-max_rate, max_rate] (signed) or [0, max_rate] (magnitude), checked at both ends.
  const double lowest = r.rate_law == compensation::RateLaw::kSigned ? -r.max_rate_v_per_s : 0.0;
  for (const double rate : {lowest, r.max_rate_v_per_s}) {
    double w = 0.0;
    for (std::size_t i = 0; i < r.rate_coefficients.size(); ++i) {
      w += c.hysteresis.play_weights_um_per_v[i];
      require(w + r.rate_coefficients[i] * rate > 0.0,
              element("rate_dependence.rate_coefficients", i),
              "makes the cumulative play weight " + std::to_string(w) + " + c * " +
                  std::to_string(rate) + " V/s not positive (the loading curve would fall)");
    }
  }
}

void validate_creep(const SimulatedActuatorConfig::Creep& c) {
  if (c.law == CreepLaw::kLogarithmic) {
    require(std::isfinite(c.fraction_per_decade) && c.fraction_per_decade >= 0.0 &&
                c.fraction_per_decade <= 0.1,
            "creep.fraction_per_decade", "must be in [0, 0.1]");
    require(std::isfinite(c.longest_s) && c.longest_s >= 10.0 && c.longest_s <= 1e7,
            "creep.longest_s", "must be in [10, 1e7] s");
    return;
  }
  require_same_length(c.gains_um_per_v, "creep.gains_um_per_v", c.time_constants_s.size(),
                      "creep.time_constants_s");
  for (std::size_t k = 0; k < c.time_constants_s.size(); ++k) {
    require_positive(c.time_constants_s[k], element("creep.time_constants_s", k));
  }
  require_finite(c.gains_um_per_v, "creep.gains_um_per_v");
}

void validate_dynamics(const SimulatedActuatorConfig::Dynamics& d) {
  const std::string f = "dynamics.natural_frequencies_hz";
  require(!d.natural_frequencies_hz.empty(), f, "must not be empty");
  require_same_length(d.damping_ratios, "dynamics.damping_ratios", d.natural_frequencies_hz.size(),
                      f);
  require_same_length(d.mode_gains, "dynamics.mode_gains", d.natural_frequencies_hz.size(), f);
  for (std::size_t i = 0; i < d.natural_frequencies_hz.size(); ++i) {
    require_positive(d.natural_frequencies_hz[i], element(f, i));
    require_positive(d.damping_ratios[i], element("dynamics.damping_ratios", i));
  }
  require_finite(d.mode_gains, "dynamics.mode_gains");
  const double sum = std::accumulate(d.mode_gains.begin(), d.mode_gains.end(), 0.0);
  require(std::abs(sum - 1.0) <= 1e-6, "dynamics.mode_gains",
          "must sum to 1 (unit DC gain), they sum to " + std::to_string(sum));
}

void validate_quantization(const QuantizationConfig& q, const std::string& name) {
  require(q.bits >= 1 && q.bits <= 32, name + ".bits", "must be in [1, 32]");
  require_range(q.range_min, q.range_max, name + ".range_min", name + ".range_max");
}

}  // namespace

PreisachParameters preisach_parameters(const SimulatedActuatorConfig& c) {
  const auto& h = c.hysteresis;
  return PreisachParameters{c.input.min_v, c.input.max_v, h.coercive_median_v, h.coercive_spread,
                            h.bias_mean_v, h.bias_std_v,  h.switching_um,      h.grid_points};
}

SimulatedActuatorConfig SimulatedActuatorConfig::modified_pi_truth() {
  SimulatedActuatorConfig c;
  c.hysteresis.kind = HysteresisKind::kModifiedPi;
  c.rate_dependence.mechanism = RateMechanism::kPlayWeights;
  c.creep.law = CreepLaw::kInputLags;
  c.dynamics.natural_frequencies_hz = {3000.0};
  c.dynamics.damping_ratios = {0.08};
  c.dynamics.mode_gains = {1.0};
  c.sensor_filter.enabled = false;
  return c;
}

std::string_view to_string(HysteresisKind kind) noexcept {
  return kind == HysteresisKind::kPreisach ? "preisach" : "modified_pi";
}

std::string_view to_string(RateMechanism mechanism) noexcept {
  switch (mechanism) {
    case RateMechanism::kSwitchingFront:
      return "switching_front";
    case RateMechanism::kSwitchingThresholds:
      return "switching_thresholds";
    case RateMechanism::kPlayWeights:
      break;
  }
  return "play_weights";
}

std::string_view to_string(CreepLaw law) noexcept {
  return law == CreepLaw::kLogarithmic ? "logarithmic" : "input_lags";
}

std::string_view to_string(DriftShape shape) noexcept {
  switch (shape) {
    case DriftShape::kSinusoid:
      return "sinusoid";
    case DriftShape::kRandomWalk:
      return "random_walk";
  }
  return "unknown";
}

void validate(const SimulatedActuatorConfig& c) {
  require_range(c.input.min_v, c.input.max_v, "input.min_v", "input.max_v");
  validate_hysteresis(c);
  if (c.rate_dependence.enabled) validate_rate_dependence(c);
  if (c.creep.enabled) validate_creep(c.creep);
  if (c.dynamics.enabled) validate_dynamics(c.dynamics);
  if (c.sensor_filter.enabled) {
    require_positive(c.sensor_filter.cutoff_hz, "sensor_filter.cutoff_hz");
    require_positive(c.sensor_filter.damping_ratio, "sensor_filter.damping_ratio");
  }
  if (c.delay.enabled) {
    require(std::isfinite(c.delay.delay_s) && c.delay.delay_s >= 0.0 && c.delay.delay_s <= 1.0,
            "delay.delay_s", "must be in [0, 1] s");
  }
  if (c.sensor_noise.enabled) require_non_negative(c.sensor_noise.rms_um, "sensor_noise.rms_um");
  if (c.dac.enabled) validate_quantization(c.dac, "dac");
  if (c.adc.enabled) validate_quantization(c.adc, "adc");
  if (c.thermal_drift.enabled) {
    const auto& d = c.thermal_drift;
    require_non_negative(d.amplitude_um, "thermal_drift.amplitude_um");
    require_positive(d.period_s, "thermal_drift.period_s");
    require_non_negative(d.random_walk_um_per_sqrt_s, "thermal_drift.random_walk_um_per_sqrt_s");
    require_positive(d.random_walk_limit_um, "thermal_drift.random_walk_limit_um");
  }
  if (c.displacement_saturation.enabled) {
    require_range(c.displacement_saturation.min_um, c.displacement_saturation.max_um,
                  "displacement_saturation.min_um", "displacement_saturation.max_um");
  }
}

}  // namespace hystbench::sim
