// JSON conversion of SimulatedActuatorConfig. One list of sections and one list of fields per
// section serve both directions, so a new field needs one line here.
#include <concepts>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "hystbench/sim/simulated_actuator_config.hpp"

namespace hystbench::sim {

namespace {

using json = nlohmann::json;
using Config = SimulatedActuatorConfig;

template <class T, class U>
concept Is = std::same_as<std::remove_const_t<T>, U>;

template <class C, class Visit>
requires Is<C, Config>
void visit_sections(C& c, Visit&& visit) {
  visit("input", c.input);
  visit("hysteresis", c.hysteresis);
  visit("rate_dependence", c.rate_dependence);
  visit("creep", c.creep);
  visit("dynamics", c.dynamics);
  visit("delay", c.delay);
  visit("sensor_noise", c.sensor_noise);
  visit("dac", c.dac);
  visit("adc", c.adc);
  visit("thermal_drift", c.thermal_drift);
  visit("input_saturation", c.input_saturation);
  visit("displacement_saturation", c.displacement_saturation);
}

template <class S, class Visit>
requires Is<S, Config::Input>
void visit_fields(S& s, Visit&& visit) {
  visit("min_v", s.min_v);
  visit("max_v", s.max_v);
}

template <class S, class Visit>
requires Is<S, Config::Hysteresis>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("play_thresholds_v", s.play_thresholds_v);
  visit("play_weights_um_per_v", s.play_weights_um_per_v);
  visit("play_offset_um", s.play_offset_um);
  visit("dead_zone_thresholds_um", s.dead_zone_thresholds_um);
  visit("dead_zone_weights", s.dead_zone_weights);
  visit("dead_zone_center_um", s.dead_zone_center_um);
}

template <class S, class Visit>
requires Is<S, Config::RateDependence>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("rate_law", s.rate_law);
  visit("rate_coefficients", s.rate_coefficients);
  visit("max_rate_v_per_s", s.max_rate_v_per_s);
}

template <class S, class Visit>
requires Is<S, Config::Creep>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("time_constants_s", s.time_constants_s);
  visit("gains_um_per_v", s.gains_um_per_v);
}

template <class S, class Visit>
requires Is<S, Config::Dynamics>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("natural_frequency_hz", s.natural_frequency_hz);
  visit("damping_ratio", s.damping_ratio);
}

template <class S, class Visit>
requires Is<S, Config::Delay>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("delay_s", s.delay_s);
}

template <class S, class Visit>
requires Is<S, Config::SensorNoise>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("rms_um", s.rms_um);
  visit("seed", s.seed);
}

template <class S, class Visit>
requires Is<S, QuantizationConfig>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("bits", s.bits);
  visit("range_min", s.range_min);
  visit("range_max", s.range_max);
}

template <class S, class Visit>
requires Is<S, Config::ThermalDrift>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("shape", s.shape);
  visit("amplitude_um", s.amplitude_um);
  visit("period_s", s.period_s);
  visit("random_walk_um_per_sqrt_s", s.random_walk_um_per_sqrt_s);
  visit("random_walk_limit_um", s.random_walk_limit_um);
  visit("seed", s.seed);
}

template <class S, class Visit>
requires Is<S, Config::InputSaturation>
void visit_fields(S& s, Visit&& visit) { visit("enabled", s.enabled); }

template <class S, class Visit>
requires Is<S, Config::DisplacementSaturation>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("min_um", s.min_um);
  visit("max_um", s.max_um);
}

// --- encoding ---

json encode(const auto& value) { return value; }
json encode(DriftShape shape) { return std::string(to_string(shape)); }
json encode(compensation::RateLaw law) { return std::string(compensation::to_string(law)); }

// --- decoding: every reader names the key path on a type error ---

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::invalid_argument(path + ": " + what);
}

void decode(const json& j, const std::string& path, bool& out) {
  if (!j.is_boolean()) fail(path, "expected true or false, got " + j.dump());
  out = j.get<bool>();
}

void decode(const json& j, const std::string& path, double& out) {
  if (!j.is_number()) fail(path, "expected a number, got " + j.dump());
  out = j.get<double>();
}

void decode(const json& j, const std::string& path, int& out) {
  if (!j.is_number_integer()) fail(path, "expected an integer, got " + j.dump());
  const auto v = j.get<std::int64_t>();
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max())
    fail(path, "integer out of range: " + j.dump());
  out = static_cast<int>(v);
}

void decode(const json& j, const std::string& path, std::uint64_t& out) {
  if (!j.is_number_unsigned()) fail(path, "expected a non-negative integer, got " + j.dump());
  out = j.get<std::uint64_t>();
}

void decode(const json& j, const std::string& path, std::vector<double>& out) {
  if (!j.is_array()) fail(path, "expected an array of numbers, got " + j.dump());
  std::vector<double> values(j.size());
  for (std::size_t i = 0; i < j.size(); ++i) {
    decode(j[i], path + "[" + std::to_string(i) + "]", values[i]);
  }
  out = std::move(values);
}

void decode(const json& j, const std::string& path, DriftShape& out) {
  for (const DriftShape shape : {DriftShape::kSinusoid, DriftShape::kRandomWalk}) {
    if (j.is_string() && j.get<std::string>() == to_string(shape)) {
      out = shape;
      return;
    }
  }
  fail(path, "expected \"sinusoid\" or \"random_walk\", got " + j.dump());
}

void decode(const json& j, const std::string& path, compensation::RateLaw& out) {
  if (j.is_string()) {
    if (const auto law = compensation::rate_law_from_string(j.get<std::string>())) {
      out = *law;
      return;
    }
  }
  fail(path, "expected \"signed\" or \"magnitude\", got " + j.dump());
}

/// Names accepted by a visitor function, for "unknown key" messages.
template <class Visitable>
std::string key_list(Visitable&& visit_names) {
  std::string names;
  visit_names([&](const char* name, const auto&) {
    if (!names.empty()) names += ", ";
    names += name;
  });
  return names;
}

template <class Section>
void decode_section(const json& j, const std::string& path, Section& section) {
  if (!j.is_object()) fail(path, "expected an object, got " + j.dump());
  for (const auto& item : j.items()) {
    // Not a structured binding: clang 14 (the fuzz build) cannot capture one in a lambda.
    const std::string& key = item.key();
    const json& value = item.value();
    bool known = false;
    visit_fields(section, [&](const char* name, auto& field) {
      if (key != name) return;
      known = true;
      decode(value, path + "." + key, field);
    });
    if (!known) {
      fail(path + "." + key,
           "unknown key (valid: " + key_list([&](auto&& v) { visit_fields(section, v); }) + ")");
    }
  }
}

}  // namespace

json to_json(const SimulatedActuatorConfig& config) {
  json j = json::object();
  visit_sections(config, [&](const char* section_name, const auto& section) {
    json& out = j[section_name];
    out = json::object();
    visit_fields(section, [&](const char* name, const auto& field) { out[name] = encode(field); });
  });
  return j;
}

SimulatedActuatorConfig from_json(const json& j) {
  if (!j.is_object()) fail("simulated actuator config", "expected an object, got " + j.dump());
  SimulatedActuatorConfig config;
  for (const auto& item : j.items()) {
    // Not a structured binding: clang 14 (the fuzz build) cannot capture one in a lambda.
    const std::string& key = item.key();
    const json& value = item.value();
    bool known = false;
    visit_sections(config, [&](const char* name, auto& section) {
      if (key != name) return;
      known = true;
      decode_section(value, key, section);
    });
    if (!known) {
      fail(key,
           "unknown key (valid: " + key_list([&](auto&& v) { visit_sections(config, v); }) + ")");
    }
  }
  validate(config);
  return config;
}

}  // namespace hystbench::sim
