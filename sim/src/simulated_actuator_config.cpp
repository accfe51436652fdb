#include "hystbench/sim/simulated_actuator_config.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hystbench::sim {

namespace {

// Every message starts with the field path: "<field>: <what is wrong>".
void require(bool ok, const std::string& field, const std::string& what) {
  if (!ok) throw std::invalid_argument(field + ": " + what);
}

void require_finite(double value, const std::string& field) {
  require(std::isfinite(value), field, "must be a finite number");
}

void require_positive(double value, const std::string& field) {
  require(std::isfinite(value) && value > 0.0, field, "must be > 0");
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

void validate_hysteresis(const SimulatedActuatorConfig::Hysteresis& h) {
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

void validate_quantization(const QuantizationConfig& q, const std::string& name) {
  require(q.bits >= 1 && q.bits <= 32, name + ".bits", "must be in [1, 32]");
  require_range(q.range_min, q.range_max, name + ".range_min", name + ".range_max");
}

}  // namespace

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
  validate_hysteresis(c.hysteresis);

  if (c.rate_dependence.enabled) {
    require(c.hysteresis.enabled, "rate_dependence.enabled", "needs hysteresis.enabled");
    require_same_length(c.rate_dependence.rate_coefficients, "rate_dependence.rate_coefficients",
                        c.hysteresis.play_thresholds_v.size(), "hysteresis.play_thresholds_v");
    require_finite(c.rate_dependence.rate_coefficients, "rate_dependence.rate_coefficients");
    require_non_negative(c.rate_dependence.max_rate_v_per_s, "rate_dependence.max_rate_v_per_s");
    // The loading curve keeps rising at every rate the law sees: W_i + c_i rate > 0 on
    // [-max_rate, max_rate] (signed) or [0, max_rate] (magnitude), checked at both ends.
    const double lowest = c.rate_dependence.rate_law == compensation::RateLaw::kSigned
                              ? -c.rate_dependence.max_rate_v_per_s
                              : 0.0;
    for (const double rate : {lowest, c.rate_dependence.max_rate_v_per_s}) {
      double w = 0.0;
      for (std::size_t i = 0; i < c.rate_dependence.rate_coefficients.size(); ++i) {
        w += c.hysteresis.play_weights_um_per_v[i];
        require(w + c.rate_dependence.rate_coefficients[i] * rate > 0.0,
                element("rate_dependence.rate_coefficients", i),
                "makes the cumulative play weight " + std::to_string(w) + " + c * " +
                    std::to_string(rate) + " V/s not positive (the loading curve would fall)");
      }
    }
  }
  if (c.creep.enabled) {
    require_same_length(c.creep.gains_um_per_v, "creep.gains_um_per_v",
                        c.creep.time_constants_s.size(), "creep.time_constants_s");
    for (std::size_t k = 0; k < c.creep.time_constants_s.size(); ++k) {
      require_positive(c.creep.time_constants_s[k], element("creep.time_constants_s", k));
    }
    require_finite(c.creep.gains_um_per_v, "creep.gains_um_per_v");
  }
  if (c.dynamics.enabled) {
    require_positive(c.dynamics.natural_frequency_hz, "dynamics.natural_frequency_hz");
    require_positive(c.dynamics.damping_ratio, "dynamics.damping_ratio");
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
