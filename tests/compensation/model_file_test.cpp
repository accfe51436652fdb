#include "hystbench/compensation/model_file.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "hystbench/compensation/coupled_play_pi_model.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "support/random_models.hpp"

namespace hc = hystbench::compensation;
using nlohmann::json;

namespace {

std::string error_of(const std::string& text) {
  try {
    hc::parse_model_file(text);
  } catch (const hc::ModelFileError& e) {
    return e.what();
  }
  return "no error";
}

json valid_mpi() {
  return json::parse(R"({"schema":"hystbench.model/1","type":"mpi",
    "units":{"input":"V","output":"um"},"input_range":[0,150],
    "play":{"thresholds":[0,10,20],"weights":[0.2,0.05,0.03],"offset":1.5},
    "deadzone":{"thresholds":[-5,0,5],"weights":[0.1,1.0,-0.1],"center":20},
    "creep":{"time_constants_s":[0.1,10],"gains":[0.01,0.02]},
    "dynamics":{"natural_frequency_hz":3000,"damping_ratio":0.07},"delay_s":0.0002,
    "identification":{"data":"x.csv","samples":100}})");
}

}  // namespace

TEST(ModelFile, RoundTripsEveryFieldAndBehavesIdentically) {
  const hc::ModelFile a = hc::model_file_from_json(valid_mpi());
  const json again = hc::to_json(a);
  hc::ModelFile b = hc::model_file_from_json(again);
  EXPECT_EQ(again, hc::to_json(b));
  EXPECT_EQ(b.model.units.output, "um");
  EXPECT_EQ(b.identification["samples"], 100);
  ASSERT_TRUE(b.model.creep().has_value());
  ASSERT_TRUE(b.model.dynamics().has_value());
  hc::ActuatorModel ma = a.model;
  std::mt19937_64 rng(1);
  const auto u = hystbench::testing::random_reversal_signal(rng, 5000, 0.0, 150.0);
  const auto ya = ma.simulate(u, 1e-4);
  const auto yb = b.model.simulate(u, 1e-4);
  for (std::size_t k = 0; k < u.size(); ++k) ASSERT_DOUBLE_EQ(ya[k], yb[k]);
}

TEST(ModelFile, RateDependentRoundTrip) {
  std::mt19937_64 rng(2);
  hc::ModelFile f;
  f.model = hc::ActuatorModel(std::make_unique<hc::RateDependentPiModel>(
      hc::RateDependentPiParameters{hystbench::testing::random_mpi(rng, 5, 1, 10.0),
                                    {0, 1e-4, 2e-4, 3e-4, 4e-4},
                                    300.0,
                                    0.0,
                                    450.0}));
  const json j = hc::to_json(f);
  EXPECT_EQ(j["type"], "rpi");
  EXPECT_EQ(j["rate"]["record_max_rate"], 450.0);
  EXPECT_EQ(hc::to_json(hc::model_file_from_json(j)), j);
  // A file written before the record's rate was kept loads with it unknown (0).
  json old = j;
  old["rate"].erase("record_max_rate");
  const auto& p = dynamic_cast<const hc::RateDependentPiModel&>(
                      hc::model_file_from_json(old).model.hysteresis())
                      .parameters();
  EXPECT_EQ(p.record_max_rate, 0.0);
  old["rate"]["record_max_rate"] = -1.0;
  EXPECT_THROW(hc::model_file_from_json(old), std::exception);
}

TEST(ModelFile, TheRateLawRoundTripsAndAFileWithoutItIsTheMagnitude) {
  std::mt19937_64 rng(3);
  hc::RateDependentPiParameters p{
      hystbench::testing::random_mpi(rng, 3, 1, 10.0), {0, 1e-4, 2e-4}, 300.0};
  p.rate_law = hc::RateLaw::kSigned;
  hc::ModelFile f;
  f.model = hc::ActuatorModel(std::make_unique<hc::RateDependentPiModel>(p));
  json j = hc::to_json(f);
  EXPECT_EQ(j["rate"]["law"], "signed");
  auto law_of = [](const json& file) {
    return dynamic_cast<const hc::RateDependentPiModel&>(
               hc::model_file_from_json(file).model.hysteresis())
        .parameters()
        .rate_law;
  };
  EXPECT_EQ(law_of(j), hc::RateLaw::kSigned);
  j["rate"].erase("law");  // written before the law was a choice
  EXPECT_EQ(law_of(j), hc::RateLaw::kMagnitude);
  j["rate"]["law"] = "sign";
  try {
    hc::model_file_from_json(j);
    ADD_FAILURE() << "a bad law loaded";
  } catch (const hc::ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("rate.law"), std::string::npos) << e.what();
  }
}

// A coupled-play model carries its output dead zones when it has them; a file without them
// (the coupled-play paper's model, and every cpi file written before the stage existed) loads
// as before, with an identity output stage.
TEST(ModelFile, CoupledPlayRoundTripWithAndWithoutOutputDeadZones) {
  json j = json::parse(R"({"schema":"hystbench.model/1","type":"cpi",
    "units":{"input":"V","output":"um"},"input_range":[0,150],
    "coupled_play":{"r":[0,10,20],"ra":[0,10,20],"rb":[0,10,20],"rc":[0,30,60],
                    "weights":[0.2,0.05,0.03],"offset":1.5}})");
  const hc::ModelFile plain = hc::model_file_from_json(j);
  EXPECT_FALSE(hc::to_json(plain).contains("deadzone"));
  j["deadzone"] = valid_mpi()["deadzone"];
  const hc::ModelFile staged = hc::model_file_from_json(j);
  const json again = hc::to_json(staged);
  ASSERT_TRUE(again.contains("deadzone"));
  EXPECT_EQ(hc::to_json(hc::model_file_from_json(again)), again);
  const auto& p =
      dynamic_cast<const hc::CoupledPlayPiModel&>(staged.model.hysteresis()).parameters();
  EXPECT_DOUBLE_EQ(p.center, 20.0);
  // The stage acts on the plays' output: y = center + S[v - center], v the plain model's.
  hc::ActuatorModel a = plain.model, b = staged.model;
  const hc::DeadZoneSuperposition s(p.dead_zone);
  std::mt19937_64 rng(3);
  const auto u = hystbench::testing::random_reversal_signal(rng, 2000, 0.0, 150.0);
  const auto v = a.simulate(u, 1e-4);
  const auto y = b.simulate(u, 1e-4);
  double differs = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    ASSERT_NEAR(y[k], 20.0 + s.apply(v[k] - 20.0), 1e-12) << k;
    differs = std::max(differs, std::abs(y[k] - v[k]));
  }
  EXPECT_GT(differs, 0.1);  // the stage is not the identity on this range
  j["deadzone"]["weights"] = {0.1, 1.0};
  EXPECT_NE(error_of(j.dump()).find("deadzone.weights"), std::string::npos) << error_of(j.dump());
}

TEST(ModelFile, ErrorsNameTheField) {
  json j = valid_mpi();
  j["type"] = "bouc_wen";
  EXPECT_NE(error_of(j.dump()).find("type"), std::string::npos);
  j["type"] = "preisach";  // a known type without its member
  EXPECT_NE(error_of(j.dump()).find("preisach: missing"), std::string::npos) << error_of(j.dump());

  j = valid_mpi();
  j["play"].erase("weights");
  EXPECT_NE(error_of(j.dump()).find("play.weights: missing"), std::string::npos);

  j = valid_mpi();
  j["play"]["thresholds"] = {0, 20, 10};
  EXPECT_NE(error_of(j.dump()).find("play.thresholds[2]"), std::string::npos);

  // NaN cannot be written in JSON; tools write null or the bare word NaN.
  j = valid_mpi();
  j["deadzone"]["weights"][1] = nullptr;
  EXPECT_NE(error_of(j.dump()).find("deadzone.weights[1]"), std::string::npos);
  EXPECT_NE(error_of(R"({"schema":"hystbench.model/1","type":"pi","play":{"thresholds":[0],
    "weights":[NaN]}})")
                .find("not valid JSON"),
            std::string::npos);
  // A number beyond double is bad JSON too (the fuzzer found it escaping as out_of_range).
  EXPECT_NE(error_of(R"({"schema":"hystbench.model/1","type":"pi","play":{"thresholds":[0],
    "weights":[7e777]}})")
                .find("not valid JSON"),
            std::string::npos);

  // A file that is not JSON is described by where and what, never by its bytes: the text may be
  // a file its reader can open and whoever asked cannot.
  const std::string secret = error_of("{\n  \"type\": \"pi\",\n  Secret: hunter2\n}");
  EXPECT_EQ(secret.rfind("not valid JSON at line 3, column 3: ", 0), 0u) << secret;
  EXPECT_EQ(secret.find("Secret"), std::string::npos) << secret;
  EXPECT_EQ(secret.find("hunter2"), std::string::npos) << secret;
  EXPECT_EQ(secret.find("'S'"), std::string::npos) << secret;
  const std::string first_byte = error_of("Secret: hunter2\n");
  EXPECT_EQ(first_byte.rfind("not valid JSON at line 1, column 1: syntax error", 0), 0u)
      << first_byte;
  EXPECT_EQ(first_byte.find("'S'"), std::string::npos) << first_byte;
  EXPECT_EQ(first_byte.find("Secret"), std::string::npos) << first_byte;

  j = valid_mpi();
  j["play"]["weights"][0] = "0.2";
  EXPECT_NE(error_of(j.dump()).find("play.weights[0]: must be a number"), std::string::npos);

  j = valid_mpi();
  j["schema"] = "hystbench.model/9";
  EXPECT_NE(error_of(j.dump()).find("schema"), std::string::npos);

  j = valid_mpi();
  j["deadzone"]["thresholds"] = {-5, 1, 5};
  EXPECT_NE(error_of(j.dump()).find("deadzone.thresholds must contain 0"), std::string::npos);

  j = valid_mpi();
  j["dynamics"]["damping_ratio"] = -1;
  EXPECT_NE(error_of(j.dump()).find("dynamics.damping_ratio"), std::string::npos);
}
