#pragma once
// Test fixture for the whole bench in-process (hystbenchd's Bench without the socket): a
// temporary folder per test for logs and models, settings a shared CI machine can keep (no
// SCHED_FIFO, no mlockall, an overrun budget that never faults: timing is not under test), the
// run.finished results collected, and run_and_wait().
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "hystbench/daemon/config/config.hpp"
#include "hystbench/daemon/config/daemon_settings.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "support/temp_dir_test.hpp"

namespace hystbench::test {

class BenchFixture : public TempDirTest {
 protected:
  /// `prefix` names the temporary folder (prefix_pid_testname).
  explicit BenchFixture(std::string prefix) : TempDirTest(std::move(prefix)) {}

  void TearDown() override {
    bench_.reset();
    TempDirTest::TearDown();
  }

  /// Loop at `rate_hz` [Hz], logs and models in the test's folder, precondition 0.4 s.
  daemon::BenchSettings base_settings(double rate_hz) const {
    daemon::BenchSettings s;
    s.loop.rate_hz = rate_hz;
    s.loop.realtime.fifo = false;
    s.loop.realtime.lock_memory = false;
    s.loop.overrun_budget = 1000000;
    s.log_dir = (dir_ / "logs").string();
    s.model_dir = (dir_ / "models").string();
    s.precondition_s = 0.4;
    return s;
  }

  /// The [loop] keys of a bench test whose figures are under test: the simulated clock, so a run
  /// takes a fraction of its duration in wall time while the plant sees the same samples.
  static constexpr const char* kSimulatedClock = "clock = \"simulated\"\n";

  /// A loopback config at `rate_hz` [Hz] with the 0..`y_max` um range, `loop_keys` in its [loop]
  /// table, then `tables` (e.g. "[actuator.delay]\nenabled = true\n"): by default the loopback
  /// of config/loopback.toml on the simulated clock, with one effect switched on.
  static std::string loopback_toml(const std::string& tables = {},
                                   const std::string& loop_keys = kSimulatedClock,
                                   double rate_hz = 10000.0, double y_max = 44.0) {
    return "[loop]\nrate_hz = " + std::to_string(rate_hz) + "\n" + loop_keys +
           "[limits]\ny_min = 0.0\ny_max = " + std::to_string(y_max) +
           "\n[driver]\ntype = \"loopback\"\n" + tables;
  }

  /// The slow bench: a 1 kHz loop on the simulated clock whose loopback has one mode, at 190 Hz
  /// (damping 0.07), and `tables` switched on beside it.
  static std::string slow_bench_toml(const std::string& tables = {}) {
    return loopback_toml(
        "[actuator.dynamics]\nnatural_frequencies_hz = [190.0]\ndamping_ratios = [0.07]\n"
        "mode_gains = [1.0]\n" +
            tables,
        kSimulatedClock, 1000.0);
  }

  /// The daemon's settings for a TOML config (the user's path: bench_settings_from), with the
  /// test's folders and the shared-machine loop settings of base_settings().
  daemon::BenchSettings settings_from_toml(const std::string& toml) const {
    daemon::BenchSettings s = daemon::bench_settings_from(daemon::parse_config(toml));
    const daemon::BenchSettings base = base_settings(s.loop.rate_hz);
    s.loop.realtime = base.loop.realtime;
    s.loop.overrun_budget = base.loop.overrun_budget;
    s.log_dir = base.log_dir;
    s.model_dir = base.model_dir;
    return s;
  }

  /// The standard excitation's segments shortened so an identification at 5 kHz plays about
  /// 18 s (from 34 s): 2 major loops, 4 minor loops, 2 and 10 Hz rate segments, 1 s holds at the
  /// range's ends; the settle hold, the preconditioning and the segment order stay the daemon's.
  static void shorten_identify(daemon::BenchSettings& s) {
    s.identify.cycles = 2;
    auto& e = s.identify_excitation;
    e.minor_loops = 4;
    e.rate_frequencies_hz = {2.0, 10.0};
    e.rate_cycles = {2, 5};
    e.hold_levels = {1.0, 0.0};
    e.hold_s = 1.0;
  }

  /// shorten_identify() cut further to what a fit needs, about 5 s of excitation, for a test
  /// whose model only has to exist and take most of the hysteresis out: no settle hold, a 0.2 s
  /// sweep, one 2 Hz major loop, no minor loops, one 10 Hz rate segment, 0.25 s holds.
  static void cut_identify(daemon::BenchSettings& s) {
    shorten_identify(s);
    s.identify.settle_s = 0.0;
    s.identify.precondition_s = 0.2;
    s.identify.cycles = 1;
    s.identify.frequency_hz = 2.0;
    s.identify_excitation.minor_loops = 0;
    s.identify_excitation.rate_frequencies_hz = {10.0};
    s.identify_excitation.rate_cycles = {5};
    s.identify_excitation.hold_s = 0.25;
  }

  void start(daemon::BenchSettings s) {
    bench_ = std::make_unique<daemon::Bench>(std::move(s));
    bench_->set_event_sink([this](const nlohmann::json& e) {
      if (e["event"] == "run.finished") {
        std::lock_guard lock(m_);
        results_.push_back(e["result"]);
      }
    });
    bench_->start();
  }

  /// Sends a run command and waits for the bench to be idle; the run's result (null if none).
  nlohmann::json run_and_wait(const std::string& cmd, const nlohmann::json& params,
                              int timeout_s = 120) {
    bench_->handle(cmd, params);
    EXPECT_TRUE(bench_->wait_idle(std::chrono::seconds(timeout_s)));
    std::lock_guard lock(m_);
    return results_.empty() ? nlohmann::json() : results_.back();
  }

  nlohmann::json status() { return bench_->handle("status", nlohmann::json::object()); }

  /// Whether identify's `model.extension` lists a part for `cause` ("delay", "rate_dependence").
  static bool has_part(const nlohmann::json& extension, const std::string& cause) {
    const nlohmann::json parts = extension.value("parts", nlohmann::json::array());
    return std::any_of(parts.begin(), parts.end(),
                       [&](const nlohmann::json& p) { return p.value("cause", "") == cause; });
  }

  /// True when identify's extension was adopted with the part `cause` in it (an extension
  /// adopted in part, its fast parts alone, leaves the others out).
  static bool adopted_part(const nlohmann::json& extension, const std::string& cause) {
    const nlohmann::json parts = extension.value("parts", nlohmann::json::array());
    return extension.value("adopted", false) &&
           std::any_of(parts.begin(), parts.end(), [&](const nlohmann::json& p) {
             return p.value("cause", "") == cause && p.value("adopted", false);
           });
  }

  /// Waits until the active run has done `samples` ticks; false after `timeout`.
  bool wait_run_samples(std::uint64_t samples,
                        std::chrono::seconds timeout = std::chrono::seconds(20)) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < until) {
      const auto* run = bench_->loop().active();
      if (run != nullptr && run->done.load() >= samples) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  }

  /// The latest run.finished result, or null.
  nlohmann::json last_result() {
    std::lock_guard lock(m_);
    return results_.empty() ? nlohmann::json() : results_.back();
  }

  std::unique_ptr<daemon::Bench> bench_;
  std::mutex m_;
  std::vector<nlohmann::json> results_;
};

}  // namespace hystbench::test
