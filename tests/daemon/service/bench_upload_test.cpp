// A user's trajectory and a user's drive, uploaded in chunks and played by the bench in-process
// (loopback driver): limits checked before anything moves, a broken upload leaves nothing, a
// trajectory works as a built-in reference does, an excitation's log is a record `fit` reads.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/cli/offline/offline_commands.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "hystbench/sim/signal_generator.hpp"
#include "support/bench_fixture.hpp"

namespace hd = hystbench::daemon;
namespace cli = hystbench::cli;
namespace common = hystbench::common;
namespace hs = hystbench::sim;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

class BenchUploadTest : public hystbench::test::BenchFixture {
 protected:
  BenchUploadTest() : BenchFixture("hystbench_bench_upload_test") {}
  // The loopback at 5 kHz with the 0..45 um range from a config file, on the simulated clock;
  // precondition 0.4 s.
  hd::BenchSettings settings() const {
    hd::BenchSettings s = settings_from_toml(loopback_toml({}, kSimulatedClock, 5000.0, 45.0));
    s.precondition_s = 0.4;
    return s;
  }
  /// Uploads (t, values) in chunks of 1000 as `client` (0: the connection run_and_wait uses);
  /// returns the upload's name.
  std::string upload(const std::string& kind, const std::vector<double>& t,
                     const std::vector<double>& v, std::uint64_t client = 0,
                     std::size_t stop_after = SIZE_MAX) {
    const json begun =
        bench_->handle("upload.begin", {{"kind", kind}, {"samples", v.size()}}, client);
    const std::string name = begun["upload"];
    for (std::size_t k = 0; k < v.size() && k < stop_after; k += 1000) {
      const std::size_t m = std::min<std::size_t>(1000, v.size() - k);
      bench_->handle("upload.chunk",
                     {{"upload", name},
                      {"offset", k},
                      {"t", std::vector<double>(t.begin() + k, t.begin() + k + m)},
                      {"values", std::vector<double>(v.begin() + k, v.begin() + k + m)}},
                     client);
    }
    return name;
  }
  /// The refusal of a command as {code, detail}, or {"ok", {}}.
  std::pair<std::string, json> refused(const std::string& cmd, const json& params,
                                       std::uint64_t client = 0) {
    try {
      bench_->handle(cmd, params, client);
    } catch (const common::CommandError& e) {
      return {e.code(), e.detail()};
    }
    return {"ok", json::object()};
  }
  std::size_t log_files() const {
    std::size_t n = 0;
    if (fs::exists(dir_ / "logs")) {
      for (const auto& e : fs::directory_iterator(dir_ / "logs"))
        n += e.path().extension() == ".csv";
    }
    return n;
  }
  /// The offline `fit` of a record, with its defaults; the result JSON.
  static json fit(const std::string& path, const fs::path& model_out) {
    cli::FitCommand cmd;
    cmd.data_path = path;
    cmd.output_path = model_out.string();
    cmd.json_output = true;
    std::ostringstream out, err;
    EXPECT_EQ(cli::run_fit(cmd, out, err), 0) << err.str();
    return json::parse(out.str());
  }
};

}  // namespace

// A trajectory that leaves the actuator range, or moves faster than the slew limit, is refused
// with its first offending sample named, and nothing moves: no run, no log, the output where it
// was, the bench idle. The upload stays for a corrected retry on the same connection.
TEST_F(BenchUploadTest, ATrajectoryWithALimitViolationIsRefusedAndNothingMoves) {
  hd::BenchSettings s = settings();
  s.loop.limits.slew_v_per_s = 1e4;  // 3000 um/s through the 45 um / 150 V range
  start(s);
  std::vector<double> t, yr;
  for (int k = 0; k < 2000; ++k) {
    t.push_back(k * 1e-3);
    yr.push_back(10.0 + 0.02 * k);  // 20 um/s, leaves the 45 um range at row 1751
  }
  const double u_before = bench_->loop().last_output();
  const std::size_t logs_before = log_files();
  const std::string name = upload("reference", t, yr);
  auto [code, detail] = refused("track", {{"reference_upload", name}});
  EXPECT_EQ(code, "out_of_range");
  EXPECT_EQ(detail["sample"], 1751) << detail.dump();
  EXPECT_EQ(status()["state"], "idle");
  EXPECT_EQ(log_files(), logs_before);
  EXPECT_EQ(bench_->loop().last_output(), u_before);

  // Within range but with a 10 um step in one row at t = 0.5 s.
  for (int k = 500; k < 2000; ++k) yr[k] = 20.0 + (k == 500 ? 10.0 : 0.0) + 0.001 * k;
  for (int k = 0; k < 500; ++k) yr[k] = 20.0 + 0.001 * k;
  const std::string steep = upload("reference", t, yr);
  std::tie(code, detail) = refused("track", {{"reference_upload", steep}});
  EXPECT_EQ(code, "slew_limit");
  EXPECT_EQ(detail["sample"], 500) << detail.dump();
  EXPECT_EQ(status()["state"], "idle");
  EXPECT_EQ(log_files(), logs_before);
  EXPECT_EQ(status()["uploads"]["open"], 2);  // kept for a retry

  // A drive beyond [u_min, u_max] likewise.
  std::vector<double> u(t.size(), 50.0);
  u[1234] = 151.0;
  std::tie(code, detail) = refused("excite", {{"drive_upload", upload("drive", t, u)}});
  EXPECT_EQ(code, "out_of_range");
  EXPECT_EQ(detail["sample"], 1234);
  EXPECT_EQ(log_files(), logs_before);
  EXPECT_EQ(bench_->loop().last_output(), u_before);
}

// A client that goes away mid-upload leaves the bench idle and unchanged: its upload is gone
// and nothing ran; another connection cannot use an upload that is not its own.
TEST_F(BenchUploadTest, ADisconnectMidUploadLeavesTheBenchIdleAndUnchanged) {
  start(settings());
  std::vector<double> t, yr;
  for (int k = 0; k < 5000; ++k) {
    t.push_back(k * 1e-3);
    yr.push_back(20.0 + 5.0 * std::sin(k * 1e-2));
  }
  const std::string name = upload("reference", t, yr, 7, 3000);
  EXPECT_EQ(status()["uploads"]["staged_samples"], 3000);
  EXPECT_EQ(refused("track", {{"reference_upload", name}}, 7).first, "upload_incomplete");
  EXPECT_EQ(refused("track", {{"reference_upload", name}}, 8).first, "upload_unknown");
  bench_->client_closed(7);
  EXPECT_EQ(status()["uploads"]["open"], 0);
  EXPECT_EQ(status()["uploads"]["staged_samples"], 0);
  EXPECT_EQ(refused("track", {{"reference_upload", name}}, 7).first, "upload_unknown");
  EXPECT_EQ(status()["state"], "idle");
  EXPECT_EQ(log_files(), 0u);
  // The bench still runs what comes next.
  const json r = run_and_wait("track", {{"compensator", "none"}, {"periods", 2}});
  EXPECT_EQ(r["end"], "completed");
}

// 1 M samples (500 kHz over 2 s), uploaded in 1000 chunks, resampled to the 5 kHz loop and
// tracked; the result reports the error over the trajectory, the upload is consumed.
TEST_F(BenchUploadTest, AMillionSampleTrajectoryIsTrackedWithItsErrorReported) {
  start(settings());
  const std::size_t n = 1'000'000;
  std::vector<double> t(n), yr(n);
  for (std::size_t k = 0; k < n; ++k) {
    t[k] = static_cast<double>(k) * 2e-6;
    yr[k] = 22.5 + 15.0 * std::sin(2.0 * M_PI * 2.0 * t[k]);  // 2 Hz, 30 um
  }
  const std::string name = upload("reference", t, yr);
  EXPECT_EQ(status()["uploads"]["staged_samples"], n);
  const json r = run_and_wait("track", {{"reference_upload", name}, {"compensator", "none"}});
  ASSERT_EQ(r["end"], "completed") << r.dump();
  const auto header = hd::read_sample_log_header(r["log"].get<std::string>());
  EXPECT_EQ(header["run"]["reference"], "upload");
  EXPECT_EQ(header["run"]["upload_samples"], n);
  EXPECT_EQ(header["run"]["resampled_samples"], 10'000);  // 2 s at 5 kHz, both ends
  EXPECT_NEAR(r["range_um"].get<double>(), 30.0, 0.01);
  // Without compensation the error is the actuator's hysteresis: several % of the range.
  EXPECT_GT(r["rms_error_percent"].get<double>(), 1.0);
  EXPECT_LT(r["rms_error_percent"].get<double>(), 30.0);
  EXPECT_EQ(status()["uploads"]["open"], 0);
  // The scored part is the trajectory: the approach before it is not.
  EXPECT_EQ(r["samples"].get<std::uint64_t>() - header["run"]["metrics_from"].get<std::uint64_t>(),
            10'000u);
}

// The same triangle tracked as a built-in reference and as an uploaded trajectory through the
// identified model's inverse: the same error (the inverse, the preview and the result are the
// built-in reference's); and an excitation's log, read back by `fit` with its defaults, gives
// a model as good as the identification run's own record does.
TEST_F(BenchUploadTest, AnUploadedTrajectoryAndExcitationWorkAsTheBuiltInOnes) {
  hd::BenchSettings s = settings();
  shorten_identify(s);
  start(s);
  const json id = run_and_wait("identify", json::object(), 180);
  ASSERT_EQ(id["end"], "completed") << id.dump();

  const json builtin = run_and_wait("track", {{"reference", "triangle"},
                                              {"frequency_hz", 1.0},
                                              {"periods", 3},
                                              {"min_um", 8.0},
                                              {"max_um", 36.0}});
  ASSERT_EQ(builtin["end"], "completed");
  hs::SignalSpec spec;
  spec.kind = hs::SignalKind::kTriangle;
  spec.amplitude = 14.0;
  spec.offset = 22.0;
  spec.phase_rad = -M_PI / 2.0;
  const auto tri = hs::make_signal_generator(spec);
  std::vector<double> t, yr;
  for (int k = 0; k <= 2000; ++k) {  // two periods at 1 kHz
    t.push_back(k * 1e-3);
    yr.push_back(tri->value(t.back()));
  }
  const json uploaded = run_and_wait("track", {{"reference_upload", upload("reference", t, yr)}});
  ASSERT_EQ(uploaded["end"], "completed") << uploaded.dump();
  EXPECT_EQ(uploaded["compensator"], "inverse");
  EXPECT_EQ(uploaded["feedforward"], builtin["feedforward"]);
  const double b = builtin["rms_error_percent"], u = uploaded["rms_error_percent"];
  std::cout << "triangle 1 Hz through the inverse: built-in " << b << " %, uploaded " << u
            << " % rms\n";
  EXPECT_LT(u, 1.5 * b + 0.05);
  EXPECT_LT(uploaded["max_error_percent"].get<double>(),
            1.5 * builtin["max_error_percent"].get<double>() + 0.1);

  // The identification's applied drive, played again as a user's excitation.
  const auto id_log = cli::DataTable::read_csv(id["log"].get<std::string>());
  const json excited = run_and_wait(
      "excite", {{"drive_upload", upload("drive", id_log.column("t"), id_log.column("u"))}}, 180);
  ASSERT_EQ(excited["end"], "completed") << excited.dump();
  EXPECT_EQ(excited["kind"], "excite");
  const json from_identify = fit(id["log"], dir_ / "id.json");
  const json from_excite = fit(excited["log"], dir_ / "ex.json");
  const double hi = from_identify["heldout"]["rmse"], he = from_excite["heldout"]["rmse"];
  std::cout << "fit held-out rms: identification record " << hi << " um, excitation record " << he
            << " um; identify's own " << id["model"]["heldout"]["rmse"] << " um\n";
  EXPECT_LT(he, 1.1 * hi);
}
