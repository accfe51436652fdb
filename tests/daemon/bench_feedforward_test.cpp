// The dynamic feedforward on the bench, as a user closes the loop: `identify`, `hystbench
// diagnose` of the identify log with the active model and --save-extended, `model load` of the
// extended model, then `track`. The extended model holds what the diagnosis found, and the
// feedforward previews the reference to invert it.
// - On the modified-PI truth with its 0.2 ms input delay (every other effect of that truth at its
//   default: creep lags, the 3 kHz resonance, noise, converters) the delay and the resonance are
//   recovered together: a 500 Hz sine within 2 % of range rms, far below identify's model.
// - On the default truth with its modes replaced by one at 800 Hz (the Preisach loop, its creep,
//   the 5 kHz sensor) the diagnosis finds the mode on top of the loop's shape, but the identify
//   record excites it little: it lowers the held-out error about 1.15x, below the 1.2x that names
//   a cause, and is reported, not named (docs/measurements.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>

#include "hystbench/daemon/config.hpp"
#include "hystbench/daemon/daemon_settings.hpp"
#include "hystbench/daemon/diagnose_command.hpp"
#include "hystbench/daemon/offline_commands.hpp"
#include "support/bench_fixture.hpp"

namespace hd = hystbench::daemon;
using nlohmann::json;

namespace {

class BenchFeedforwardTest : public hystbench::test::BenchFixture {
 protected:
  BenchFeedforwardTest() : BenchFixture("hystbench_feedforward_test") {}
  /// What the extended model must reach: rms % of range at 200 and 500 Hz, and at 500 Hz at
  /// most this share of identify's model's error.
  struct Expected {
    double max_200 = 0.0, max_500 = 0.0, share_500 = 0.0;
  };
  /// identify, then a 500 Hz sine with identify's model, then `diagnose` of the identify log
  /// with that model (--json, --save-extended to path("extended.json")); the diagnosis's JSON.
  json identify_and_diagnose(const char* toml);
  /// Loads the extended model and tracks 200 and 500 Hz sines: its inversion reaches `expected`.
  void extended_model_tracks(const Expected& expected);
  /// A 20-period sine over the default amplitude, tracked with the inverse.
  json sine(double f) {
    return run_and_wait(
        "track",
        {{"reference", "sine"}, {"frequency_hz", f}, {"periods", 20}, {"compensator", "inverse"}});
  }
  json plain_;  ///< the 500 Hz sine tracked with identify's model
};

constexpr const char* kDelayed =
    "[actuator.hysteresis]\nkind = \"modified_pi\"\n[actuator.delay]\nenabled = true\n";
// No delay; the structural modes replaced by one at 800 Hz.
constexpr const char* kResonance800 =
    "[actuator.dynamics]\nnatural_frequencies_hz = [800.0]\ndamping_ratios = [0.06]\n"
    "mode_gains = [1.0]\nenabled = true\n";

}  // namespace

json BenchFeedforwardTest::identify_and_diagnose(const char* toml) {
  start(settings_from_toml(loopback_toml(toml)));
  const json id = run_and_wait("identify", json::object());
  EXPECT_EQ(id["end"], "completed") << id.dump(2);
  EXPECT_FALSE(id.contains("fit_error")) << id.dump(2);
  plain_ = sine(500.0);
  EXPECT_EQ(plain_["end"], "completed") << plain_.dump(2);

  hd::DiagnoseCommand diag;
  diag.data_paths = {id["log"].get<std::string>()};
  diag.model_path = id["model"]["path"].get<std::string>();
  diag.save_extended = path("extended.json");
  diag.json_output = true;
  std::ostringstream out, err;
  EXPECT_EQ(hd::run_diagnose(diag, out, err), 0) << err.str();
  const json d = json::parse(out.str());
  std::cout << "diagnose: " << d["extended"]["description"] << "\n";
  return d;
}

void BenchFeedforwardTest::extended_model_tracks(const Expected& expected) {
  bench_->handle("model.load",
                 {{"model", hd::read_model_document(path("extended.json"))}, {"name", "extended"}});
  for (const double f : {200.0, 500.0}) {
    const json r = sine(f);
    ASSERT_EQ(r["end"], "completed") << r.dump(2);
    const json& ff = r["feedforward"];
    const json inverted = ff["inverted"];
    EXPECT_NE(std::find(inverted.begin(), inverted.end(), "dynamics"), inverted.end()) << ff;
    const double rms = r["rms_error_percent"].get<double>();
    std::cout << f << " Hz: " << rms << " % of range rms with the extended model\n";
    EXPECT_LE(rms, f == 200.0 ? expected.max_200 : expected.max_500) << f << " Hz: " << r.dump(2);
    if (f == 500.0) {
      std::cout << "  identify's model: " << plain_["rms_error_percent"] << " %\n";
      EXPECT_LT(rms, expected.share_500 * plain_["rms_error_percent"].get<double>());
    }
  }
}

static bool names(const json& diagnosis, const std::string& part) {
  const json& parts = diagnosis["extended"]["parts"];
  return std::find(parts.begin(), parts.end(), part) != parts.end();
}

TEST_F(BenchFeedforwardTest, DiagnosedDelayAndResonanceAreInvertedFromThePreviewedReference) {
  const json d = identify_and_diagnose(kDelayed);
  ASSERT_TRUE(names(d, "delay")) << d["extended"].dump();
  extended_model_tracks({1.0, 2.0, 0.25});
}

TEST_F(BenchFeedforwardTest, AnEightHundredHertzResonanceIsFoundOnTheDefaultTruth) {
  const json d = identify_and_diagnose(kResonance800);
  const auto dynamics = std::find_if(d["candidates"].begin(), d["candidates"].end(),
                                     [](const json& c) { return c["cause"] == "dynamics"; });
  ASSERT_NE(dynamics, d["candidates"].end()) << d.dump(1);
  // Found: significant, at the mode's frequency, and lowering the held-out error.
  EXPECT_TRUE((*dynamics)["significant"].get<bool>()) << dynamics->dump();
  const std::string extension = (*dynamics)["extension"];
  const std::string::size_type at = extension.find("natural frequency ");
  ASSERT_NE(at, std::string::npos) << extension;
  const double hz = std::stod(extension.substr(at + std::string("natural frequency ").size()));
  EXPECT_NEAR(hz, 800.0, 80.0) << extension;
  EXPECT_GT((*dynamics)["gain"].get<double>(), 1.05) << dynamics->dump();
  // identify's model matches the record it was fitted on: the record's settling and
  // preconditioning, before the input has reached both its extremes, is not scored.
  for (const json& note : d["notes"]) {
    EXPECT_EQ(note.get<std::string>().find("do not match this record"), std::string::npos) << note;
  }
}
