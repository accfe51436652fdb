#include "hystbench/sim/simulated_stage_config.hpp"

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

#include "details/field_checks.hpp"

namespace hystbench::sim {

namespace {

// Every message starts with the field path: "<field>: <what is wrong>".
// Inside the unnamed namespace, so that a unity batch's other files' helpers of the same name
// overload these instead of hiding them.
using details::fail;

using json = nlohmann::json;

std::string axis_path(std::size_t i) { return "axes[" + std::to_string(i) + "]"; }

void validate_coupling(const StageCouplingConfig& c, std::size_t n) {
  if (!c.enabled) return;
  if (!(std::isfinite(c.shared_mode_hz) && c.shared_mode_hz > 0.0)) {
    fail("coupling.shared_mode_hz", "must be > 0");
  }
  if (!(std::isfinite(c.shared_damping_ratio) && c.shared_damping_ratio > 0.0)) {
    fail("coupling.shared_damping_ratio", "must be > 0");
  }
  if (c.gains.empty()) return;
  if (c.gains.size() != n) {
    fail("coupling.gains", "needs one row per axis (" + std::to_string(n) + "), has " +
                               std::to_string(c.gains.size()));
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::string row = "coupling.gains[" + std::to_string(i) + "]";
    if (c.gains[i].size() != n) {
      fail(row, "needs one column per axis (" + std::to_string(n) + "), has " +
                    std::to_string(c.gains[i].size()));
    }
    for (std::size_t j = 0; j < n; ++j) {
      const double k = c.gains[i][j];
      const std::string field = row + "[" + std::to_string(j) + "]";
      if (i == j && k != 0.0) fail(field, "must be 0 (an axis's own gain is its actuator's)");
      if (!(std::isfinite(k) && std::abs(k) <= 0.5)) fail(field, "must be in [-0.5, 0.5]");
    }
  }
}

double number(const json& j, const std::string& path) {
  if (!j.is_number()) fail(path, "expected a number, got " + j.dump());
  return j.get<double>();
}

StageCouplingConfig coupling_from_json(const json& j, StageCouplingConfig c) {
  if (!j.is_object()) fail("coupling", "expected a table, got " + j.dump());
  for (const auto& item : j.items()) {
    const std::string path = "coupling." + item.key();
    const json& v = item.value();
    if (item.key() == "enabled") {
      if (!v.is_boolean()) fail(path, "expected true or false, got " + v.dump());
      c.enabled = v.get<bool>();
    } else if (item.key() == "shared_mode_hz") {
      c.shared_mode_hz = number(v, path);
    } else if (item.key() == "shared_damping_ratio") {
      c.shared_damping_ratio = number(v, path);
    } else if (item.key() == "gains") {
      if (!v.is_array()) fail(path, "expected an array of rows, got " + v.dump());
      c.gains.clear();
      for (std::size_t i = 0; i < v.size(); ++i) {
        const std::string row = path + "[" + std::to_string(i) + "]";
        if (!v[i].is_array()) fail(row, "expected an array of numbers, got " + v[i].dump());
        std::vector<double> values;
        for (std::size_t k = 0; k < v[i].size(); ++k) {
          values.push_back(number(v[i][k], row + "[" + std::to_string(k) + "]"));
        }
        c.gains.push_back(std::move(values));
      }
    } else {
      fail(path, "unknown key (valid: enabled, gains, shared_mode_hz, shared_damping_ratio)");
    }
  }
  return c;
}

bool sets_seed(const json& actuator, const char* section) {
  return actuator.contains(section) && actuator[section].is_object() &&
         actuator[section].contains("seed");
}

StageAxisConfig axis_from_json(const json& j, std::size_t i) {
  const std::string path = axis_path(i);
  if (!j.is_object()) fail(path, "expected a table with a name, got " + j.dump());
  StageAxisConfig axis;
  json actuator = json::object();
  for (const auto& item : j.items()) {
    if (item.key() == "name") {
      if (!item.value().is_string()) fail(path + ".name", "expected a string");
      axis.name = item.value().get<std::string>();
    } else if (item.key() == "actuator") {
      actuator = item.value();
    } else {
      fail(path + "." + item.key(), "unknown key (valid: name, actuator)");
    }
  }
  if (!j.contains("name")) fail(path + ".name", "missing: every axis needs a name");
  try {
    axis.actuator = from_json(actuator);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ".actuator." + e.what());
  }
  if (!sets_seed(actuator, "sensor_noise")) axis.actuator.sensor_noise.seed = 1 + 2 * i;
  if (!sets_seed(actuator, "thermal_drift")) axis.actuator.thermal_drift.seed = 2 + 2 * i;
  return axis;
}

}  // namespace

bool is_axis_name(std::string_view name) noexcept {
  if (name.empty() || name.size() > 16) return false;
  for (const char ch : name) {
    if (!((ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_')) return false;
  }
  return true;
}

SimulatedStageConfig SimulatedStageConfig::xy() {
  SimulatedStageConfig c;
  StageAxisConfig x{"x", SimulatedActuatorConfig{}};
  StageAxisConfig y{"y", SimulatedActuatorConfig{}};
  auto& h = y.actuator.hysteresis;
  h.coercive_median_v = 14.0;
  h.coercive_spread = 0.5;
  h.bias_mean_v = 62.0;
  h.bias_std_v = 40.0;
  h.switching_um = 16.0;
  h.reversible_um_per_v = 0.2;
  y.actuator.creep.fraction_per_decade = 0.014;
  y.actuator.dynamics.natural_frequencies_hz = {2400.0, 7000.0};
  y.actuator.dynamics.damping_ratios = {0.05, 0.03};
  y.actuator.dynamics.mode_gains = {0.9, 0.1};
  y.actuator.sensor_noise.seed = 3;
  y.actuator.thermal_drift.seed = 4;
  c.axes = {std::move(x), std::move(y)};
  c.coupling.gains = {{0.0, 0.056}, {0.1, 0.0}};
  return c;
}

void validate(const SimulatedStageConfig& config) {
  const std::size_t n = config.axes.size();
  if (n < 1 || n > kMaxStageAxes) {
    fail("axes", "a stage has 1 to " + std::to_string(kMaxStageAxes) + " axes, this one " +
                     std::to_string(n));
  }
  std::set<std::string> names;
  for (std::size_t i = 0; i < n; ++i) {
    const StageAxisConfig& axis = config.axes[i];
    if (!is_axis_name(axis.name)) {
      fail(axis_path(i) + ".name", "\"" + axis.name + "\": 1 to 16 of a-z, 0-9 and _");
    }
    if (!names.insert(axis.name).second) {
      fail(axis_path(i) + ".name", "\"" + axis.name + "\" names two axes");
    }
    try {
      validate(axis.actuator);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(axis_path(i) + ".actuator." + e.what());
    }
  }
  validate_coupling(config.coupling, n);
}

nlohmann::json to_json(const SimulatedStageConfig& config) {
  json axes = json::array();
  for (const StageAxisConfig& axis : config.axes) {
    axes.push_back({{"name", axis.name}, {"actuator", to_json(axis.actuator)}});
  }
  const StageCouplingConfig& c = config.coupling;
  return {{"axes", axes},
          {"coupling",
           {{"enabled", c.enabled},
            {"gains", c.gains},
            {"shared_mode_hz", c.shared_mode_hz},
            {"shared_damping_ratio", c.shared_damping_ratio}}}};
}

SimulatedStageConfig stage_from_json(const nlohmann::json& j) {
  if (!j.is_object()) fail("simulated stage config", "expected an object, got " + j.dump());
  for (const auto& item : j.items()) {
    if (item.key() != "axes" && item.key() != "coupling") {
      fail(item.key(), "unknown key (valid: axes, coupling)");
    }
  }
  SimulatedStageConfig config = SimulatedStageConfig::xy();
  if (j.contains("axes")) {
    const json& axes = j["axes"];
    if (!axes.is_array()) fail("axes", "expected an array of axis tables, got " + axes.dump());
    config.axes.clear();
    config.coupling = StageCouplingConfig{};
    for (std::size_t i = 0; i < axes.size(); ++i) config.axes.push_back(axis_from_json(axes[i], i));
  }
  if (j.contains("coupling")) config.coupling = coupling_from_json(j["coupling"], config.coupling);
  validate(config);
  return config;
}

}  // namespace hystbench::sim
