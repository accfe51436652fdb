// The dynamic feedforward on the bench, as a user closes the loop: `identify`, `hystbench
// diagnose` of the identify log with the active model and --save-extended, `model load` of the
// extended model, then `track`. The extended model holds what the diagnosis found, and the
// feedforward previews the reference to invert it.
// - On the modified-PI truth with its 0.2 ms input delay (every other effect of that truth at its
//   default: creep lags, the 3 kHz resonance, noise, converters) the delay and the resonance are
//   recovered together: a 500 Hz sine within 2 % of range rms, far below identify's model.
// - On the default truth with its modes replaced by one at 800 Hz (the Preisach loop, its creep,
//   the 5 kHz sensor): the diagnosis finds the mode on top of the loop's shape and the extended
//   model tracks 500 Hz about twice as well as identify's (measured 17 % against 31 %); the
//   targets (1 % at 200 Hz, 2 % at 500 Hz) are missed: the models hold whole-tick delays (the
//   sensor lags by half a tick), one mode, and not the loop's shape (docs/measurements.md).
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
    std::string part;
    double max_200 = 0.0, max_500 = 0.0, share_500 = 0.0;
  };
  void closes_the_loop(const char* toml, const Expected& expected);
};

constexpr const char* kDelayed =
    "[actuator.hysteresis]\nkind = \"modified_pi\"\n[actuator.delay]\nenabled = true\n";
// No delay; the structural modes replaced by one at 800 Hz.
constexpr const char* kResonance800 =
    "[actuator.dynamics]\nnatural_frequencies_hz = [800.0]\ndamping_ratios = [0.06]\n"
    "mode_gains = [1.0]\nenabled = true\n";

}  // namespace

// identify, track a 500 Hz sine with identify's model, diagnose the identify log with
// --save-extended, load the extended model, track 200 and 500 Hz: the extended model holds
// `expected.part` and its inversion reaches `expected`.
void BenchFeedforwardTest::closes_the_loop(const char* toml, const Expected& expected) {
  start(settings_from_toml(loopback_toml(toml)));
  const json id = run_and_wait("identify", json::object());
  ASSERT_EQ(id["end"], "completed") << id.dump(2);
  ASSERT_FALSE(id.contains("fit_error")) << id.dump(2);
  auto sine = [&](double f) {
    return run_and_wait(
        "track",
        {{"reference", "sine"}, {"frequency_hz", f}, {"periods", 20}, {"compensator", "inverse"}});
  };
  const json plain = sine(500.0);
  ASSERT_EQ(plain["end"], "completed") << plain.dump(2);

  hd::DiagnoseCommand diag;
  diag.data_paths = {id["log"].get<std::string>()};
  diag.model_path = id["model"]["path"].get<std::string>();
  diag.save_extended = path("extended.json");
  diag.json_output = true;
  std::ostringstream out, err;
  ASSERT_EQ(hd::run_diagnose(diag, out, err), 0) << err.str();
  const json d = json::parse(out.str());
  const json parts = d["extended"]["parts"];
  std::cout << "diagnose: " << d["extended"]["description"] << "\n";
  EXPECT_NE(std::find(parts.begin(), parts.end(), expected.part), parts.end()) << parts.dump();
  bench_->handle("model.load",
                 {{"model", hd::read_model_document(diag.save_extended)}, {"name", "extended"}});

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
      std::cout << "  identify's model: " << plain["rms_error_percent"] << " %\n";
      EXPECT_LT(rms, expected.share_500 * plain["rms_error_percent"].get<double>());
    }
  }
}

TEST_F(BenchFeedforwardTest, DiagnosedDelayAndResonanceAreInvertedFromThePreviewedReference) {
  closes_the_loop(kDelayed, {"delay", 1.0, 2.0, 0.25});
}

TEST_F(BenchFeedforwardTest, ADiagnosedEightHundredHertzResonanceIsInvertedOnTheDefaultTruth) {
  closes_the_loop(kResonance800, {"dynamics", 9.0, 20.0, 0.7});
}
