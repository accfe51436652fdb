// The loop on the simulated clock ([loop] clock = "simulated"), in-process on the loopback: a run
// ticks on virtual time (tick count x period) as fast as it computes, logs every sample on the
// exact time grid with no drops even through the smallest log ring, says so in its result, log
// header and status; stop and abort end it mid-run; idle time stands still for a grace after
// the gap, and then idle ticks are paced on the wall clock.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <iostream>
#include <string>
#include <thread>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/daemon/loop/sample_log_writer.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "support/bench_fixture.hpp"

namespace hd = hystbench::daemon;
namespace cli = hystbench::cli;
using nlohmann::json;

namespace {

class BenchSimulatedClockTest : public hystbench::test::BenchFixture {
 protected:
  BenchSimulatedClockTest() : BenchFixture("hystbench_simulated_clock_test") {}
  /// The loopback at 10 kHz on the simulated clock; the smallest sample-log ring (1024 records,
  /// a tenth of a second of samples), so the writer is always behind a free-running loop.
  void start_simulated() {
    start(settings_from_toml(
        loopback_toml({}, std::string(kSimulatedClock) + "ring_capacity = 1024\n")));
  }
};

}  // namespace

TEST_F(BenchSimulatedClockTest, ARunLogsEverySampleOnTheExactTimeGridFasterThanItsDuration) {
  start_simulated();
  const json st = status();
  EXPECT_EQ(st["loop"]["clock"], "simulated") << st.dump(2);
  EXPECT_NE(st["loop"]["realtime"].get<std::string>().find("simulated clock"), std::string::npos)
      << st.dump(2);
  EXPECT_FALSE(st["loop"]["degraded"].get<bool>());
  constexpr double kDuration = 10.0;  // 100 000 samples at 10 kHz, 100 times the log ring
  const auto begin = std::chrono::steady_clock::now();
  const json r = run_and_wait(
      "track", {{"compensator", "none"}, {"duration_s", kDuration}, {"precondition_s", 0.0}});
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  std::cout << "[ simulated ] " << kDuration << " s of 10 kHz track in " << wall_s
            << " s of wall time, execution p99 " << r["loop"]["exec_ns"]["p99"] << " ns\n";
  ASSERT_EQ(r["end"], "completed") << r.dump(2);
  EXPECT_EQ(r["clock"], "simulated");
  EXPECT_EQ(r["samples"], 100000);
  EXPECT_EQ(r["logged"], 100000);
  EXPECT_EQ(r["dropped"], 0);
  // Lateness means nothing on virtual time; the work per tick is still measured.
  EXPECT_EQ(r["overruns"], 0);
  EXPECT_EQ(r["loop"]["overruns"], 0);
  EXPECT_EQ(r["loop"]["wake_latency_ns"]["max"], 0);
  EXPECT_GT(r["loop"]["exec_ns"]["max"].get<double>(), 0.0);
  // On the wall clock the run cannot end before its duration has passed.
  EXPECT_LT(wall_s, kDuration);

  const std::string log = r["log"].get<std::string>();
  EXPECT_EQ(hd::read_sample_log_header(log)["run"]["clock"], "simulated");
  const auto table = cli::DataTable::read_csv(log);
  ASSERT_EQ(table.rows(), 100000u);
  const auto& index = table.column("index");
  const auto& scheduled = table.column("t_scheduled_ns");
  const auto& wake = table.column("t_wake_ns");
  const auto& t = table.column("t");
  for (std::size_t k = 0; k < table.rows(); ++k) {
    ASSERT_EQ(index[k], static_cast<double>(k));
    ASSERT_EQ(scheduled[k], static_cast<double>(k) * 100000.0) << "row " << k;
    ASSERT_EQ(wake[k], scheduled[k]) << "row " << k;
    ASSERT_DOUBLE_EQ(t[k], static_cast<double>(k) * 1e-4) << "row " << k;
  }
}

TEST_F(BenchSimulatedClockTest, StopAndAbortEndARunMidway) {
  start_simulated();
  const json long_run = {{"compensator", "none"}, {"duration_s", 3600.0}, {"precondition_s", 0.0}};
  for (const char* end : {"stop", "abort"}) {
    const json reply = bench_->handle("track", long_run);
    ASSERT_TRUE(wait_run_samples(50000)) << end;
    bench_->handle(end, json::object());
    ASSERT_TRUE(bench_->wait_idle(std::chrono::seconds(30))) << end;
    const json r = last_result();
    EXPECT_EQ(r["run_id"], reply["run_id"]);
    EXPECT_EQ(r["end"], std::string(end) == "stop" ? "stopped" : "aborted") << r.dump(2);
    EXPECT_EQ(r["clock"], "simulated");
    EXPECT_GE(r["samples"].get<std::uint64_t>(), 50000u);
    EXPECT_LT(r["samples"].get<std::uint64_t>(), r["planned_samples"].get<std::uint64_t>());
    EXPECT_EQ(r["logged"], r["samples"]) << r.dump(2);
    EXPECT_EQ(r["dropped"], 0);
    EXPECT_EQ(status()["state"], "idle");
  }
  EXPECT_DOUBLE_EQ(bench_->loop().last_output(), bench_->driver().safe_output_v());
}

// Between runs the loop does not run free: the idle plant evolves at a real one's pace and an
// idle daemon leaves the CPU alone. A loaded machine only lowers the count.
TEST_F(BenchSimulatedClockTest, IdleTimeStandsStillForTheGraceThenTicksPacedOnTheWallClock) {
  start_simulated();
  // The gap after start (1 s of virtual time, 10 000 ticks at 10 kHz) ticks at once; then the
  // plant's time stands still for the grace (2 s of wall time by default).
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const std::uint64_t in_grace = bench_->loop().statistics().ticks;
  EXPECT_EQ(in_grace, 10000u);
  std::this_thread::sleep_for(std::chrono::milliseconds(2000));  // past the grace
  const std::uint64_t before = bench_->loop().statistics().ticks;
  const auto begin = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const std::uint64_t ticks = bench_->loop().statistics().ticks - before;
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  std::cout << "[ simulated ] idle: " << ticks << " ticks in " << wall_s << " s\n";
  EXPECT_LE(static_cast<double>(ticks), 10000.0 * wall_s + 10.0);
  EXPECT_GT(ticks, 0u);
}
