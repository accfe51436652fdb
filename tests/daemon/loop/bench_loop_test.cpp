// BenchLoop driven by step() with an injected clock: the per-tick path runs deterministically,
// tick by tick, on the test's thread.
#include "hystbench/daemon/loop/bench_loop.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "drivers/example_driver.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "hystbench/daemon/runs/track_drive.hpp"
#include "hystbench/sim/simulated_actuator.hpp"
#include "support/stepped_loop.hpp"

namespace hd = hystbench::daemon;
namespace hs = hystbench::sim;

namespace {
std::int64_t fake_now = 0;
std::int64_t fake_clock() noexcept { return fake_now += 1000; }  // 1 µs per reading

std::unique_ptr<hystbench::drivers::Driver> loopback(double rate_hz) {
  auto d = hystbench::drivers::make_driver("loopback");
  // The modified-PI truth, so that its model (the run's inverse) is the plant's.
  const nlohmann::json truth = hs::to_json(hs::SimulatedActuatorConfig::modified_pi_truth());
  EXPECT_TRUE(d->configure({{"actuator", truth}}, rate_hz).ok);
  EXPECT_TRUE(d->activate().ok);
  return d;
}
}  // namespace

TEST(BenchLoop, StepsATrackRunTickByTickToTheSameResultEveryTime) {
  constexpr double kRate = 5000.0;
  auto run_once = [&]() -> double {
    fake_now = 0;
    auto driver = loopback(kRate);
    hd::BenchLoopOptions o;
    o.rate_hz = kRate;
    o.clock_ns = &fake_clock;
    hd::BenchLoop loop(*driver, o);
    EXPECT_EQ(loop.state(), hd::BenchLoop::State::kStopped);
    loop.step();  // an idle tick: reads the actuator, no run
    EXPECT_EQ(loop.state(), hd::BenchLoop::State::kIdle);
    const auto truth =
        hs::make_truth_model(hs::SimulatedActuatorConfig::modified_pi_truth(), 1.0 / kRate);
    hd::VerificationSpec spec;
    spec.frequency_hz = 5.0;
    spec.periods = 2.0;
    spec.precondition_s = 0.2;
    auto program =
        hd::make_verification_program(truth, spec, loop.last_output(), o.limits, 1.0 / kRate);
    const std::uint64_t total = program->total_samples;
    EXPECT_EQ(loop.submit(std::move(program)), nullptr);
    loop.step();
    EXPECT_EQ(loop.state(), hd::BenchLoop::State::kRunning);
    if (loop.active() == nullptr) {
      ADD_FAILURE() << "no active run after the first tick";
      return NAN;
    }
    EXPECT_EQ(loop.active()->done.load(), 1u);
    for (std::uint64_t k = 1; k < total; ++k) loop.step();
    EXPECT_EQ(loop.state(), hd::BenchLoop::State::kIdle);
    auto done = loop.take_finished();
    if (done == nullptr) {
      ADD_FAILURE() << "the run did not finish";
      return NAN;
    }
    EXPECT_EQ(done->end, hd::RunEnd::kCompleted);
    EXPECT_EQ(done->done.load(), total);
    EXPECT_EQ(done->counters.overruns, 0u);
    // The injected clock times each tick: 1 µs between its start and its end.
    const auto stats = loop.statistics();
    EXPECT_EQ(stats.ticks, total + 1);
    return std::sqrt(done->error.sum2 / static_cast<double>(done->error.samples));
  };
  const double first = run_once();
  // The truth's own inverse tracks its actuator, and the same ticks give the same figure.
  EXPECT_LT(first, 0.01 * 36.0);
  EXPECT_EQ(run_once(), first);
}

TEST(BenchLoop, StepIsIgnoredWhileTheLoopThreadRuns) {
  auto driver = loopback(1000.0);
  hd::BenchLoopOptions o;
  o.rate_hz = 1000.0;
  o.realtime.fifo = false;
  o.realtime.lock_memory = false;
  hd::BenchLoop loop(*driver, o);
  loop.start();
  const std::uint64_t before = loop.ticks();
  for (int i = 0; i < 100; ++i) loop.step();
  // At 1 kHz the thread adds a few ticks meanwhile; step() would have added 100 at once.
  EXPECT_LT(loop.ticks() - before, 100u);
  loop.shutdown();
}

// A stale reading is the last fresh one again: the feedback holds on it instead of integrating
// an error that only the reading's age makes. The example driver's sensor answers every second
// tick, so every second tick's feedback holds: the drive does not move on the tick after a
// stale reading, and does on the tick after a fresh one while the loop still converges.
TEST(BenchLoop, TheFeedbackHoldsOnAStaleReading) {
  constexpr double kRate = 2000.0, kDt = 1.0 / kRate;
  hystbench::test::SteppedLoop s =
      hystbench::test::stepped_loop(std::make_unique<example::FirstOrderDriver>(), kRate);
  hd::BenchLoop& loop = *s.loop;
  namespace hc = hystbench::compensation;
  hc::FeedbackLaw law;
  law.pid.ki = 200.0;  // [1/s] on the 50 Hz first-order stage through its gain
  const hc::LinearMap linear{.gain = 0.2, .offset = 0.0};
  auto program = std::make_unique<hd::RunProgram>();
  program->kind = hd::RunKind::kTrack;
  program->total_samples = 400;
  hd::TrackDrive& track = hd::make_track_drive(*program);
  track.program.reference = hystbench::sim::make_uniform_signal({10.0, 10.0}, 1.0);
  track.program.compensator.emplace(hc::CompensatorKind::kPid, nullptr,
                                    hc::FeedbackController(law, kDt), linear);
  program->records.capacity = program->total_samples;
  program->records.u.resize(program->total_samples);
  program->records.y.resize(program->total_samples);
  program->records.yr.resize(program->total_samples);
  ASSERT_EQ(loop.submit(std::move(program)), nullptr);
  for (int k = 0; k < 400; ++k) loop.step();
  auto done = loop.take_finished();
  ASSERT_NE(done, nullptr);
  ASSERT_EQ(done->end, hd::RunEnd::kCompleted);
  EXPECT_EQ(done->counters.stale_reads, 200u);
  const auto& u = done->records.u;
  int held = 0, moved = 0;
  for (std::size_t k = 2; k < 100; ++k) {
    // The driver's first, third ... reading is stale: the one at tick k - 1 when k - 1 is odd
    // (the loop's first step read before the run).
    if ((k - 1) % 2 == 1) {
      held += u[k] == u[k - 1] ? 1 : 0;
    } else {
      moved += u[k] != u[k - 1] ? 1 : 0;
    }
  }
  EXPECT_EQ(held, 49) << "the drive moved on a stale reading";
  EXPECT_EQ(moved, 49);
  // Held or not, the loop reaches the reference.
  EXPECT_NEAR(done->records.y[399], 10.0, 0.05);
}
