// The bench on a stage of several axes, through the shipped config/loopback-xy.toml on the
// simulated clock: identify moves each axis alone and names the coupling, track plays a raster
// through each axis's inverse with the coupling taken out, the results, status and log are given
// per axis, and what the stage cannot do yet is refused with its cause.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "hystbench/common/command_error.hpp"
#include "support/bench_fixture.hpp"

namespace hd = hystbench::daemon;
namespace common = hystbench::common;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string shipped_xy_config() {
  std::ifstream in(fs::path(HYSTBENCH_SOURCE_DIR) / "config" / "loopback-xy.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  // The simulated clock, as every bench test whose figures are under test.
  const std::size_t loop = toml.find("[loop]\n");
  EXPECT_NE(loop, std::string::npos);
  toml.insert(loop + 7, "clock = \"simulated\"\n");
  return toml;
}

class BenchStage : public hystbench::test::BenchFixture {
 protected:
  BenchStage() : BenchFixture("bench_stage") {}

  void start_xy() { start(settings_from_toml(shipped_xy_config())); }

  std::pair<std::string, std::string> refused(const std::string& cmd, const json& params,
                                              std::uint64_t client = 0) {
    try {
      bench_->handle(cmd, params, client);
    } catch (const common::CommandError& e) {
      return {e.code(), e.what()};
    }
    return {"ok", ""};
  }

  std::string upload(const std::vector<double>& values, double rate_hz,
                     const std::string& kind = "reference") {
    const json begun = bench_->handle(
        "upload.begin", {{"kind", kind}, {"samples", values.size()}, {"rate_hz", rate_hz}});
    std::string name = begun["upload"];
    for (std::size_t k = 0; k < values.size(); k += 1000) {
      const std::size_t m = std::min<std::size_t>(1000, values.size() - k);
      bench_->handle("upload.chunk",
                     {{"upload", name},
                      {"offset", k},
                      {"values", std::vector<double>(values.begin() + k, values.begin() + k + m)}});
    }
    return name;
  }
};

double rms_um(const json& result, const std::string& axis) {
  return result["axes"][axis]["rms_error_um"].get<double>();
}

}  // namespace

TEST_F(BenchStage, IdentifiesEachAxisAndTheCouplingThenARasterDecoupledLeavesTenTimesLess) {
  start_xy();
  const json st = status();
  ASSERT_TRUE(st.contains("axes"));
  EXPECT_TRUE(st["axes"].contains("x") && st["axes"].contains("y"));

  const json id = run_and_wait("identify", json::object(), 600);
  ASSERT_EQ(id.value("end", ""), "completed") << id.dump();
  ASSERT_FALSE(id.contains("fit_error")) << id["fit_error"];
  const json& gains = id["stage_model"]["coupling"]["gains"];
  // The stage's truth: x reaches y at 0.1, y reaches x at 0.056 (sim::SimulatedStageConfig::xy).
  EXPECT_NEAR(gains["y<-x"]["gain"].get<double>(), 0.1, 0.01) << gains.dump();
  EXPECT_NEAR(gains["x<-y"]["gain"].get<double>(), 0.056, 0.01) << gains.dump();
  for (const char* axis : {"x", "y"}) {
    const json& fit = id["stage_model"]["axes"][axis];
    EXPECT_EQ(fit["model"], "preisach");
    EXPECT_LT(fit["heldout_rms_error_percent"].get<double>(), 1.0) << fit.dump();
    EXPECT_TRUE(
        fs::exists(dir_ / "models" / (id["run_id"].get<std::string>() + "-" + axis + ".json")));
  }
  EXPECT_TRUE(status()["stage_model"].is_object());

  const json plain = run_and_wait("track", {{"reference", "raster"}, {"decouple", false}}, 600);
  const json decoupled = run_and_wait("track", {{"reference", "raster"}}, 600);
  ASSERT_EQ(plain.value("end", ""), "completed") << plain.dump();
  ASSERT_EQ(decoupled.value("end", ""), "completed") << decoupled.dump();
  EXPECT_EQ(plain["decoupling"]["static"], false);
  EXPECT_EQ(decoupled["decoupling"]["static"], true);
  EXPECT_FALSE(decoupled["decoupling"].contains("beyond_reach")) << decoupled["decoupling"];
  const double left_plain = plain["coupling_error"]["y"]["rms_um"].get<double>();
  const double left_decoupled = decoupled["coupling_error"]["y"]["rms_um"].get<double>();
  RecordProperty("y_coupling_error_um_without", std::to_string(left_plain));
  RecordProperty("y_coupling_error_um_with", std::to_string(left_decoupled));
  RecordProperty("x_rms_percent",
                 std::to_string(decoupled["axes"]["x"]["rms_error_percent"].get<double>()));
  RecordProperty("y_rms_percent",
                 std::to_string(decoupled["axes"]["y"]["rms_error_percent"].get<double>()));
  // x's 10 Hz lines move y by a tenth of their span without the decoupling.
  EXPECT_GT(left_plain, 0.5);
  EXPECT_LT(left_decoupled, left_plain / 10.0);
  // Each axis tracks better decoupled, within a percent of its span through its inverse alone.
  for (const char* axis : {"x", "y"}) {
    EXPECT_LT(rms_um(decoupled, axis), rms_um(plain, axis)) << axis;
    EXPECT_LT(decoupled["axes"][axis]["rms_error_percent"].get<double>(), 1.0) << axis;
    for (const char* key : {"rms_error_um", "max_error_um", "model_rms_error_um", "range_um"}) {
      EXPECT_TRUE(std::isfinite(decoupled["axes"][axis][key].get<double>())) << axis << key;
    }
  }

  // The coupling's paths fitted to the responses identify measured: x's path into y shows the
  // mode the axes share (1.5 kHz). Asked for, the dynamic decoupling takes it out of a fast
  // raster's targets too. On this stage what is left on y is x's own error at that rate (its
  // drive's coupling follows its motion, not its reference), so the gain over the static
  // gains is small either way: no worse than a fifth.
  const json& paths = decoupled["decoupling"]["dynamic"]["paths"];
  ASSERT_TRUE(paths.is_array()) << decoupled["decoupling"].dump();
  bool shared_mode = false;
  for (const json& p : paths) {
    if (p["into"] != "y") continue;
    for (const json& m : p["modes"]) {
      shared_mode |= std::abs(m["frequency_hz"].get<double>() - 1500.0) < 75.0;
    }
  }
  EXPECT_TRUE(shared_mode) << paths.dump();
  const json fast = {
      {"reference", "raster"}, {"frequencies_hz", {200.0, 0.1}}, {"duration_s", 0.5}};
  json fast_dynamic = fast;
  fast_dynamic["decoupling"] = "dynamic";
  const json statically = run_and_wait("track", fast, 600);
  const json dynamically = run_and_wait("track", fast_dynamic, 600);
  ASSERT_EQ(dynamically.value("end", ""), "completed") << dynamically.dump();
  EXPECT_EQ(statically["decoupling"]["dynamic"]["used"], false);
  ASSERT_EQ(dynamically["decoupling"]["dynamic"]["used"], true) << dynamically.dump();
  EXPECT_GT(dynamically["decoupling"]["dynamic"]["sweeps"].get<int>(), 1);
  const double left_static = statically["coupling_error"]["y"]["rms_um"].get<double>();
  const double left_dynamic = dynamically["coupling_error"]["y"]["rms_um"].get<double>();
  RecordProperty("fast_raster_y_coupling_error_um_static", std::to_string(left_static));
  RecordProperty("fast_raster_y_coupling_error_um_dynamic", std::to_string(left_dynamic));
  EXPECT_LT(left_dynamic, 1.2 * left_static);
  for (const char* axis : {"x", "y"}) {
    EXPECT_TRUE(std::isfinite(dynamically["axes"][axis]["rms_error_um"].get<double>())) << axis;
  }

  // Each axis's own loop beside the decoupled feedforward, designed on the responses identify
  // measured for it.
  for (const char* axis : {"x", "y"}) {
    EXPECT_TRUE(id["stage_model"]["frequency_responses"]["axes"].contains(axis)) << id.dump();
  }
  const json fed =
      run_and_wait("track", {{"reference", "raster"}, {"compensator", "inverse+pid"}}, 600);
  ASSERT_EQ(fed.value("end", ""), "completed") << fed.dump();
  for (const char* axis : {"x", "y"}) {
    RecordProperty(std::string(axis) + "_rms_percent_with_feedback",
                   std::to_string(fed["axes"][axis]["rms_error_percent"].get<double>()));
    EXPECT_GT(fed["axes"][axis]["feedback"]["crossover_hz"].get<double>(), 100.0) << axis;
    EXPECT_LT(fed["axes"][axis]["rms_error_percent"].get<double>(), 0.1) << axis;
  }
  // The loops, each designed alone, checked together through the cross responses identify
  // measured: the stage's -20 and -25 dB keep them well inside dominance.
  const json& interaction = fed["feedback_interaction"];
  ASSERT_TRUE(interaction.is_object()) << fed.dump();
  EXPECT_EQ(interaction["dominant"], true) << interaction.dump();
  EXPECT_GT(interaction["peak"].get<double>(), 0.01) << interaction.dump();
  EXPECT_LT(interaction["peak"].get<double>(), 0.5) << interaction.dump();
  RecordProperty("feedback_interaction_peak", std::to_string(interaction["peak"].get<double>()));
  // Under the limit as designed: each loop runs as designed alone.
  EXPECT_EQ(interaction["designed_together"]["lowered_by"], 1.0) << interaction.dump();
  // tune states the loops the track ran, nothing run: each axis's, and the check together.
  const json tuned = bench_->handle("tune", json::object());
  for (const char* axis : {"x", "y"}) {
    EXPECT_NEAR(tuned["axes"][axis]["crossover_hz"].get<double>(),
                fed["axes"][axis]["feedback"]["crossover_hz"].get<double>(), 1e-9)
        << axis;
    EXPECT_FALSE(tuned["axes"][axis]["curves"].empty()) << axis;
  }
  EXPECT_NEAR(tuned["feedback_interaction"]["peak"].get<double>(),
              interaction["peak"].get<double>(), 1e-9);

  // Both axes learned at once over the default Lissajous (10 and 11 Hz, a trial its 2 s) from
  // each axis's decoupled inverse: each within 0.03 % rms after ten updates.
  const json learned =
      run_and_wait("track", {{"reference", "lissajous"}, {"learn_trials", 10}}, 600);
  ASSERT_EQ(learned.value("end", ""), "completed") << learned.dump();
  for (const char* axis : {"x", "y"}) {
    const json& a = learned["axes"][axis];
    ASSERT_TRUE(a.contains("learning")) << learned.dump();
    const json& trials = a["learning"]["trials"];
    ASSERT_GE(trials.size(), 10u) << a.dump();
    const double last = a["rms_error_percent"].get<double>();
    RecordProperty(std::string(axis) + "_lissajous_learned_rms_percent", std::to_string(last));
    EXPECT_LT(last, trials.front()["rms_error_percent"].get<double>() / 10.0) << trials.dump();
    EXPECT_LT(last, 0.03) << axis << ": " << trials.dump();
    EXPECT_EQ(a["learning"]["drive"],
              learned["run_id"].get<std::string>() + "-" + axis + "-learned");
  }
  // Each axis's drive kept; the run's id replays them all, twice in a row, each axis's trial 0
  // after a lead-in that ended for every axis at once.
  ASSERT_EQ(learned["learned_drive"], learned["run_id"]) << learned.dump();
  for (int replay = 0; replay < 2; ++replay) {
    const json again = run_and_wait(
        "track", {{"reference", "lissajous"}, {"learned", learned["learned_drive"]}}, 600);
    ASSERT_EQ(again.value("end", ""), "completed") << again.dump();
    EXPECT_EQ(again["axes"]["x"]["learning"]["lead_in_periods"],
              again["axes"]["y"]["learning"]["lead_in_periods"]);
    for (const char* axis : {"x", "y"}) {
      const double replayed = again["axes"][axis]["rms_error_percent"].get<double>();
      RecordProperty(
          std::string(axis) + "_lissajous_replayed_rms_percent_" + std::to_string(replay),
          std::to_string(replayed));
      EXPECT_LT(replayed, 0.05) << axis << " replay " << replay << ": "
                                << again["axes"][axis]["learning"].dump();
      EXPECT_EQ(again["axes"][axis]["learning"]["started_from"],
                learned["run_id"].get<std::string>() + "-" + axis + "-learned");
    }
    EXPECT_FALSE(again.contains("learned_drive"));  // a replay keeps nothing new
  }
  // A Lissajous's drives asked to replay a raster: refused in the stage's words.
  const std::string other =
      refused("track", {{"reference", "raster"}, {"learned", learned["learned_drive"]}}).second;
  EXPECT_NE(other.find("was learned for another reference or range than this raster"),
            std::string::npos)
      << other;
  // And beside each axis's loop: the loops then correct through the linear map (through each
  // axis's plane inverse their corrections jump at ticks that differ from trial to trial, ring
  // the shared mode, and the learning stalled at 0.09-0.15 %, three to five times its floor).
  const json beside_loops = run_and_wait(
      "track", {{"reference", "lissajous"}, {"compensator", "inverse+pid"}, {"learn_trials", 10}},
      600);
  ASSERT_EQ(beside_loops.value("end", ""), "completed") << beside_loops.dump();
  for (const char* axis : {"x", "y"}) {
    const json& a = beside_loops["axes"][axis];
    EXPECT_EQ(a["feedback"]["through"], "the linear map") << axis;
    EXPECT_TRUE(a["feedback"].contains("through_why")) << axis;
    const json& trials = a["learning"]["trials"];
    ASSERT_GE(trials.size(), 4u) << a.dump();
    const double last = a["rms_error_percent"].get<double>();
    RecordProperty(std::string(axis) + "_lissajous_learned_beside_loop_rms_percent",
                   std::to_string(last));
    EXPECT_LT(last, trials.front()["rms_error_percent"].get<double>() / 2.0) << trials.dump();
    EXPECT_LT(last, 0.03) << axis << ": " << trials.dump();
  }
  // A track without learning keeps its loops through the inverse, as tune states them.
  EXPECT_EQ(fed["axes"]["x"]["feedback"]["through"], "the model's inverse");

  // The log: one row per tick, a set of columns per axis.
  std::ifstream log(decoupled["log"].get<std::string>());
  std::string line;
  while (std::getline(log, line) && line.rfind('#', 0) == 0) {
  }
  EXPECT_NE(line.find(",yr_x,u_ff_x,u_fb_x,u_x,y_x,y_model_x,flags_x,yr_y,"), std::string::npos)
      << line;
  // Every axis's measurement and the stage's prediction for it, from the first tick on (yr is
  // NaN through the open-loop precondition, as on one axis).
  std::getline(log, line);
  std::vector<std::string> cells;
  std::stringstream row(line);
  for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
  ASSERT_EQ(cells.size(), 19u) << line;
  for (const std::size_t column : {9u, 10u, 16u, 17u}) {
    EXPECT_TRUE(std::isfinite(std::stod(cells[column]))) << column << ": " << line;
  }

  // A daemon restarted loads the stage back by its identify's run id: each axis's model with the
  // responses its loop is designed on, and the coupling, as they were. Or from the files'
  // documents sent by axis (`hystbench model load RUN-x.json RUN-y.json` from elsewhere), which
  // it keeps as the identify's files again; one axis's alone is refused, keeping nothing.
  bench_.reset();
  json documents = json::object();
  for (const char* axis : {"x", "y"}) {
    const fs::path file =
        dir_ / "models" / (id["run_id"].get<std::string>() + "-" + axis + ".json");
    std::ifstream in(file);
    documents[axis] = json::parse(in);
    fs::remove(file);
  }
  start_xy();
  EXPECT_EQ(refused("model.load", {{"models", {{"x", documents["x"]}}}}).second,
            "models: no model for axis 'y' (a stage's models load together)");
  EXPECT_FALSE(fs::exists(dir_ / "models" / (id["run_id"].get<std::string>() + "-x.json")));
  EXPECT_EQ(bench_->handle("model.load", {{"models", documents}})["stage_run_id"], id["run_id"]);
  bench_.reset();
  start_xy();
  EXPECT_TRUE(status()["stage_model"].is_null());
  const json loaded = bench_->handle("model.load", {{"stored", id["run_id"]}});
  EXPECT_EQ(loaded["stage_run_id"], id["run_id"]);
  for (const char* axis : {"x", "y"}) {
    EXPECT_EQ(loaded["axes"][axis]["responses"], true) << axis;
    // Identified on this bench: its drives within the limits, no warning.
    EXPECT_TRUE(loaded["axes"][axis]["input_range"]["model"].is_array()) << axis;
    EXPECT_FALSE(loaded["axes"][axis].contains("warning")) << loaded["axes"][axis].dump();
  }
  EXPECT_NEAR(loaded["coupling"]["gains"]["y<-x"]["gain"].get<double>(),
              gains["y<-x"]["gain"].get<double>(), 1e-12);
  // Both axes' files are the active models: listed so, and not deleted under the stage.
  for (const json& m : bench_->handle("model.list", json::object())["models"]) {
    EXPECT_EQ(m["active"], true) << m.dump();
  }
  const std::string x_file = id["run_id"].get<std::string>() + "-x.json";
  EXPECT_EQ(refused("model.delete", {{"name", x_file}}).first, "bad_params");
  EXPECT_TRUE(fs::exists(dir_ / "models" / x_file));
  const json again =
      run_and_wait("track", {{"reference", "raster"}, {"compensator", "inverse+pid"}}, 600);
  ASSERT_EQ(again.value("end", ""), "completed") << again.dump();
  EXPECT_EQ(again["decoupling"]["static"], true);
  for (const char* axis : {"x", "y"}) {
    EXPECT_GT(again["axes"][axis]["feedback"]["crossover_hz"].get<double>(), 100.0) << axis;
    EXPECT_LT(again["axes"][axis]["rms_error_percent"].get<double>(), 0.1) << axis;
  }
  EXPECT_NEAR(again["feedback_interaction"]["peak"].get<double>(),
              interaction["peak"].get<double>(), 1e-9);
}

// A stage whose axes reach each other at 0.4 through the mode they share (sensors that see the
// coupled stroke). Each axis's loop designed alone (crossovers near 420 Hz) would reach 1.6
// checked together, and run so, they oscillate. Designed for the coupling, every loop is
// lowered by one factor until the check stays under 0.7, and the raster tracks. Its
// references span 40 % of each range: at 80 % a strongly coupled stage asks an axis for less
// than its stroke's floor.
TEST_F(BenchStage, LoopsOnAStronglyCoupledStageAreLoweredUntilTheyHoldTogether) {
  std::string toml = shipped_xy_config();
  const std::string stage = "[driver.loopback.stage]\n";
  toml.insert(toml.find(stage) + stage.size(),
              "axes = [{name = \"x\", actuator = {adc = {range_max = 100.0}}}, "
              "{name = \"y\", actuator = {adc = {range_max = 100.0}}}]\n");
  toml += "\n[driver.loopback.stage.coupling]\ngains = [[0.0, 0.4], [0.4, 0.0]]\n";
  start(settings_from_toml(toml));
  const json id = run_and_wait("identify", json::object(), 600);
  ASSERT_EQ(id.value("end", ""), "completed") << id.dump();
  const json fed = run_and_wait(
      "track", {{"reference", "raster"}, {"range_fraction", 0.4}, {"compensator", "inverse+pid"}},
      600);
  ASSERT_EQ(fed.value("end", ""), "completed") << fed.value("reason", "") << fed.dump();
  const json& interaction = fed["feedback_interaction"];
  const json& together = interaction["designed_together"];
  ASSERT_TRUE(together.is_object()) << interaction.dump();
  RecordProperty("peak_alone", std::to_string(together["peak_alone"].get<double>()));
  RecordProperty("lowered_by", std::to_string(together["lowered_by"].get<double>()));
  EXPECT_GT(together["peak_alone"].get<double>(), 1.0) << together.dump();
  const double by = together["lowered_by"].get<double>();
  EXPECT_GT(by, 0.2);
  EXPECT_LT(by, 0.95);
  EXPECT_LE(interaction["peak"].get<double>(), 0.7 + 1e-6) << interaction.dump();
  EXPECT_EQ(interaction["dominant"], true);
  for (const char* axis : {"x", "y"}) {
    const json& a = fed["axes"][axis];
    EXPECT_NEAR(a["feedback"]["lowered"]["by"].get<double>(), by, 1e-12) << axis;
    EXPECT_EQ(a["feedback"]["meets_targets"], true) << axis;
    RecordProperty(std::string(axis) + "_rms_percent",
                   std::to_string(a["rms_error_percent"].get<double>()));
    EXPECT_LT(a["rms_error_percent"].get<double>(), 0.2) << axis;
  }
  // tune designs them the same way, nothing run.
  const json tuned = bench_->handle("tune", json::object());
  EXPECT_NEAR(tuned["feedback_interaction"]["designed_together"]["lowered_by"].get<double>(), by,
              1e-12)
      << tuned["feedback_interaction"].dump();
  // Over 80 % of each range the coupling taken out asks an axis for less than its stroke's
  // floor: the run says so (its reply too, before it starts), naming how far.
  const json wide = run_and_wait(
      "track", {{"reference", "raster"}, {"compensator", "inverse"}, {"duration_s", 0.2}}, 600);
  const json& beyond = wide["decoupling"]["beyond_reach"];
  ASSERT_TRUE(beyond.is_object()) << wide["decoupling"].dump();
  // y, at x's top, would have to go 14 µm under its floor.
  EXPECT_GT(beyond["y"]["below_um"].get<double>(), 10.0) << beyond.dump();
}

TEST_F(BenchStage, RefusesWhatDrivesOneAxisAndReferencesThatDoNotNameEveryAxis) {
  start_xy();
  {
    const auto [code, message] = refused("model.load", {{"model", json::object()}});
    EXPECT_EQ(code, "not_on_stage") << message;
    EXPECT_NE(message.find("stage of 2 axes"), std::string::npos) << message;
  }
  // excite drives every axis: one drive is refused, naming what a stage's takes.
  EXPECT_NE(refused("excite", {{"drive_upload", "u"}})
                .second.find("drive_uploads: missing; a stage's excite names a complete drive "
                             "upload per axis"),
            std::string::npos);
  const std::string u = upload(std::vector<double>(100, 10.0), 1000.0, "drive");
  EXPECT_EQ(refused("excite", {{"drive_uploads", {{"x", u}}}}).second,
            "drive_uploads: no drive for axis 'y' (a stage's excite drives every axis)");
  const std::string x = upload(std::vector<double>(2000, 10.0), 10000.0);
  EXPECT_EQ(refused("track", {{"reference_uploads", {{"x", x}}}}).second,
            "reference_uploads: no reference for axis 'y' (a stage's reference names every axis)");
  EXPECT_EQ(refused("track", {{"reference_uploads", {{"x", x}, {"y", x}, {"z", x}}}}).second,
            "reference_uploads: 'z' is no axis of the stage");
  EXPECT_NE(refused("track", {{"reference", "zigzag"}}).second.find("reference: "),
            std::string::npos);
  EXPECT_NE(refused("track", {{"reference", "raster"}, {"decoupling", "full"}})
                .second.find("decoupling: 'static' (the default"),
            std::string::npos);
  // A stage's learned drive is its learning run's, one file per axis; each is looked for.
  const std::string none =
      refused("track", {{"reference", "lissajous"}, {"learned", "20260101T000000Z-track-1"}})
          .second;
  EXPECT_NE(none.find("learned: no learned drive '20260101T000000Z-track-1-x-learned'"),
            std::string::npos)
      << none;
  EXPECT_NE(
      refused("track", {{"reference", "lissajous"}, {"learned", "20260101T000000Z-track-1-y"}})
          .second.find("learned: on a stage, the learning run's id (20260101T000000Z-track-1)"),
      std::string::npos);
  // Each axis's responses are measured for its model: identify first.
  EXPECT_EQ(refused("frf", json::object()).first, "no_model");
  EXPECT_EQ(refused("tune", json::object()).first, "no_frequency_response");
  EXPECT_EQ(refused("tune", {{"compensator", "inverse+pid"}}).first, "no_model");
  EXPECT_NE(refused("track", {{"reference", "raster"}, {"frequency_hz", 5.0}})
                .second.find("frequency_hz: a one-axis reference's key"),
            std::string::npos);
  // Nothing ran.
  EXPECT_TRUE(status()["last_result"].is_null());
}

TEST_F(BenchStage, TracksAnUploadedReferencePerAxisWithoutAModel) {
  start_xy();
  // 1 s of a 2 Hz sine on x beside a held y, each within the configured 0..44 um range.
  std::vector<double> xs, ys;
  for (int k = 0; k <= 1000; ++k) {
    xs.push_back(22.0 + 10.0 * std::sin(2.0 * M_PI * 2.0 * k / 1000.0));
    ys.push_back(15.0);
  }
  const std::string x = upload(xs, 1000.0), y = upload(ys, 1000.0);
  const json r = run_and_wait("track", {{"reference_uploads", {{"x", x}, {"y", y}}}}, 300);
  ASSERT_EQ(r.value("end", ""), "completed") << r.dump();
  EXPECT_EQ(r["compensator"], "none");
  EXPECT_EQ(r["decoupling"]["static"], false);
  for (const char* axis : {"x", "y"}) {
    EXPECT_TRUE(std::isfinite(r["axes"][axis]["rms_error_um"].get<double>())) << axis;
  }
  // The other axis's motion shows on y: x moved, y was held.
  EXPECT_GT(std::abs(r["coupling_error"]["y"]["gain_from"]["x"].get<double>()), 0.02)
      << r["coupling_error"].dump();
  // The built-in references of a stage, over the configured range without a model.
  for (const json& params :
       {json{{"reference", "lissajous"}}, json{{"reference", "spiral"}, {"duration_s", 2.0}}}) {
    const json b = run_and_wait("track", params, 300);
    ASSERT_EQ(b.value("end", ""), "completed") << b.dump();
    for (const char* axis : {"x", "y"}) {
      EXPECT_GT(b["axes"][axis]["range_um"].get<double>(), 20.0) << params.dump() << axis;
    }
  }
}

// excite on a stage: each axis plays its own drive open loop in one run, the shorter one
// holding its last value, and the log holds every axis's drive and reading.
TEST_F(BenchStage, ExcitesEachAxisWithItsOwnDrive) {
  start_xy();
  std::vector<double> xs, ys;
  for (int k = 0; k <= 1000; ++k) {
    xs.push_back(75.0 + 40.0 * std::sin(2.0 * M_PI * 3.0 * k / 1000.0));
    if (k < 600) ys.push_back(40.0 + 20.0 * k / 600.0);
  }
  const json r = run_and_wait(
      "excite",
      {{"drive_uploads", {{"x", upload(xs, 1000.0, "drive")}, {"y", upload(ys, 1000.0, "drive")}}}},
      300);
  ASSERT_EQ(r.value("end", ""), "completed") << r.dump();
  std::ifstream log(r["log"].get<std::string>());
  std::string line;
  while (std::getline(log, line) && line.rfind('#', 0) == 0) {
  }
  std::vector<std::string> names;
  {
    std::stringstream header(line);
    for (std::string cell; std::getline(header, cell, ',');) names.push_back(cell);
  }
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  ASSERT_LT(column("u_y"), names.size()) << line;
  double x_lo = 1e9, x_hi = -1e9, y_last = 0.0;
  std::size_t rows = 0;
  while (std::getline(log, line)) {
    std::vector<std::string> cells;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    const double ux = std::stod(cells[column("u_x")]);
    x_lo = std::min(x_lo, ux), x_hi = std::max(x_hi, ux);
    y_last = std::stod(cells[column("u_y")]);
    for (const char* y : {"y_x", "y_y"}) EXPECT_TRUE(std::isfinite(std::stod(cells[column(y)])));
    ++rows;
  }
  EXPECT_GT(rows, 10000u);  // 1 s of drive at the 10 kHz loop, after the ramps
  EXPECT_GT(x_hi - x_lo, 75.0);
  EXPECT_NEAR(y_last, ys.back(), 1e-9);  // y held its last drive while x played on
}

TEST_F(BenchStage, AOneAxisBenchRefusesAStagesKeysByName) {
  start(settings_from_toml(loopback_toml()));
  const auto [code, message] = refused("track", {{"reference", "sine"}, {"frequencies_hz", {10}}});
  EXPECT_EQ(code, "not_on_stage");
  EXPECT_EQ(message, "frequencies_hz: a stage's key (several axes); this bench drives one axis");
  EXPECT_EQ(refused("track", {{"reference_uploads", {{"x", "a"}}}}).first, "not_on_stage");
  EXPECT_EQ(refused("track", {{"reference", "sine"}, {"decoupling", "dynamic"}}).first,
            "not_on_stage");
  EXPECT_EQ(refused("excite", {{"drive_uploads", {{"x", "a"}}}}).first, "not_on_stage");
  EXPECT_EQ(refused("model.load", {{"models", {{"x", json::object()}}}}).first, "not_on_stage");
  EXPECT_FALSE(status().contains("axes"));
}
