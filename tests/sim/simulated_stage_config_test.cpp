#include "hystbench/sim/simulated_stage_config.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace hs = hystbench::sim;
using json = nlohmann::json;

namespace {

// The message of the std::invalid_argument that stage_from_json(j) throws ("" if none).
std::string refusal(const json& j) {
  try {
    hs::stage_from_json(j);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

json two_axes() { return json::parse(R"({"axes": [{"name": "x"}, {"name": "y"}]})"); }

}  // namespace

TEST(SimulatedStageConfig, TheDefaultStageHasTwoAxesThatDifferAndCoupleBothWays) {
  const hs::SimulatedStageConfig c = hs::SimulatedStageConfig::xy();
  ASSERT_EQ(c.axes.size(), 2u);
  EXPECT_EQ(c.axes[0].name, "x");
  EXPECT_EQ(c.axes[1].name, "y");
  EXPECT_NE(c.axes[0].actuator.hysteresis.bias_mean_v, c.axes[1].actuator.hysteresis.bias_mean_v);
  EXPECT_NE(c.axes[0].actuator.creep.fraction_per_decade,
            c.axes[1].actuator.creep.fraction_per_decade);
  EXPECT_NE(c.axes[0].actuator.sensor_noise.seed, c.axes[1].actuator.sensor_noise.seed);
  // -30 to -15 dB each way.
  for (const double k : {c.coupling.gains[0][1], c.coupling.gains[1][0]}) {
    EXPECT_GE(20.0 * std::log10(k), -30.0);
    EXPECT_LE(20.0 * std::log10(k), -15.0);
  }
  EXPECT_NO_THROW(hs::validate(c));
}

TEST(SimulatedStageConfig, JsonRoundTripKeepsEveryField) {
  hs::SimulatedStageConfig c = hs::SimulatedStageConfig::xy();
  c.axes[1].actuator.delay.enabled = true;
  c.coupling.shared_mode_hz = 900.0;
  const json j = hs::to_json(c);
  EXPECT_EQ(hs::to_json(hs::stage_from_json(j)), j);
  EXPECT_EQ(hs::to_json(hs::stage_from_json(json::object())),
            hs::to_json(hs::SimulatedStageConfig::xy()));
}

TEST(SimulatedStageConfig, AxesGivenStartUncoupledWithTheirOwnNoiseSeeds) {
  json j = two_axes();
  j["axes"][1]["actuator"] = json::parse(R"({"sensor_noise": {"seed": 42}})");
  const hs::SimulatedStageConfig c = hs::stage_from_json(j);
  EXPECT_TRUE(c.coupling.gains.empty());
  EXPECT_EQ(c.axes[0].actuator.sensor_noise.seed, 1u);
  EXPECT_EQ(c.axes[0].actuator.thermal_drift.seed, 2u);
  EXPECT_EQ(c.axes[1].actuator.sensor_noise.seed, 42u);
  EXPECT_EQ(c.axes[1].actuator.thermal_drift.seed, 4u);
}

TEST(SimulatedStageConfig, BadInputIsRefusedNamingTheField) {
  json seven = json::object();
  seven["axes"] = json::array();
  for (int i = 0; i < 7; ++i) seven["axes"].push_back({{"name", "a" + std::to_string(i)}});
  EXPECT_EQ(refusal(seven), "axes: a stage has 1 to 6 axes, this one 7");
  EXPECT_EQ(refusal(json::parse(R"({"axes": []})")), "axes: a stage has 1 to 6 axes, this one 0");

  json same = two_axes();
  same["axes"][1]["name"] = "x";
  EXPECT_EQ(refusal(same), "axes[1].name: \"x\" names two axes");
  json bad_name = two_axes();
  bad_name["axes"][0]["name"] = "X axis";
  EXPECT_EQ(refusal(bad_name), "axes[0].name: \"X axis\": 1 to 16 of a-z, 0-9 and _");
  EXPECT_EQ(refusal(json::parse(R"({"axes": [{"actuator": {}}]})")),
            "axes[0].name: missing: every axis needs a name");

  json actuator = two_axes();
  actuator["axes"][1]["actuator"] = {{"creep", {{"fraction_per_decade", 0.5}}}};
  EXPECT_NE(refusal(actuator).find("axes[1].actuator.creep.fraction_per_decade"), std::string::npos)
      << refusal(actuator);

  json rows = two_axes();
  rows["coupling"] = {{"gains", {{0.0, 0.1}}}};
  EXPECT_EQ(refusal(rows), "coupling.gains: needs one row per axis (2), has 1");
  json diagonal = two_axes();
  diagonal["coupling"] = {{"gains", {{0.2, 0.1}, {0.1, 0.0}}}};
  EXPECT_EQ(refusal(diagonal),
            "coupling.gains[0][0]: must be 0 (an axis's own gain is its actuator's)");
  json large = two_axes();
  large["coupling"] = {{"gains", {{0.0, 0.7}, {0.1, 0.0}}}};
  EXPECT_EQ(refusal(large), "coupling.gains[0][1]: must be in [-0.5, 0.5]");
  json mode = two_axes();
  mode["coupling"] = {{"shared_mode_hz", -1.0}};
  EXPECT_EQ(refusal(mode), "coupling.shared_mode_hz: must be > 0");
  EXPECT_EQ(refusal(json::parse(R"({"coupling": {"gain": 1}})")),
            "coupling.gain: unknown key (valid: enabled, gains, shared_mode_hz, "
            "shared_damping_ratio)");
  EXPECT_EQ(refusal(json::parse(R"({"axis": []})")), "axis: unknown key (valid: axes, coupling)");
}
