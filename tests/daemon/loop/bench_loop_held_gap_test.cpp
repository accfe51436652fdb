// BenchLoop on the simulated clock with its thread running: two runs are never closer than the
// gap, and time stands still after it for the grace, and between the runs of one request until
// the next run comes: the second run meets the same plant however long the control thread
// computed in between.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "drivers/example_driver.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "hystbench/sim/simulated_actuator.hpp"

namespace hd = hystbench::daemon;
namespace hs = hystbench::sim;

namespace {
constexpr double kRate = 5000.0;

std::unique_ptr<hystbench::drivers::Driver> loopback(const nlohmann::json& config) {
  auto driver = hystbench::drivers::make_driver("loopback");
  EXPECT_TRUE(driver->configure(config, kRate).ok);
  EXPECT_TRUE(driver->activate().ok);
  return driver;
}

/// The simulated clock at kRate, a gap of 0.2 s (1000 ticks), a grace of 0.25 s.
hd::BenchLoopOptions simulated_options() {
  hd::BenchLoopOptions o;
  o.rate_hz = kRate;
  o.clock = hd::LoopClock::kSimulated;
  o.realtime.fifo = false;
  o.realtime.lock_memory = false;
  o.held_gap_s = 0.2;
  o.idle_grace_s = 0.25;
  return o;
}

/// A short verification run of the modified-PI truth's own inverse on the loopback.
std::unique_ptr<hd::RunProgram> verification(const hd::BenchLoop& loop) {
  const auto truth =
      hs::make_truth_model(hs::SimulatedActuatorConfig::modified_pi_truth(), 1.0 / kRate);
  hd::VerificationSpec spec;
  spec.frequency_hz = 5.0;
  spec.periods = 2.0;
  spec.precondition_s = 0.1;
  return hd::make_verification_program(truth, spec, loop.last_output(), loop.options().limits,
                                       1.0 / kRate);
}

std::unique_ptr<hd::RunProgram> play(hd::BenchLoop& loop, std::unique_ptr<hd::RunProgram> p) {
  EXPECT_EQ(loop.submit(std::move(p)), nullptr);
  std::unique_ptr<hd::RunProgram> done;
  loop.wait_for([&] { return (done = loop.take_finished()) != nullptr; }, std::chrono::seconds(60));
  return done;
}

/// Two runs on a fresh loopback, `computing` of wall time between them; the second run's sum of
/// squared errors (its creep remembers how long the output idled at the safe value).
double second_run_sum2(bool hold, std::chrono::milliseconds computing) {
  auto driver =
      loopback({{"actuator", hs::to_json(hs::SimulatedActuatorConfig::modified_pi_truth())}});
  hd::BenchLoop loop(*driver, simulated_options());
  loop.start();
  loop.hold_time_between_runs(hold);
  EXPECT_NE(play(loop, verification(loop)), nullptr);
  std::this_thread::sleep_for(computing);
  auto second = play(loop, verification(loop));
  loop.hold_time_between_runs(false);
  loop.shutdown();
  if (second == nullptr) {
    ADD_FAILURE() << "the second run did not finish";
    return 0.0;
  }
  EXPECT_EQ(second->end, hd::RunEnd::kCompleted);
  return second->error.sum2;
}
}  // namespace

TEST(BenchLoopHeldGap, TheSecondRunOfARequestMeetsThePlantTheFixedGapLeftWhateverTheComputation) {
  const double quick = second_run_sum2(true, std::chrono::milliseconds(5));
  const double slow = second_run_sum2(true, std::chrono::milliseconds(400));
  EXPECT_GT(quick, 0.0);
  EXPECT_EQ(quick, slow);
  // Without the hold, a run sent within the grace meets the same plant; 600 ms is past the
  // grace, where the idle is paced on the wall clock: about 1700 ticks more relax the creep,
  // and the second run differs.
  EXPECT_EQ(second_run_sum2(false, std::chrono::milliseconds(5)), quick);
  EXPECT_NE(second_run_sum2(false, std::chrono::milliseconds(600)), quick);
}

TEST(BenchLoopHeldGap, ARunSentAtOnceAfterAnotherWaitsForTheGapWithoutAHold) {
  auto driver =
      loopback({{"actuator", hs::to_json(hs::SimulatedActuatorConfig::modified_pi_truth())}});
  hd::BenchLoop loop(*driver, simulated_options());
  const std::uint64_t gap = 1000;  // 0.2 s at kRate
  loop.start();
  auto second = verification(loop);  // built before: sent as soon as the first is taken
  const auto first = play(loop, verification(loop));
  ASSERT_NE(first, nullptr);
  const auto done = play(loop, std::move(second));
  ASSERT_NE(done, nullptr);
  EXPECT_EQ(done->end, hd::RunEnd::kCompleted);
  // The gap after start, the first run, the gap after it, the second run: at least that many
  // ticks, where a loop that started each run at once would have ticked a few paced ones.
  EXPECT_GE(loop.ticks(), 2 * gap + first->done.load() + done->done.load());
  loop.shutdown();
}

TEST(BenchLoopHeldGap, TimeStandsStillAfterTheGapAndTheWatchdogStillSeesTheLoopAlive) {
  auto driver = loopback(nlohmann::json::object());
  hd::BenchLoop loop(*driver, simulated_options());
  loop.start();
  loop.hold_time_between_runs(true);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  // Idle ticks stopped at the gap's 1000; the count still advances (polls) for the watchdog.
  const std::uint64_t ticked = loop.statistics().ticks;
  EXPECT_EQ(ticked, 1000u);
  const std::uint64_t alive = loop.ticks();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_GT(loop.ticks(), alive);
  EXPECT_EQ(loop.statistics().ticks, ticked);
  // Released past the grace, the idle is paced on the wall clock again.
  loop.hold_time_between_runs(false);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_GT(loop.statistics().ticks, ticked);
  loop.shutdown();
}
