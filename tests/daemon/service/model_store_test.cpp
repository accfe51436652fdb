// The bench's model store: what it adopts, loads and keeps, and the generation runs key on.
#include "service/details/model_store.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "hystbench/common/command_error.hpp"
#include "hystbench/common/model_file_io.hpp"
#include "hystbench/compensation/pi_model.hpp"

namespace hc = hystbench::compensation;
namespace hd = hystbench::daemon::details;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

hc::ModelFile pi_model(double slope) {
  hc::ActuatorModel m(
      std::make_unique<hc::PiModel>(hc::PiParameters{{0.0, 20.0}, {slope, 0.1}, 0.0}));
  m.input_min = 0.0;
  m.input_max = 150.0;
  return hc::ModelFile{std::move(m), json::object()};
}

// One flat response of gain 0.3 over three lines, as measured by run `run_id`.
hc::StageResponses responses(const std::string& run_id) {
  hc::MeasuredResponse m;
  m.frequency_hz = {10.0, 100.0, 1000.0};
  m.response.assign(3, {0.3, 0.0});
  m.noise.assign(3, 1e-4);
  m.coherence.assign(3, 1.0);
  m.operating_point = 75.0;
  m.amplitude = 1.5;
  m.label = "u 75 V";
  hc::StageResponses r;
  r.rate_hz = 10000.0;
  r.responses = {m};
  r.run_id = run_id;
  return r;
}

class ModelStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("hystbench-model-store-" +
            std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(ModelStoreTest, WithoutAModelGetRefusesAndStatusSaysNull) {
  hd::ModelStore store(dir_.string());
  EXPECT_EQ(store.active(), nullptr);
  EXPECT_TRUE(store.summary().is_null());
  try {
    (void)store.get();
    FAIL() << "model.get without a model answered";
  } catch (const hystbench::common::CommandError& e) {
    EXPECT_EQ(e.code(), "no_model");
  }
}

TEST_F(ModelStoreTest, EveryChangeRunsSeeIsANewGeneration) {
  hd::ModelStore store(dir_.string());
  const auto g0 = store.generation();
  store.adopt(pi_model(0.3), (dir_ / "a.json").string());
  EXPECT_GT(store.generation(), g0);
  const auto g1 = store.generation();
  store.changed();  // a stage's model
  EXPECT_GT(store.generation(), g1);
  EXPECT_EQ(store.active_path(), (dir_ / "a.json").string());
  EXPECT_EQ(store.summary()["type"], "pi");
}

TEST_F(ModelStoreTest, ADocumentIsKeptUnderItsNameAndLoadsAgainByThatName) {
  hd::ModelStore store(dir_.string());
  const json loaded = store.load_document("mine", hc::to_json(pi_model(0.4)));
  EXPECT_EQ(loaded["name"], "mine.json");
  EXPECT_TRUE(fs::exists(dir_ / "mine.json"));
  const auto g = store.generation();
  hd::ModelStore again(dir_.string());
  const json stored = again.load_stored("mine");
  EXPECT_EQ(stored["path"], (dir_ / "mine.json").string());
  EXPECT_EQ(again.get()["model"], store.get()["model"]);
  EXPECT_EQ(store.generation(), g);  // loading into another store changes nothing here
}

TEST_F(ModelStoreTest, AModelOfDrivesBeyondTheBenchsLimitsLoadsWithAWarningNamingBoth) {
  // pi_model was identified on [0, 150] V: a bench whose driver puts out 0-10 V (a DAQ into an
  // amplifier) would clamp nearly every drive its inverse asks for.
  hd::ModelStore daq(dir_.string(), 0.0, 10.0);
  const json loaded = daq.load_document("amplifier", hc::to_json(pi_model(0.4)));
  EXPECT_EQ(loaded["input_range"]["model"], json::array({0.0, 150.0}));
  EXPECT_EQ(loaded["input_range"]["limits"], json::array({0.0, 10.0}));
  ASSERT_TRUE(loaded.contains("warning")) << loaded.dump();
  EXPECT_NE(loaded["warning"].get<std::string>().find("[0, 150] V"), std::string::npos);
  EXPECT_NE(loaded["warning"].get<std::string>().find("[0, 10] V"), std::string::npos);
  ASSERT_NE(daq.active(), nullptr);  // loaded all the same: the user may know better
  // On the bench it was identified on, or one a little narrower (within 1 % of the span): no
  // warning.
  for (const double u_max : {150.0, 149.0}) {
    hd::ModelStore same(dir_.string(), 0.0, u_max);
    const json again = same.load_stored("amplifier");
    EXPECT_FALSE(again.contains("warning")) << u_max << ": " << again.dump();
  }
}

TEST_F(ModelStoreTest, AModelOfAnotherInputUnitLoadsWithAWarningNamingIt) {
  hc::ModelFile force = pi_model(0.4);
  force.model.units.input = "N";  // a shaker's force record, fitted offline
  hd::ModelStore bench(dir_.string(), 0.0, 150.0);
  const json loaded = bench.load_document("shaker", hc::to_json(force));
  ASSERT_TRUE(loaded.contains("warning")) << loaded.dump();
  EXPECT_NE(loaded["warning"].get<std::string>().find("input is in N"), std::string::npos);
}

TEST_F(ModelStoreTest, ARefusedLoadChangesNothing) {
  hd::ModelStore store(dir_.string());
  store.adopt(pi_model(0.3), (dir_ / "a.json").string());
  const auto g = store.generation();
  EXPECT_THROW((void)store.load_stored("../etc/passwd"), hystbench::common::CommandError);
  EXPECT_THROW((void)store.load_stored("absent"), hystbench::common::CommandError);
  EXPECT_EQ(store.generation(), g);
  EXPECT_EQ(store.active_path(), (dir_ / "a.json").string());
}

TEST_F(ModelStoreTest, MeasuredResponsesGoWithTheActiveModelAndItsFile) {
  hd::ModelStore store(dir_.string());
  json report = json::object();
  store.keep_frf_responses(responses("frf-1"), report);
  ASSERT_NE(store.design_responses(), nullptr);  // the bench's, without a model
  EXPECT_EQ(store.design_responses()->run_id, "frf-1");
  EXPECT_FALSE(report.contains("kept_in"));

  const fs::path path = dir_ / "m.json";
  hystbench::common::save_model_file(path.string(), pi_model(0.3));
  store.adopt(hystbench::common::load_model_file(path.string()), path.string());
  EXPECT_EQ(store.design_responses()->run_id, "frf-1");  // the model holds none
  store.keep_frf_responses(responses("frf-2"), report);
  EXPECT_EQ(report["kept_in"], path.string());
  EXPECT_EQ(store.design_responses()->run_id, "frf-2");
  const hc::ModelFile saved = hystbench::common::load_model_file(path.string());
  ASSERT_TRUE(saved.responses.has_value());
  EXPECT_EQ(saved.responses->run_id, "frf-2");
}

}  // namespace
