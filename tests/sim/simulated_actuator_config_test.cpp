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
  c.dynamics.natural_frequencies_hz = {4200.0, 9000.0};
  c.hysteresis.coercive_median_v = 12.0;
  c.rate_dependence.switching_lag_v = 4.0;
  c.creep.fraction_per_decade = 0.02;
  c.sensor_filter.cutoff_hz = 3000.0;
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
  EXPECT_EQ(back.dynamics.natural_frequencies_hz, c.dynamics.natural_frequencies_hz);
  EXPECT_EQ(j["thermal_drift"]["shape"], "random_walk");
  EXPECT_EQ(j["hysteresis"]["kind"], "preisach");
  EXPECT_EQ(j["rate_dependence"]["mechanism"], "switching_front");
  EXPECT_EQ(j["creep"]["law"], "logarithmic");
  // Only the keys of the forms in use: the others would be refused when read back.
  EXPECT_FALSE(j["hysteresis"].contains("play_thresholds_v"));
  EXPECT_FALSE(j["rate_dependence"].contains("rate_law"));
  EXPECT_FALSE(j["creep"].contains("gains_um_per_v"));
}

TEST(SimulatedActuatorConfigJson, RoundTripsTheModifiedPiTruth) {
  hs::SimulatedActuatorConfig c = hs::SimulatedActuatorConfig::modified_pi_truth();
  c.rate_dependence.enabled = true;
  c.rate_dependence.rate_law = hystbench::compensation::RateLaw::kMagnitude;
  c.creep.time_constants_s = {0.2, 20.0};
  c.creep.gains_um_per_v = {0.001, 0.002};
  const json j = hs::to_json(c);
  const hs::SimulatedActuatorConfig back = hs::from_json(j);
  EXPECT_EQ(hs::to_json(back), j);
  EXPECT_EQ(back.creep.gains_um_per_v, c.creep.gains_um_per_v);
  EXPECT_EQ(j["rate_dependence"]["rate_law"], "magnitude");
  EXPECT_EQ(back.rate_dependence.rate_law, hystbench::compensation::RateLaw::kMagnitude);
  EXPECT_FALSE(j["hysteresis"].contains("coercive_median_v"));
}

TEST(SimulatedActuatorConfigJson, AModifiedPiKindBringsTheTruthTheModelsContain) {
  const auto c = hs::from_json(json::parse(R"({"hysteresis": {"kind": "modified_pi"}})"));
  EXPECT_EQ(hs::to_json(c), hs::to_json(hs::SimulatedActuatorConfig::modified_pi_truth()));
  EXPECT_EQ(c.rate_dependence.mechanism, hs::RateMechanism::kPlayWeights);
  EXPECT_EQ(c.creep.law, hs::CreepLaw::kInputLags);
  EXPECT_EQ(c.dynamics.natural_frequencies_hz.size(), 1u);
  EXPECT_FALSE(c.sensor_filter.enabled);
  // An effect's own key still overrides what the kind brings.
  const auto mixed = hs::from_json(json::parse(
      R"({"hysteresis": {"kind": "modified_pi"}, "sensor_filter": {"enabled": true}})"));
  EXPECT_TRUE(mixed.sensor_filter.enabled);
}

TEST(SimulatedActuatorConfigJson, AKeyOfAnotherFormIsNamedNotIgnored) {
  const auto play = from_json_error(json::parse(R"({"hysteresis": {"play_offset_um": 1.0}})"));
  EXPECT_TRUE(mentions(play, "hysteresis.play_offset_um")) << play;
  EXPECT_TRUE(mentions(play, "applies to hysteresis.kind = \"modified_pi\"")) << play;
  const auto lags = from_json_error(json::parse(R"({"creep": {"time_constants_s": [1.0]}})"));
  EXPECT_TRUE(mentions(lags, "creep.time_constants_s")) << lags;
  EXPECT_TRUE(mentions(lags, "creep.law = \"input_lags\"")) << lags;
  const auto law = from_json_error(json::parse(R"({"rate_dependence": {"rate_law": "signed"}})"));
  EXPECT_TRUE(mentions(law, "rate_dependence.mechanism = \"play_weights\"")) << law;
  const auto preisach = from_json_error(
      json::parse(R"({"hysteresis": {"kind": "modified_pi", "coercive_median_v": 10}})"));
  EXPECT_TRUE(mentions(preisach, "hysteresis.kind = \"preisach\"")) << preisach;
  // A mechanism that does not fit the kind is refused too.
  const auto mismatch = from_json_error(
      json::parse(R"({"rate_dependence": {"enabled": true, "mechanism": "play_weights"}})"));
  EXPECT_TRUE(mentions(mismatch, "rate_dependence.mechanism")) << mismatch;
  EXPECT_TRUE(mentions(mismatch, "modified_pi")) << mismatch;
  const auto widening =
      from_json_error(json::parse(R"({"rate_dependence": {"threshold_rate_s": 1e-3}})"));
  EXPECT_TRUE(mentions(widening, "rate_dependence.mechanism = \"switching_thresholds\""))
      << widening;
  const auto thresholds_on_pi = from_json_error(json::parse(
      R"({"hysteresis": {"kind": "modified_pi"},
          "rate_dependence": {"enabled": true, "mechanism": "switching_thresholds"}})"));
  EXPECT_TRUE(mentions(thresholds_on_pi, "rate_dependence.mechanism")) << thresholds_on_pi;
  EXPECT_TRUE(mentions(thresholds_on_pi, "preisach")) << thresholds_on_pi;
  const auto kind = from_json_error(json::parse(R"({"hysteresis": {"kind": "bouc_wen"}})"));
  EXPECT_TRUE(mentions(kind, "hysteresis.kind")) << kind;
  EXPECT_TRUE(mentions(kind, "\"preisach\" or \"modified_pi\"")) << kind;
}

TEST(SimulatedActuatorConfigJson, MissingKeysKeepTheDefaults) {
  const auto c = hs::from_json(json::parse(R"({"sensor_filter": {"cutoff_hz": 2500}})"));
  const hs::SimulatedActuatorConfig defaults;
  EXPECT_EQ(c.sensor_filter.cutoff_hz, 2500.0);
  EXPECT_EQ(c.sensor_filter.damping_ratio, defaults.sensor_filter.damping_ratio);
  EXPECT_EQ(hs::to_json(hs::from_json(json::object())), hs::to_json(defaults));
}

TEST(SimulatedActuatorConfigJson, UnknownKeysAreNamedWithTheValidOnes) {
  const auto top = from_json_error(json::parse(R"({"dynamcis": {}})"));
  EXPECT_TRUE(mentions(top, "dynamcis")) << top;
  EXPECT_TRUE(mentions(top, "dynamics")) << top;  // listed among the valid keys

  const auto nested = from_json_error(json::parse(R"({"dynamics": {"natural_freq": 1}})"));
  EXPECT_TRUE(mentions(nested, "dynamics.natural_freq")) << nested;
  EXPECT_TRUE(mentions(nested, "natural_frequencies_hz")) << nested;
}

TEST(SimulatedActuatorConfigJson, ASeedBuiltInCodeIsTakenAsParsedTextIs) {
  // json{{"seed", 42}} holds a signed integer, where parsed text holds an unsigned one.
  const json built = {{"sensor_noise", {{"seed", 42}}}, {"thermal_drift", {{"seed", 7}}}};
  ASSERT_TRUE(built["sensor_noise"]["seed"].is_number_integer());
  ASSERT_FALSE(built["sensor_noise"]["seed"].is_number_unsigned());
  const hs::SimulatedActuatorConfig c = hs::from_json(built);
  EXPECT_EQ(c.sensor_noise.seed, 42u);
  EXPECT_EQ(c.thermal_drift.seed, 7u);
  EXPECT_TRUE(
      mentions(from_json_error(json{{"sensor_noise", {{"seed", -3}}}}), "sensor_noise.seed"));
}

TEST(SimulatedActuatorConfigJson, WrongTypesAreNamed) {
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"({"dynamics": {"damping_ratios": "0.1"}})")),
                       "dynamics.damping_ratios"));
  EXPECT_TRUE(mentions(
      from_json_error(json::parse(R"({"dynamics": {"natural_frequencies_hz": [3000, true]}})")),
      "dynamics.natural_frequencies_hz[1]"));
  EXPECT_TRUE(
      mentions(from_json_error(json::parse(R"({"delay": {"enabled": 1}})")), "delay.enabled"));
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"({"adc": {"bits": 12.5}})")), "adc.bits"));
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"({"sensor_noise": {"seed": -3}})")),
                       "sensor_noise.seed"));
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"({"thermal_drift": {"shape": "square"}})")),
                       "thermal_drift.shape"));
  EXPECT_TRUE(
      mentions(from_json_error(json::parse(R"({"rate_dependence": {"mechanism": "viscous"}})")),
               "rate_dependence.mechanism"));
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"({"input": 150})")), "input"));
  EXPECT_TRUE(mentions(from_json_error(json::parse(R"([1, 2])")), "expected an object"));
}

TEST(SimulatedActuatorConfigJson, InvalidValuesAreNamed) {
  const auto e = from_json_error(json::parse(R"({"dynamics": {"damping_ratios": [0.05, -0.1]}})"));
  EXPECT_TRUE(mentions(e, "dynamics.damping_ratios[1]")) << e;
  const auto sizes = from_json_error(json::parse(R"({"dynamics": {"mode_gains": [1.0]}})"));
  EXPECT_TRUE(mentions(sizes, "dynamics.mode_gains")) << sizes;
  const auto sum = from_json_error(json::parse(R"({"dynamics": {"mode_gains": [0.8, 0.1]}})"));
  EXPECT_TRUE(mentions(sum, "must sum to 1")) << sum;
  const auto gamma = from_json_error(json::parse(R"({"creep": {"fraction_per_decade": 0.5}})"));
  EXPECT_TRUE(mentions(gamma, "creep.fraction_per_decade")) << gamma;
  const auto grid = from_json_error(json::parse(R"({"hysteresis": {"grid_points": 8}})"));
  EXPECT_TRUE(mentions(grid, "hysteresis.grid_points")) << grid;
  const auto lag = from_json_error(
      json::parse(R"({"rate_dependence": {"enabled": true, "switching_lag_v": 0}})"));
  EXPECT_TRUE(mentions(lag, "rate_dependence.switching_lag_v")) << lag;
  const auto lags = from_json_error(json::parse(
      R"({"hysteresis": {"kind": "modified_pi"}, "creep": {"time_constants_s": [1.0]}})"));
  EXPECT_TRUE(mentions(lags, "creep.gains_um_per_v")) << lags;
  // The signed law lowers the weights on a fall: a coefficient that makes one negative at the
  // fastest fall is refused, naming it (the default is the paper's signed law).
  const auto falling = from_json_error(json::parse(
      R"({"hysteresis": {"kind": "modified_pi"},
          "rate_dependence": {"enabled": true, "max_rate_v_per_s": 5000,
          "rate_coefficients": [1e-4, 0, 0, 0, 0, 0, 0, 0, 0, 0]}})"));
  EXPECT_TRUE(mentions(falling, "rate_dependence.rate_coefficients[0]")) << falling;
  const auto negative = from_json_error(json::parse(
      R"({"rate_dependence": {"enabled": true, "mechanism": "switching_thresholds",
          "threshold_rate_s": -1e-3}})"));
  EXPECT_TRUE(mentions(negative, "rate_dependence.threshold_rate_s")) << negative;
  const auto law_on_weights = from_json_error(json::parse(
      R"({"hysteresis": {"kind": "modified_pi"},
          "rate_dependence": {"enabled": true, "rate_law": "thresholds"}})"));
  EXPECT_TRUE(mentions(law_on_weights, "rate_dependence.rate_law")) << law_on_weights;
  EXPECT_NO_THROW(hs::from_json(json::parse(
      R"({"hysteresis": {"kind": "modified_pi"},
          "rate_dependence": {"enabled": true, "rate_law": "magnitude", "max_rate_v_per_s": 5000,
          "rate_coefficients": [1e-4, 0, 0, 0, 0, 0, 0, 0, 0, 0]}})")));
}

TEST(SimulatedActuatorConfig, DefaultsAreValid) {
  EXPECT_NO_THROW(hs::validate(hs::SimulatedActuatorConfig{}));
  EXPECT_NO_THROW(hs::validate(hs::SimulatedActuatorConfig::modified_pi_truth()));
}
