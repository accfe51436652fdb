// The bench end to end in-process, on the loopback driver (no socket).
#include "hystbench/daemon/service/bench.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/daemon/loop/sample_log_writer.hpp"
#include "hystbench/sim/simulated_actuator.hpp"
#include "support/bench_fixture.hpp"

namespace hd = hystbench::daemon;
namespace cli = hystbench::cli;
namespace common = hystbench::common;
namespace hc = hystbench::compensation;
namespace hs = hystbench::sim;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

class BenchTest : public hystbench::test::BenchFixture {
 protected:
  BenchTest() : BenchFixture("hystbench_bench_test") {}
  // The loopback at `rate_hz` with the 0..45 um range from a config file (the user's path), on
  // the simulated clock unless `loop_keys` says otherwise; precondition 0.4 s.
  hd::BenchSettings settings(double rate_hz = 5000.0,
                             const std::string& loop_keys = kSimulatedClock) const {
    hd::BenchSettings s = settings_from_toml(loopback_toml({}, loop_keys, rate_hz, 45.0));
    s.precondition_s = 0.4;
    return s;
  }
  // The short identification (shorten_identify).
  hd::BenchSettings short_identify_settings(const std::string& loop_keys = kSimulatedClock) const {
    hd::BenchSettings s = settings(5000.0, loop_keys);
    shorten_identify(s);
    return s;
  }
  // The loopback's modified-PI truth with its rate dependence on, and that truth as the model: a
  // model whose law lags the drive, which the bench plans before it plays.
  void start_rate_dependent_with_its_truth() {
    start(settings_from_toml(
        loopback_toml("[actuator.hysteresis]\nkind = "
                      "\"modified_pi\"\n[actuator.rate_dependence]\nenabled = true\n")));
    hs::SimulatedActuatorConfig truth = hs::SimulatedActuatorConfig::modified_pi_truth();
    truth.rate_dependence.enabled = true;
    const hc::ModelFile model{hs::make_truth_model(truth, 1e-4), json::object()};
    bench_->handle("model.load", {{"model", hc::to_json(model)}, {"name", "truth-rpi.json"}});
  }
  std::string error_code(const std::string& cmd, const json& params) {
    try {
      bench_->handle(cmd, params);
    } catch (const common::CommandError& e) {
      return e.code();
    }
    return "ok";
  }
};

}  // namespace

TEST_F(BenchTest, TrackWithoutModelLogsEverySampleWithNoCellEmptyAndReportsHysteresis) {
  start(settings());
  const json r =
      run_and_wait("track", {{"compensator", "none"}, {"periods", 3}, {"frequency_hz", 2}});
  ASSERT_EQ(r["end"], "completed") << r.dump(2);
  EXPECT_EQ(r["reason"], "every planned sample played");
  EXPECT_EQ(r["samples"], r["planned_samples"]);
  EXPECT_EQ(r["dropped"], 0);
  EXPECT_EQ(r["logged"], r["samples"]);
  // The default actuator has 15-20 % hysteresis; the linear map leaves it all in place.
  EXPECT_GT(r["hysteresis_percent"].get<double>(), 8.0);
  const auto table = cli::DataTable::read_csv(r["log"].get<std::string>());
  EXPECT_EQ(table.rows(), r["samples"].get<std::size_t>());
  const auto& index = table.column("index");
  for (std::size_t k = 0; k < index.size(); ++k) ASSERT_EQ(index[k], static_cast<double>(k));
  const json header = hd::read_sample_log_header(r["log"].get<std::string>());
  EXPECT_EQ(header["run"]["compensator"], "none");
  // No cell is left empty: the precondition sweep before the reference follows none, and its
  // rows say so by their flag, with the model's output (here the limits' line) as yr.
  for (const std::string& name : table.names()) {
    const auto& c = table.column(name);
    ASSERT_TRUE(std::all_of(c.begin(), c.end(), [](double v) { return std::isfinite(v); })) << name;
  }
  const auto open_loop = header["flags"]["open_loop"].get<std::uint32_t>();
  const auto &flags = table.column("flags"), &yr = table.column("yr"),
             &y_model = table.column("y_model");
  std::size_t open_rows = 0;
  for (std::size_t k = 0; k < flags.size(); ++k) {
    if ((static_cast<std::uint32_t>(flags[k]) & open_loop) == 0U) continue;
    ASSERT_EQ(open_rows, k) << "an open-loop row after the reference began";
    ASSERT_EQ(yr[k], y_model[k]) << k;
    ++open_rows;
  }
  EXPECT_GT(open_rows, 0U);
  EXPECT_LT(open_rows, flags.size());
}

// model.load carries the model document; the daemon keeps a copy in its model folder, lists it,
// and loads it again by name. A path is refused: the daemon never opens a path a client names,
// and a name cannot leave the model folder.
TEST_F(BenchTest, ModelsTravelAsDocumentsAndLoadByNameFromTheModelFolder) {
  start(settings());
  hc::ActuatorModel model(
      std::make_unique<hc::PiModel>(hc::PiParameters{{0.0, 20.0}, {0.3, 0.1}, 0.0}));
  model.input_min = 0.0;
  model.input_max = 150.0;
  const json document = hc::to_json(hc::ModelFile{model, json::object()});
  const json loaded = bench_->handle("model.load", {{"model", document}, {"name", "mine.json"}});
  EXPECT_EQ(loaded["type"], "pi");
  EXPECT_EQ(loaded["name"], "mine.json");
  EXPECT_EQ(fs::path(loaded["path"].get<std::string>()).parent_path(),
            fs::path(settings().model_dir));
  EXPECT_EQ(bench_->handle("status", json::object())["model"]["type"], "pi");

  const json list = bench_->handle("model.list", json::object());
  ASSERT_EQ(list["models"].size(), 1u) << list.dump();
  EXPECT_EQ(list["models"][0]["name"], "mine.json");
  EXPECT_EQ(list["models"][0]["type"], "pi");
  EXPECT_TRUE(list["models"][0]["active"].get<bool>());

  EXPECT_EQ(bench_->handle("model.load", {{"stored", "mine"}})["type"], "pi");
  EXPECT_EQ(error_code("model.load", {{"stored", "../mine.json"}}), "bad_params");
  EXPECT_EQ(error_code("model.load", {{"stored", "/etc/passwd"}}), "bad_params");
  EXPECT_EQ(error_code("model.load", {{"stored", "absent"}}), "bad_params");
  EXPECT_EQ(error_code("model.load", {{"model", document}, {"name", "../escape"}}), "bad_params");
  EXPECT_EQ(error_code("model.load", {{"path", "/etc/passwd"}}), "bad_params");
  EXPECT_EQ(error_code("model.load", json::object()), "bad_params");
  EXPECT_EQ(error_code("model.load", {{"model", "text"}}), "bad_params");
  json broken = document;
  broken["play"]["weights"] = {0.3};
  EXPECT_EQ(error_code("model.load", {{"model", broken}}), "bad_model");
  // A stored file that is not a model is reported without its text.
  std::ofstream(fs::path(settings().model_dir) / "notes.json") << "Secret: hunter2\n";
  try {
    bench_->handle("model.load", {{"stored", "notes.json"}});
    ADD_FAILURE() << "a text file loaded as a model";
  } catch (const common::CommandError& e) {
    EXPECT_EQ(std::string(e.what()).find("hunter2"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find("Secret"), std::string::npos) << e.what();
  }
  EXPECT_EQ(bench_->handle("model.list", json::object())["models"].size(), 2u);

  // model.delete: never the active model, never a path; a learned drive goes with its CSV.
  EXPECT_EQ(error_code("model.delete", {{"name", "mine"}}), "bad_params");
  EXPECT_EQ(error_code("model.delete", {{"name", "../mine.json"}}), "bad_params");
  EXPECT_EQ(error_code("model.delete", {{"name", "absent"}}), "bad_params");
  EXPECT_EQ(error_code("model.delete", json::object()), "bad_params");
  EXPECT_EQ(bench_->handle("model.delete", {{"name", "notes"}})["deleted"],
            json::array({"notes.json"}));
  const fs::path dir(settings().model_dir);
  std::ofstream(dir / "run-1-learned.json") << "{}\n";
  std::ofstream(dir / "run-1-learned.csv") << "t,u,u_compensator\n";
  EXPECT_EQ(bench_->handle("model.delete", {{"name", "run-1-learned.json"}})["deleted"],
            json::array({"run-1-learned.json", "run-1-learned.csv"}));
  EXPECT_FALSE(fs::exists(dir / "run-1-learned.csv"));
  const json left = bench_->handle("model.list", json::object());
  ASSERT_EQ(left["models"].size(), 1u) << left.dump();
  EXPECT_EQ(left["models"][0]["name"], "mine.json");
}

// On the wall clock: the run must still be going when the second request comes.
TEST_F(BenchTest, BadRequestsChangeNothing) {
  start(settings(5000.0, "clock = \"wall\"\n"));
  EXPECT_EQ(error_code("track", {{"compensator", "inverse"}}), "no_model");
  EXPECT_EQ(error_code("track", {{"frequency_hz", "fast"}}), "bad_params");
  EXPECT_EQ(error_code("track", {{"min_um", -100.0}, {"max_um", 10.0}}), "out_of_range");
  EXPECT_EQ(error_code("track", {{"bogus", 1}}), "bad_params");
  EXPECT_EQ(error_code("fly", json::object()), "unknown_command");
  EXPECT_EQ(error_code("stop", json::object()), "no_run");
  EXPECT_EQ(error_code("model.load", {{"path", "/nonexistent.json"}}), "bad_params");
  EXPECT_EQ(bench_->handle("status", json::object())["state"], "idle");
  // A run while one is active is refused.
  bench_->handle("track", {{"compensator", "none"}, {"periods", 20}});
  EXPECT_EQ(error_code("track", {{"compensator", "none"}}), "busy");
  EXPECT_EQ(error_code("identify", json::object()), "busy");
  bench_->handle("stop", json::object());
  ASSERT_TRUE(bench_->wait_idle(std::chrono::seconds(10)));
  std::lock_guard lock(m_);
  EXPECT_EQ(results_.back()["end"], "stopped");
}

// A sink that takes its time with run.finished (a loaded machine, a slow client fan-out): the
// bench is idle for new commands meanwhile, but wait_idle() returns only once the result is in.
TEST_F(BenchTest, WaitIdleReturnsOnlyAfterTheResultReachedTheSink) {
  start(settings());
  std::atomic<bool> in_sink{false};
  json status_in_sink;
  std::vector<json> delivered;
  bench_->set_event_sink([&](const json& e) {
    if (e["event"] != "run.finished") return;
    in_sink = true;
    status_in_sink = bench_->handle("status", json::object());
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    delivered.push_back(e["result"]);
    in_sink = false;
  });
  bench_->handle("track", {{"compensator", "none"}, {"periods", 1}, {"precondition_s", 0.0}});
  ASSERT_TRUE(bench_->wait_idle(std::chrono::seconds(30)));
  EXPECT_FALSE(in_sink.load());
  ASSERT_EQ(delivered.size(), 1u);
  EXPECT_EQ(delivered.back()["end"], "completed");
  EXPECT_EQ(status_in_sink["state"], "idle") << status_in_sink.dump();
}

TEST_F(BenchTest, DriverFaultGoesSafeAndStaysInFaultUntilReset) {
  auto s = settings();
  s.driver_params = {{"faults", {{"nan_at_tick", 3000}}}};
  start(s);
  const json r = run_and_wait("track", {{"compensator", "none"}, {"periods", 10}});
  EXPECT_EQ(r["end"], "fault");
  EXPECT_EQ(r["reason"], "measurement is not a finite number");
  EXPECT_EQ(bench_->handle("status", json::object())["state"], "fault");
  EXPECT_DOUBLE_EQ(bench_->loop().last_output(), bench_->driver().safe_output_v());
  EXPECT_EQ(error_code("track", {{"compensator", "none"}}), "fault");
  // Log intact: every sample up to and including the faulted one.
  const auto table = cli::DataTable::read_csv(r["log"].get<std::string>());
  EXPECT_EQ(table.rows(), r["samples"].get<std::size_t>());

  // reset leaves FAULT as soon as the loop acknowledges (the loop wakes the waiting command).
  const auto before = std::chrono::steady_clock::now();
  EXPECT_EQ(bench_->handle("reset", json::object()),
            json({{"was_fault", true}, {"state", "idle"}}));
  EXPECT_LT(std::chrono::steady_clock::now() - before, std::chrono::milliseconds(500));
  EXPECT_EQ(bench_->handle("reset", json::object()),
            json({{"was_fault", false}, {"state", "idle"}}));
  // The loopback's sensor stays broken: the next run is accepted, and faults again.
  const json next = run_and_wait("track", {{"compensator", "none"}, {"periods", 1}});
  EXPECT_EQ(next["end"], "fault") << next.dump(2);
  EXPECT_GT(next["samples"].get<int>(), 0);
}

// Opt-in (HYSTBENCH_LONG_TESTS=1): a 60 s track at 10 kHz logs exactly 600 000 samples.
TEST_F(BenchTest, SixtySecondsAtTenKilohertzLogEverySample) {
  if (std::getenv("HYSTBENCH_LONG_TESTS") == nullptr) {
    GTEST_SKIP() << "set HYSTBENCH_LONG_TESTS=1 to run the 60 s / 10 kHz logging test";
  }
  auto s = settings(10000.0, "clock = \"wall\"\n");
  s.loop.realtime.fifo = true;  // used when permitted, degraded otherwise
  start(s);
  const json r = run_and_wait(
      "track", {{"compensator", "none"}, {"duration_s", 60.0}, {"precondition_s", 0.0}}, 120);
  ASSERT_EQ(r["end"], "completed") << r.dump(2);
  EXPECT_EQ(r["samples"], 600000);
  EXPECT_EQ(r["logged"], 600000);
  EXPECT_EQ(r["dropped"], 0);
  const auto table = cli::DataTable::read_csv(r["log"].get<std::string>());
  EXPECT_EQ(table.rows(), 600000u);
  std::cout << "60 s at 10 kHz: wake latency p99 " << r["loop"]["wake_latency_ns"]["p99"]
            << " ns, max " << r["loop"]["wake_latency_ns"]["max"] << " ns, overruns "
            << r["overruns"] << "\n";
}

// identify on a bench with a history: identify, track, identify, track. The second
// identification starts after two runs have left the actuator's hysteresis and creep in another
// state than the first found; both models must track alike, and identify reports the tracking
// its verification saw. The same for the coupled-play family and the Preisach plane. On the
// default truth neither play family holds the loop's shape (docs/measurements.md): their
// triangle's max is guarded at 2.3 % of range.
class BenchRepeatTest : public BenchTest, public ::testing::WithParamInterface<const char*> {};

TEST_P(BenchRepeatTest, IdentifyAfterEarlierRunsTracksAsWellAsTheFirst) {
  const std::string model = GetParam();
  start(short_identify_settings());
  auto identify_and_track = [&] {
    const json id = run_and_wait("identify", {{"model", model}});
    EXPECT_EQ(id["end"], "completed") << id.dump(2);
    EXPECT_FALSE(id.contains("fit_error")) << id.dump(2);
    const json tr = run_and_wait("track", {{"compensator", "inverse"}, {"periods", 3}});
    EXPECT_EQ(tr["end"], "completed") << tr.dump(2);
    EXPECT_EQ(id["model"]["type"], model) << id.dump(2);
    std::cout << "[ repeat ] identify " << model << ": held-out rms "
              << id["model"]["heldout"]["rmse_percent"] << " %, verified max "
              << id["verification"].value("max_error_percent", -1.0) << " %, track max "
              << tr["max_error_percent"] << " %\n";
    return json{{"identify", id}, {"track", tr}};
  };
  const json first = identify_and_track();
  const json second = identify_and_track();
  // The plane holds the loop's shape: the target of its triangle, 0.5 % of range at most.
  const double bound = model == "preisach" ? 0.5 : 2.3;
  for (const json* r : {&first, &second}) {
    const json& id = (*r)["identify"];
    EXPECT_GT(id["model"]["history"]["precondition_sweep_s"].get<double>(), 0.0) << id.dump(2);
    ASSERT_EQ(id["verification"]["end"], "completed") << id.dump(2);
    EXPECT_LE(id["verification"]["max_error_percent"].get<double>(), bound) << id.dump(2);
    EXPECT_LE((*r)["track"]["max_error_percent"].get<double>(), bound) << (*r)["track"].dump(2);
  }
  const double a = first["track"]["max_error_percent"].get<double>();
  const double b = second["track"]["max_error_percent"].get<double>();
  // The worst within 1.3x of the best, the Preisach plane's too (on this shortened excitation;
  // identify-repeatability.sh measures the default one).
  EXPECT_LE(std::max(a, b), 1.3 * std::min(a, b)) << "first " << a << " %, second " << b << " %";
  EXPECT_TRUE(
      std::filesystem::exists(second["identify"]["verification"]["log"].get<std::string>()));
}

INSTANTIATE_TEST_SUITE_P(Families, BenchRepeatTest, ::testing::Values("mpi", "cpi", "preisach"),
                         [](const ::testing::TestParamInfo<const char*>& i) {
                           return std::string(i.param);
                         });

// The user's path with the Preisach plane: `identify --model preisach`, then the 1 Hz triangle
// through its inverse. The plane holds the default truth's loop that the play families miss: the
// verification and the track within 0.8 % of range at their largest on this shortened
// excitation, where the modified PI leaves more than twice that (BenchRepeatTest).
TEST_F(BenchTest, IdentifyWithThePreisachFamilyTracksTheTriangleThroughItsInverse) {
  start(short_identify_settings());
  const json id = run_and_wait("identify", {{"model", "preisach"}});
  ASSERT_EQ(id["end"], "completed") << id.dump(2);
  EXPECT_FALSE(id.contains("fit_error")) << id.dump(2);
  EXPECT_EQ(id["model"]["type"], "preisach") << id.dump(2);
  ASSERT_EQ(id["verification"]["end"], "completed") << id.dump(2);
  EXPECT_LE(id["verification"]["max_error_percent"].get<double>(), 0.8) << id.dump(2);
  const json tr = run_and_wait("track", {{"compensator", "inverse"}, {"periods", 3}});
  ASSERT_EQ(tr["end"], "completed") << tr.dump(2);
  EXPECT_LE(tr["max_error_percent"].get<double>(), 0.8) << tr.dump(2);
  // `model get`: the active model is the plane, its cells in the file.
  const json active = bench_->handle("model.get", json::object())["model"];
  EXPECT_NE(active.dump().find("\"preisach\""), std::string::npos) << active.dump().substr(0, 2000);
}

// The user's path with the defaults: `identify` alone. Its extension diagnoses the record with
// the play family it kept, finds the loop's shape it misses, swaps the operator for a Preisach
// plane, and keeps it where the bench tracks better; the inverse then tracks the 1 Hz triangle
// better than the modified PI it replaced. A family the request names is kept as it is
// (BenchRepeatTest: `identify --model mpi` and `cpi` keep theirs).
TEST_F(BenchTest, IdentifyKeepsThePlaneItsDiagnosisFindsForTheLoopsShape) {
  start(short_identify_settings());
  const json id = run_and_wait("identify", json::object());
  ASSERT_EQ(id["end"], "completed") << id.dump(2);
  const json& extension = id["model"]["extension"];
  bool shape = false;
  for (const json& p : extension["parts"]) shape = shape || p["cause"] == "loop_shape";
  ASSERT_TRUE(shape) << extension.dump(2);
  EXPECT_EQ(extension["adopted"], true) << extension.dump(2);
  // Checked before it was played: its inverse tracks the plane over its input range.
  EXPECT_EQ(extension["check"]["passed"], true) << extension.dump(2);
  EXPECT_LT(extension["check"]["inverse_rms_percent"].get<double>(), 0.5) << extension.dump(2);
  EXPECT_EQ(id["model"]["type"], "preisach") << id.dump(2);
  const double replaced = extension["verified"]["triangle_max_percent"]["model"].get<double>();
  const json tr = run_and_wait("track", {{"compensator", "inverse"}, {"periods", 3}});
  ASSERT_EQ(tr["end"], "completed") << tr.dump(2);
  EXPECT_LT(tr["max_error_percent"].get<double>(), 0.8 * replaced) << tr.dump(2);
}

// A run's model starts where the actuator's history left it: the active model stepped through
// every output the loop wrote since (identify's excitation and verification runs, the idle
// between), not relaxed at the present output. The default truth's logarithmic creep keeps
// moving for minutes after identify: a model relaxed at the start of a 20-period triangle does
// not know that drift and misses the triangle's rms target over the 20 periods; one stepped
// through the history holds it. A model loaded anew is replayed over the same history.
TEST_F(BenchTest, TheInverseStartsWhereTheBenchsHistoryLeftTheActuator) {
  start(settings_from_toml(loopback_toml()));
  const json id = run_and_wait("identify", json::object(), 300);
  ASSERT_EQ(id["end"], "completed") << id.dump(2);
  const json track = {{"reference", "triangle"},
                      {"frequency_hz", 1.0},
                      {"periods", 20},
                      {"compensator", "inverse"}};
  const json tr = run_and_wait("track", track);
  ASSERT_EQ(tr["end"], "completed") << tr.dump(2);
  EXPECT_EQ(tr["model_start"], "history") << tr.dump(2);
  // identify's runs: its excitation alone is 36 s.
  EXPECT_GT(tr["model_history_s"].get<double>(), 36.0) << tr.dump(2);
  EXPECT_LE(tr["rms_error_percent"].get<double>(), 0.15) << tr.dump(2);
  EXPECT_LE(tr["max_error_percent"].get<double>(), 0.5) << tr.dump(2);

  const json model = bench_->handle("model.get", json::object())["model"];
  bench_->handle("model.load", {{"model", model}, {"name", "again.json"}});
  const json again = run_and_wait("track", track);
  ASSERT_EQ(again["end"], "completed") << again.dump(2);
  EXPECT_EQ(again["model_start"], "history") << again.dump(2);
  EXPECT_GT(again["model_history_s"].get<double>(), tr["model_history_s"].get<double>());
  EXPECT_LE(again["rms_error_percent"].get<double>(), 0.15) << again.dump(2);
}

// The tare: an output offset the model does not predict (a sensor offset, the slow
// creep a bench's history leaves) is measured as y - y_model on the precondition sweep's falling
// ramp and taken off the feedforward's target. A model shifted by 2 µm (4.4 % of the range)
// tracks as well as the model it was shifted from, and the result names the tare it applied.
TEST_F(BenchTest, AnOffsetTheModelDoesNotPredictIsTaredOffTheFeedforward) {
  start(short_identify_settings());
  const json id = run_and_wait("identify", {{"model", "mpi"}});
  ASSERT_EQ(id["end"], "completed") << id.dump(2);
  const json track = {{"compensator", "inverse"}, {"periods", 3}};
  const json base = run_and_wait("track", track);
  ASSERT_EQ(base["end"], "completed") << base.dump(2);
  ASSERT_TRUE(base.contains("tare_um")) << base.dump(2);

  json shifted = bench_->handle("model.get", json::object())["model"];
  // y = center + dz(pi(u) - center): both moved by 2 µm move the output by 2 µm.
  shifted["play"]["offset"] = shifted["play"]["offset"].get<double>() + 2.0;
  shifted["deadzone"]["center"] = shifted["deadzone"]["center"].get<double>() + 2.0;
  bench_->handle("model.load", {{"model", shifted}, {"name", "shifted.json"}});
  const json r = run_and_wait("track", track);
  ASSERT_EQ(r["end"], "completed") << r.dump(2);
  std::cout << "[ tare ] base: tare " << base["tare_um"] << " um, rms " << base["rms_error_percent"]
            << " %, max " << base["max_error_percent"] << " %; shifted by 2 um: tare "
            << r["tare_um"] << " um, rms " << r["rms_error_percent"] << " %, max "
            << r["max_error_percent"] << " %\n";
  EXPECT_NEAR(r["tare_um"].get<double>(), base["tare_um"].get<double>() - 2.0, 0.2) << r.dump(2);
  // The offset is off the error: what is left is a fraction of what the 2 um would leave. Not
  // the base's error exactly: the reference follows the model's range, so the shifted run tracks
  // 2 um higher, nearer the default truth's saturating top where its loop bends most (the test
  // prints both).
  const double offset_percent = 100.0 * 2.0 / r["range_um"].get<double>();
  EXPECT_LE(r["rms_error_percent"].get<double>(),
            base["rms_error_percent"].get<double>() + 0.25 * offset_percent)
      << r.dump(2);
  // The simulation's own error is reported as it is: the shift shows in y - y_model.
  EXPECT_GT(r["model_rms_error_um"].get<double>(), 1.5) << r.dump(2);
}

// identify's verification is a run like any other: status names the stage, progress events
// carry it, stop ends it; the fitted model is still adopted and the result says what happened.
// On the wall clock, so the verification still runs when stop comes; the cut identification
// (cut_identify: the model's figures are not under test here).
TEST_F(BenchTest, StopDuringIdentifyVerificationAdoptsTheModelAndSaysSo) {
  hd::BenchSettings s = settings(5000.0, "clock = \"wall\"\n");
  cut_identify(s);
  start(s);
  std::vector<json> progress;
  bench_->set_event_sink([&](const json& e) {
    std::lock_guard lock(m_);
    if (e["event"] == "run.finished") results_.push_back(e["result"]);
    if (e["event"] == "run.progress") progress.push_back(e);
  });
  const std::string run_id = bench_->handle("identify", {{"model", "mpi"}})["run_id"];
  json st;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(90);
  while (std::chrono::steady_clock::now() < until) {
    st = status();
    if (st["run"].is_object() && st["run"].value("stage", "") == "verify mpi") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_EQ(st["run"].value("stage", ""), "verify mpi") << st.dump(2);
  EXPECT_EQ(st["run"]["run_id"], run_id);
  EXPECT_EQ(error_code("track", {{"compensator", "none"}}), "busy");
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // a progress event or more
  bench_->handle("stop", json::object());
  ASSERT_TRUE(bench_->wait_idle(std::chrono::seconds(30)));
  std::lock_guard lock(m_);
  ASSERT_EQ(results_.size(), 1u);
  const json& r = results_.back();
  EXPECT_EQ(r["run_id"], run_id);
  EXPECT_EQ(r["end"], "completed");  // the excitation and the fit completed
  EXPECT_EQ(r["verification"]["end"], "stopped") << r.dump(2);
  EXPECT_TRUE(r.contains("model")) << r.dump(2);
  EXPECT_EQ(status()["model"]["path"], r["model"]["path"]);
  bool saw_stage = false;
  for (const json& e : progress) saw_stage = saw_stage || e.value("stage", "") == "verify mpi";
  EXPECT_TRUE(saw_stage);
}

// A rate-dependent model's feedforward is planned before the run starts, off the command
// thread: the track reply comes at once and says so, status answers "preparing" with the stage,
// progress events count the plan. Stop and abort cancel the plan and end the run unplayed (0
// samples, the log closed with its header, the output untouched), and the next run plans and
// plays as usual.
TEST_F(BenchTest, ARateDependentTrackIsPlannedBeforeItStartsAndStopCancelsThePlan) {
  start_rate_dependent_with_its_truth();
  std::vector<json> planning;
  bench_->set_event_sink([&](const json& e) {
    std::lock_guard lock(m_);
    if (e["event"] == "run.finished") results_.push_back(e["result"]);
    if (e["event"] == "run.progress" && e.value("stage", "") == "planning the feedforward") {
      planning.push_back(e);
    }
  });
  const double output_before = status()["output_v"];
  // 40 000 samples to plan: seconds of work.
  const json long_track = {{"reference", "sine"}, {"frequency_hz", 10.0}, {"periods", 40}};
  for (const char* cancel : {"stop", "abort"}) {
    const json reply = bench_->handle("track", long_track);
    EXPECT_EQ(reply["feedforward"]["planned"]["planning"], true) << reply.dump(2);
    const json st = status();
    EXPECT_EQ(st["state"], "preparing") << st.dump(2);
    EXPECT_EQ(st["run"]["stage"], "planning the feedforward") << st.dump(2);
    EXPECT_EQ(st["run"]["run_id"], reply["run_id"]);
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    for (;;) {
      {
        std::lock_guard lock(m_);
        if (!planning.empty() && planning.back()["run_id"] == reply["run_id"]) break;
      }
      ASSERT_LT(std::chrono::steady_clock::now(), until) << "no planning progress";
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    EXPECT_EQ(error_code("track", long_track), "busy");
    bench_->handle(cancel, json::object());
    ASSERT_TRUE(bench_->wait_idle(std::chrono::seconds(30)));
    const json r = last_result();
    EXPECT_EQ(r["run_id"], reply["run_id"]);
    EXPECT_EQ(r["end"], std::string(cancel) == "stop" ? "stopped" : "aborted") << r.dump(2);
    EXPECT_EQ(r["samples"], 0);
    EXPECT_NE(r["reason"].get<std::string>().find("while planning the feedforward"),
              std::string::npos)
        << r.dump(2);
    EXPECT_EQ(r["feedforward"]["planned"]["samples"], 0) << r.dump(2);
    EXPECT_TRUE(fs::exists(r["log"].get<std::string>()));
    EXPECT_EQ(status()["state"], "idle");
    EXPECT_EQ(status()["output_v"], output_before);
  }
  EXPECT_EQ(error_code("stop", json::object()), "no_run");
  // The next run is planned and played.
  const json r =
      run_and_wait("track", {{"reference", "sine"}, {"frequency_hz", 10.0}, {"periods", 3}});
  EXPECT_EQ(r["end"], "completed") << r.dump(2);
  EXPECT_GT(r["feedforward"]["planned"]["samples"].get<double>(), 0.0) << r.dump(2);
  EXPECT_EQ(r["feedforward"]["planned"]["reused"], false) << r.dump(2);
  EXPECT_LT(r["rms_error_percent"].get<double>(), 3.0) << r.dump(2);
  {
    std::lock_guard lock(m_);
    EXPECT_DOUBLE_EQ(planning.back()["fraction"].get<double>(), 1.0);
  }
  // The same reference through another compensator (as a sweep runs them) plays the same plan,
  // kept from the run before; another reference is planned anew. (A feedback needs the stage's
  // measured responses, which a model loaded without them has not: frf measures them.)
  EXPECT_EQ(error_code("track", {{"compensator", "inverse+pid"}}), "no_frequency_response");
  const json again = run_and_wait("track", {{"reference", "sine"},
                                            {"frequency_hz", 10.0},
                                            {"periods", 3},
                                            {"compensator", "inverse_multiplicative"}});
  ASSERT_EQ(again["end"], "completed") << again.dump(2);
  EXPECT_EQ(again["feedforward"]["planned"]["reused"], true) << again.dump(2);
  EXPECT_EQ(again["feedforward"]["planned"]["model_rms_um"],
            r["feedforward"]["planned"]["model_rms_um"]);
  const json other =
      run_and_wait("track", {{"reference", "sine"}, {"frequency_hz", 11.0}, {"periods", 3}});
  ASSERT_EQ(other["end"], "completed") << other.dump(2);
  EXPECT_EQ(other["feedforward"]["planned"]["reused"], false) << other.dump(2);
}

// A run still being prepared when the daemon shuts down ends aborted, with its result delivered.
TEST_F(BenchTest, ShutdownWhilePlanningEndsTheRunUnplayed) {
  start_rate_dependent_with_its_truth();
  const json reply =
      bench_->handle("track", {{"reference", "sine"}, {"frequency_hz", 10.0}, {"periods", 40}});
  bench_->shutdown();
  const json r = last_result();
  EXPECT_EQ(r["run_id"], reply["run_id"]);
  EXPECT_EQ(r["end"], "aborted") << r.dump(2);
  EXPECT_EQ(r["samples"], 0);
}
