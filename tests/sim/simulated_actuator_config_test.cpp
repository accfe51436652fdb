#include "hystbench/sim/simulated_actuator_config.hpp"

#include <gtest/gtest.h>

#include <string>

namespace hs = hystbench::sim;
using json = nlohmann::json;

namespace {

/// what() of the std::invalid_argument that from_json throws, or "no exception".
std::string from_json_error(const json& j) {
  try {
    hs::from_json(j);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no exception";
}

bool mentions(const std::string& message, const std::string& text) {
  return message.find(text) != std::string::npos;
}

}  // namespace

TEST(SimulatedActuatorConfigJson, RoundTripsEveryField) {
  hs::SimulatedActuatorConfig c;
  c.input = {-10.0, 100.0};
  c.hysteresis.play_offset_um = 1.5;
  c.rate_dependence.enabled = true;
  c.rate_dependence.rate_law = hystbench::compensation::RateLaw::kMagnitude;
  c.creep.time_constants_s = {0.2, 20.0};
  c.creep.gains_um_per_v = {0.001, 0.002};
  c.dynamics.natural_frequency_hz = 4200.0;
  c.delay = {true, 3e-4};
  c.sensor_noise.seed = 1234567890123ULL;
  c.dac.bits = 12;
  c.adc.range_max = 80.0;
  c.thermal_drift.enabled = true;
  c.thermal_drift.shape = hs::DriftShape::kRandomWalk;
  c.input_saturation.enabled = false;
  c.displacement_saturation = {true, -1.0, 44.0};

  const json j = hs::to_json(c);
  const hs::SimulatedActuatorConfig back = hs::from_json(j);
  EXPECT_EQ(hs::to_json(back), j);
  EXPECT_EQ(back.sensor_noise.seed, 1234567890123ULL);
  EXPECT_EQ(back.thermal_drift.shape, hs::DriftShape::kRandomWalk);
  EXPECT_EQ(back.creep.gains_um_per_v, c.creep.gains_um_per_v);
  EXPECT_EQ(j["thermal_drift"]["shape"], "random_walk");
  EXPECT_EQ(j["rate_dependence"]["rate_law"], "magnitude");
  EXPECT_EQ(back.rate_dependence.rate_law, hystbench::compensation::RateLaw::kMagnitude);
}

TEST(SimulatedActuatorConfigJson, MissingKeysKeepTheDefaults) {
  const auto c = hs::from_json(json::parse(R"({"dynamics": {"natural_frequency_hz": 2500}})"));
  const hs::SimulatedActuatorConfig defaults;
  EXPECT_EQ(c.dynamics.natural_frequency_hz, 2500.0);
  EXPECT_EQ(c.dynamics.damping_ratio, defaults.dynamics.damping_ratio);
  EXPECT_EQ(hs::to_json(hs::from_json(json::object())), hs::to_json(defaults));
}

TEST(SimulatedActuatorConfigJson, UnknownKeysAreNamedWithTheValidOnes) {
  const auto top = from_json_error(json::parse(R"({"dynamcis": {}})"));
  EXPECT_TRUE(mentions(top, "dynamcis")) << top;
  EXPECT_TRUE(mentions(top, "dynamics")) << top;  // listed among the valid keys

  const auto nested = from_json_error(json::parse(R"({"dynamics": {"natural_freq": 1}})"));
  EXPECT_TRUE(mentions(nested, "dynamics.natural_freq")) << nested;
  EXPECT_TRUE(mentions(nested, "natural_frequency_hz")) << nested;
}

TEST(SimulatedActuatorConfigJson, WrongTypesAreNamed) {
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"({"dynamics": {"damping_ratio": "0.1"}})")),
                       "dynamics.damping_ratio"));
  EXPECT_TRUE(
      mentions(from_json_error(json::parse(R"({"creep": {"gains_um_per_v": [0.1, true]}})")),
               "creep.gains_um_per_v[1]"));
  EXPECT_TRUE(
      mentions(from_json_error(json::parse(R"({"delay": {"enabled": 1}})")), "delay.enabled"));
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"({"adc": {"bits": 12.5}})")), "adc.bits"));
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"({"sensor_noise": {"seed": -3}})")),
                       "sensor_noise.seed"));
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"({"thermal_drift": {"shape": "square"}})")),
                       "thermal_drift.shape"));
  EXPECT_TRUE(
      mentions(from_json_error(json::parse(R"({"rate_dependence": {"rate_law": "absolute"}})")),
               "rate_dependence.rate_law"));
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"({"input": 150})")), "input"));
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"([1, 2])")), "expected an object"));
}

TEST(SimulatedActuatorConfigJson, InvalidValuesAreNamed) {
  const auto e = from_json_error(json::parse(R"({"dynamics": {"damping_ratio": -0.1}})"));
  EXPECT_TRUE(mentions(e, "dynamics.damping_ratio")) << e;
  const auto sizes = from_json_error(json::parse(R"({"creep": {"time_constants_s": [1.0]}})"));
  EXPECT_TRUE(mentions(sizes, "creep.gains_um_per_v")) << sizes;
  // The signed law lowers the weights on a fall: a coefficient that makes one negative at the
  // fastest fall is refused, naming it (the default is the paper's signed law).
  const auto falling = from_json_error(json::parse(
      R"({"rate_dependence": {"enabled": true, "max_rate_v_per_s": 5000,
          "rate_coefficients": [1e-4, 0, 0, 0, 0, 0, 0, 0, 0, 0]}})"));
  EXPECT_TRUE(mentions(falling, "rate_dependence.rate_coefficients[0]")) << falling;
  EXPECT_NO_THROW(hs::from_json(json::parse(
      R"({"rate_dependence": {"enabled": true, "rate_law": "magnitude", "max_rate_v_per_s": 5000,
          "rate_coefficients": [1e-4, 0, 0, 0, 0, 0, 0, 0, 0, 0]}})")));
}

TEST(SimulatedActuatorConfig, DefaultsAreValid) { EXPECT_NO_THROW(hs::validate({})); }
