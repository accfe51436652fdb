// How much later than usual a reading answered (ReadingLateness): alone, then in the loop behind
// a driver that answers the write of the tick before as a rule, of four ticks before at times,
// of this tick at others, and sometimes not at all (a Modbus exchange on its own thread on a busy
// machine). Each drive update hears how late the reading it holds answered.
#include "hystbench/daemon/loop/reading_lateness.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/daemon/loop/run_drive.hpp"
#include "support/stepped_loop.hpp"

namespace hd = hystbench::daemon;
namespace hdr = hystbench::drivers;

namespace {

TEST(ReadingLateness, AReadingIsLateByHowFarItExceedsTheRunsMostFrequentResponse) {
  hd::ReadingLateness lateness;
  lateness.reset();
  auto late = [&lateness](std::uint64_t r) { return lateness.fresh(r).late_ticks; };
  EXPECT_EQ(late(2), 0u) << "the first fresh reading sets the usual";
  EXPECT_EQ(late(2), 0u);
  EXPECT_EQ(late(5), 3u);
  EXPECT_EQ(late(1), 0u) << "a quicker answer is not early";
  EXPECT_EQ(late(2), 0u) << "nor does it move the usual";
  EXPECT_EQ(late(5), 3u);
  for (int i = 0; i < 4; ++i) (void)late(4);
  EXPECT_EQ(late(5), 1u) << "the most frequent is the usual";
  EXPECT_EQ(late(1000), 996u) << "however late";
  lateness.reset();
  EXPECT_EQ(late(5), 0u) << "a new run keeps nothing of the last";
}

TEST(ReadingLateness, TheFeedbackHoldsAfterAStallForAsManyReadingsAsItAddedTicks) {
  hd::ReadingLateness every_tick;
  every_tick.reset();
  for (int i = 0; i < 20; ++i) EXPECT_FALSE(every_tick.fresh(1).hold);
  every_tick.stale();
  EXPECT_FALSE(every_tick.fresh(1).hold) << "one stale tick is no stall";
  for (int i = 0; i < 3; ++i) every_tick.stale();
  std::vector<bool> held;
  for (int i = 0; i < 5; ++i) held.push_back(every_tick.fresh(1).hold);
  EXPECT_EQ(held, (std::vector<bool>{true, true, true, false, false}))
      << "3 stale ticks more than usual: the next 3 readings held";

  hd::ReadingLateness every_third_tick;
  every_third_tick.reset();
  for (int i = 0; i < 30; ++i) {
    every_third_tick.stale();
    every_third_tick.stale();
    EXPECT_FALSE(every_third_tick.fresh(1).hold) << "its usual gap: " << i;
  }
  for (int i = 0; i < 4; ++i) every_third_tick.stale();
  EXPECT_TRUE(every_third_tick.fresh(1).hold) << "two ticks more than its usual gap";
  EXPECT_TRUE(every_third_tick.fresh(1).hold);
  EXPECT_FALSE(every_third_tick.fresh(1).hold);
}

// A stage whose position is its output (1 µm per V), read through an exchange that answers the
// write of the tick before, of four ticks before at every 7th tick, of this tick at every 13th,
// and nothing (stale) at every 11th. The pattern counts the run's ticks.
class LateExchangeDriver final : public hdr::DriverInterface {
 public:
  hdr::Result on_configure(const nlohmann::json&, double) override {
    return hdr::Result::success();
  }
  hdr::Result on_activate() override {
    tick_ = 0;
    writes_.fill(0.0);
    return hdr::Result::success();
  }
  hdr::DriverStatus write(double output_v) noexcept override {
    writes_[tick_ % writes_.size()] = output_v;
    return hdr::DriverStatus::kOk;
  }
  hdr::DriverStatus read(hdr::Measurement& out) noexcept override {
    const std::uint64_t k = tick_++;
    if (k % 11 == 10) return hdr::DriverStatus::kStale;
    const std::uint64_t r = k % 7 == 6 ? 4 : (k % 13 == 12 ? 0 : 1);
    if (k < r) return hdr::DriverStatus::kStale;
    out.position_um = writes_[(k - r) % writes_.size()];
    out.response_ticks = r;
    return hdr::DriverStatus::kOk;
  }
  hdr::DriverStatus safe_state() noexcept override { return hdr::DriverStatus::kOk; }
  void set_run_active(bool active) noexcept override {
    if (active) tick_ = 0;
  }
  hdr::DriverInfo info() const noexcept override {
    return {.max_rate_hz = 10000.0, .output_max_v = 150.0};
  }
  std::string_view type() const noexcept override { return "late_exchange"; }

 private:
  std::uint64_t tick_ = 0;
  std::array<double, 16> writes_{};
};

// Drives its reference as the output: a ramp of 0.5 µm per tick from 10 µm.
class RampDrive final : public hd::RunDrive {
 public:
  std::vector<hd::DriveInput> inputs;
  void configure(const hd::DriveSetup&) override { inputs.reserve(1000); }
  hd::DriveCommand update(const hd::DriveInput& in) noexcept override {
    inputs.push_back(in);
    hd::DriveCommand c;
    c.y_ref = 10.0 + 0.5 * static_cast<double>(in.k);
    c.u = c.u_ff = c.y_ref;
    return c;
  }
};

TEST(ReadingLateness, EachUpdateHearsHowLateItsReadingAnsweredAndAQuickerAnswerMovesNothing) {
  constexpr std::uint64_t kTicks = 200;
  hystbench::test::SteppedLoop s =
      hystbench::test::stepped_loop(std::make_unique<LateExchangeDriver>(), 2000.0);
  hd::BenchLoop& loop = *s.loop;

  auto owned = std::make_unique<RampDrive>();
  RampDrive& drive = *owned;
  auto p = std::make_unique<hd::RunProgram>();
  p->total_samples = kTicks;
  p->drive = std::move(owned);
  ASSERT_EQ(loop.submit(std::move(p)), nullptr);
  for (std::uint64_t k = 0; k < kTicks; ++k) loop.step();
  auto done = loop.take_finished();
  ASSERT_NE(done, nullptr);
  ASSERT_EQ(done->end, hd::RunEnd::kCompleted) << done->end_reason;
  ASSERT_GT(done->counters.stale_reads, 10u);

  // The update at tick k holds the reading of tick k - 1: 3 ticks late where that answered 4
  // ticks back, on time otherwise (a quicker answer too), and none after a stale tick.
  ASSERT_EQ(drive.inputs.size(), kTicks);
  std::size_t late = 0;
  for (const hd::DriveInput& in : drive.inputs) {
    if (in.k < 8) continue;  // the usual is known from the first fresh readings on
    const std::uint64_t read_at = in.k - 1;
    if (read_at % 11 == 10) {
      EXPECT_TRUE(std::isnan(in.y)) << in.k << ": a stale reading holds the feedback";
      continue;
    }
    EXPECT_EQ(in.y_late_ticks, read_at % 7 == 6 ? 3u : 0u) << in.k;
    // What a late reading shows is the ramp of the tick it answered.
    EXPECT_DOUBLE_EQ(in.y, 10.0 + 0.5 * static_cast<double>(read_at - 1 - in.y_late_ticks) +
                               (read_at % 7 != 6 && read_at % 13 == 12 ? 0.5 : 0.0))
        << in.k;
    late += in.y_late_ticks > 0 ? 1 : 0;
  }
  EXPECT_GT(late, 20u);
}

}  // namespace
