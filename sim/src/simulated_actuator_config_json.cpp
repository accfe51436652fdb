// JSON conversion of SimulatedActuatorConfig. One list of sections and one list of fields per
// section serve both directions, so a new field needs one line here.
#include <concepts>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>

#include "details/field_checks.hpp"
#include "hystbench/sim/simulated_actuator_config.hpp"

namespace hystbench::sim {

namespace {

// Inside the unnamed namespace, so that a unity batch's other files' helpers of the same name
// overload these instead of hiding them.
using details::fail;

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
  visit("sensor_filter", c.sensor_filter);
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
  visit("kind", s.kind);
  visit("coercive_median_v", s.coercive_median_v);
  visit("coercive_spread", s.coercive_spread);
  visit("bias_mean_v", s.bias_mean_v);
  visit("bias_std_v", s.bias_std_v);
  visit("switching_um", s.switching_um);
  visit("reversible_um_per_v", s.reversible_um_per_v);
  visit("offset_um", s.offset_um);
  visit("grid_points", s.grid_points);
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
  visit("mechanism", s.mechanism);
  visit("switching_lag_v", s.switching_lag_v);
  visit("switching_exponent", s.switching_exponent);
  visit("threshold_rate_s", s.threshold_rate_s);
  visit("threshold_filter_s", s.threshold_filter_s);
  visit("rate_law", s.rate_law);
  visit("rate_coefficients", s.rate_coefficients);
  visit("max_rate_v_per_s", s.max_rate_v_per_s);
}

template <class S, class Visit>
requires Is<S, Config::Creep>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("law", s.law);
  visit("fraction_per_decade", s.fraction_per_decade);
  visit("longest_s", s.longest_s);
  visit("time_constants_s", s.time_constants_s);
  visit("gains_um_per_v", s.gains_um_per_v);
}

template <class S, class Visit>
requires Is<S, Config::Dynamics>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("natural_frequencies_hz", s.natural_frequencies_hz);
  visit("damping_ratios", s.damping_ratios);
  visit("mode_gains", s.mode_gains);
}

template <class S, class Visit>
requires Is<S, Config::SensorFilter>
void visit_fields(S& s, Visit&& visit) {
  visit("enabled", s.enabled);
  visit("cutoff_hz", s.cutoff_hz);
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

// --- keys that belong to one form of an effect ---

/// The key `section.key` belongs to one value of its section's selector (hysteresis.kind,
/// rate_dependence.mechanism, creep.law): null when it belongs to every form, or the selector's
/// name and the value it needs.
struct Scope {
  const char* selector;
  std::string_view needs;
};

std::optional<Scope> scope_of(std::string_view section, std::string_view key) {
  static const std::set<std::string_view> preisach = {
      "coercive_median_v", "coercive_spread",     "bias_mean_v", "bias_std_v",
      "switching_um",      "reversible_um_per_v", "offset_um",   "grid_points"};
  static const std::set<std::string_view> modified_pi = {
      "play_thresholds_v",       "play_weights_um_per_v", "play_offset_um",
      "dead_zone_thresholds_um", "dead_zone_weights",     "dead_zone_center_um"};
  if (section == "hysteresis") {
    if (preisach.contains(key)) return Scope{"kind", to_string(HysteresisKind::kPreisach)};
    if (modified_pi.contains(key)) return Scope{"kind", to_string(HysteresisKind::kModifiedPi)};
  } else if (section == "rate_dependence") {
    if (key == "switching_lag_v" || key == "switching_exponent") {
      return Scope{"mechanism", to_string(RateMechanism::kSwitchingFront)};
    }
    if (key == "threshold_rate_s" || key == "threshold_filter_s") {
      return Scope{"mechanism", to_string(RateMechanism::kSwitchingThresholds)};
    }
    if (key == "rate_law" || key == "rate_coefficients" || key == "max_rate_v_per_s") {
      return Scope{"mechanism", to_string(RateMechanism::kPlayWeights)};
    }
  } else if (section == "creep") {
    if (key == "fraction_per_decade" || key == "longest_s") {
      return Scope{"law", to_string(CreepLaw::kLogarithmic)};
    }
    if (key == "time_constants_s" || key == "gains_um_per_v") {
      return Scope{"law", to_string(CreepLaw::kInputLags)};
    }
  }
  return std::nullopt;
}

/// The selector's value in `c` for section's scope.
std::string_view selected(const Config& c, std::string_view section) {
  if (section == "hysteresis") return to_string(c.hysteresis.kind);
  if (section == "rate_dependence") return to_string(c.rate_dependence.mechanism);
  return to_string(c.creep.law);
}

bool applies(const Config& c, std::string_view section, std::string_view key) {
  const auto scope = scope_of(section, key);
  return !scope || selected(c, section) == scope->needs;
}

// --- encoding ---

json encode(const auto& value) { return value; }
json encode(DriftShape shape) { return std::string(to_string(shape)); }
json encode(compensation::RateLaw law) { return std::string(compensation::to_string(law)); }
json encode(HysteresisKind kind) { return std::string(to_string(kind)); }
json encode(RateMechanism mechanism) { return std::string(to_string(mechanism)); }
json encode(CreepLaw law) { return std::string(to_string(law)); }

// --- decoding: every reader names the key path on a type error ---

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
  // A non-negative integer built in C++ (json{{"seed", 42}}) is signed; parsed text is not.
  const bool non_negative =
      j.is_number_unsigned() || (j.is_number_integer() && j.get<std::int64_t>() >= 0);
  if (!non_negative) fail(path, "expected a non-negative integer, got " + j.dump());
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

/// An enum named by to_string(): one of `values`.
template <class Enum>
void decode_name(const json& j, const std::string& path, Enum& out,
                 std::initializer_list<Enum> values) {
  std::string names;
  for (const Enum v : values) {
    if (j.is_string() && j.get<std::string>() == to_string(v)) {
      out = v;
      return;
    }
    names += (names.empty() ? "\"" : " or \"") + std::string(to_string(v)) + "\"";
  }
  fail(path, "expected " + names + ", got " + j.dump());
}

void decode(const json& j, const std::string& path, HysteresisKind& out) {
  decode_name(j, path, out, {HysteresisKind::kPreisach, HysteresisKind::kModifiedPi});
}

void decode(const json& j, const std::string& path, RateMechanism& out) {
  decode_name(j, path, out,
              {RateMechanism::kSwitchingFront, RateMechanism::kPlayWeights,
               RateMechanism::kSwitchingThresholds});
}

void decode(const json& j, const std::string& path, CreepLaw& out) {
  decode_name(j, path, out, {CreepLaw::kLogarithmic, CreepLaw::kInputLags});
}

void decode(const json& j, const std::string& path, DriftShape& out) {
  decode_name(j, path, out, {DriftShape::kSinusoid, DriftShape::kRandomWalk});
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
    std::string key_path = path;
    key_path.append(".").append(key);
    bool known = false;
    visit_fields(section, [&](const char* name, auto& field) {
      if (key != name) return;
      known = true;
      decode(value, key_path, field);
    });
    if (!known) {
      fail(key_path,
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
    visit_fields(section, [&](const char* name, const auto& field) {
      if (applies(config, section_name, name)) out[name] = encode(field);
    });
  });
  return j;
}

SimulatedActuatorConfig from_json(const json& j) {
  if (!j.is_object()) fail("simulated actuator config", "expected an object, got " + j.dump());
  // A modified-PI hysteresis brings the truth the model families contain with it: the defaults
  // of the other effects are then the forms the models have (modified_pi_truth()).
  SimulatedActuatorConfig config;
  if (j.contains("hysteresis") && j["hysteresis"].is_object() && j["hysteresis"].contains("kind")) {
    HysteresisKind kind = HysteresisKind::kPreisach;
    decode(j["hysteresis"]["kind"], "hysteresis.kind", kind);
    if (kind == HysteresisKind::kModifiedPi) config = SimulatedActuatorConfig::modified_pi_truth();
  }
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
  // A key of another form of its effect would be silently ignored: name it instead.
  for (const auto& section : j.items()) {
    for (const auto& item : section.value().items()) {
      const auto scope = scope_of(section.key(), item.key());
      if (scope && selected(config, section.key()) != scope->needs) {
        fail(section.key() + "." + item.key(),
             "applies to " + section.key() + "." + scope->selector + " = \"" +
                 std::string(scope->needs) + "\", this actuator's is \"" +
                 std::string(selected(config, section.key())) + "\"");
      }
    }
  }
  validate(config);
  return config;
}

}  // namespace hystbench::sim
