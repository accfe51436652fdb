#include "hystbench/daemon/loop/loop_timer.hpp"

#include <gtest/gtest.h>

#include <iostream>

#include "hystbench/daemon/loop/loop_statistics.hpp"

namespace hd = hystbench::daemon;
using namespace std::chrono_literals;

TEST(LoopTimer, RejectsPeriodsOutsideOneMicrosecondToOneSecond) {
  EXPECT_THROW(hd::LoopTimer(0ns), std::invalid_argument);
  EXPECT_THROW(hd::LoopTimer(999ns), std::invalid_argument);
  EXPECT_THROW(hd::LoopTimer(2s), std::invalid_argument);
  EXPECT_NO_THROW(hd::LoopTimer(50us));
}

TEST(LoopTimer, TicksFollowTheAbsoluteGridAndLatencyIsPlausibleAt1kHz) {
  hd::LoopTimer timer(1ms);
  hd::LoopStatistics stats;
  timer.start();
  std::uint64_t previous = 0;
  for (int k = 0; k < 2000; ++k) {
    const auto tick = timer.wait();
    const std::int64_t end = hd::LoopTimer::now_ns();
    ASSERT_EQ(tick.scheduled_ns,
              timer.start_ns() + static_cast<std::int64_t>(tick.index) * timer.period_ns());
    ASSERT_GE(tick.wake_ns, tick.scheduled_ns);
    if (k > 0) {
      ASSERT_EQ(tick.index, previous + 1 + tick.skipped);
    }
    previous = tick.index;
    stats.record(tick.latency_ns(), end - tick.wake_ns, timer.overran(tick, end), tick.skipped);
  }
  const auto s = stats.snapshot();
  EXPECT_EQ(s.ticks, 2000u);
  EXPECT_GE(s.wake_latency.min(), 0);
  EXPECT_LT(s.wake_latency.percentile(50), timer.period_ns());
  EXPECT_EQ(timer.next_deadline_ns(),
            timer.start_ns() + static_cast<std::int64_t>(previous + 1) * timer.period_ns());
  const auto w = s.wake_latency.summary();
  std::cout << "[ measure  ] 1 kHz, SCHED_OTHER, 2000 ticks: wake latency p50 " << w.p50_ns
            << " ns, p99 " << w.p99_ns << " ns, max " << w.max_ns << " ns, skipped " << s.skipped
            << "\n";
}

TEST(LoopTimer, AWholePeriodLateSkipsDeadlinesButKeepsThePhase) {
  hd::LoopTimer timer(1ms);
  const std::int64_t start = hd::LoopTimer::now_ns() - 10'500'000;  // 10.5 periods ago
  timer.start(start);
  const auto tick = timer.wait();
  EXPECT_GE(tick.skipped, 10u);
  EXPECT_EQ(tick.index, tick.skipped);
  EXPECT_EQ(tick.scheduled_ns, start + static_cast<std::int64_t>(tick.index) * 1'000'000);
  EXPECT_GE(tick.wake_ns, tick.scheduled_ns);
  const auto next = timer.wait();
  EXPECT_EQ(next.index, tick.index + 1 + next.skipped);
}

TEST(LoopTimer, LessThanAPeriodLateRunsAtOnceWithoutSkipping) {
  hd::LoopTimer timer(1s);
  const std::int64_t start = hd::LoopTimer::now_ns() - 400'000'000;  // 0.4 periods ago
  timer.start(start);
  const auto tick = timer.wait();
  EXPECT_EQ(tick.skipped, 0u);
  EXPECT_EQ(tick.index, 0u);
  EXPECT_EQ(tick.scheduled_ns, start);
  EXPECT_GE(tick.latency_ns(), 400'000'000);
}
