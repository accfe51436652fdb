#include "hystbench/daemon/loop/loop_statistics.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <nlohmann/json.hpp>
#include <numeric>
#include <thread>

namespace hd = hystbench::daemon;

TEST(LoopStatistics, RecordsLatencyExecutionOverrunsAndSkips) {
  hd::LoopStatistics stats;
  for (int k = 1; k <= 100; ++k) stats.record(k * 1'000, k * 10, k % 10 == 0, k == 50 ? 3 : 0);
  const auto s = stats.snapshot();
  EXPECT_EQ(s.ticks, 100u);
  EXPECT_EQ(s.overruns, 10u);
  EXPECT_EQ(s.skipped, 3u);
  EXPECT_EQ(s.wake_latency.min(), 1'000);
  EXPECT_EQ(s.wake_latency.max(), 100'000);
  EXPECT_NEAR(static_cast<double>(s.wake_latency.percentile(50)), 50'000, 50'000 / 32.0);
  EXPECT_EQ(s.execution.max(), 1'000);
  const auto j = hd::to_json(s);
  EXPECT_EQ(j["ticks"], 100);
  EXPECT_EQ(j["wake_latency_ns"]["max"], 100'000);
  EXPECT_EQ(j["exec_ns"]["count"], 100);
}

TEST(LoopStatistics, ResetRequestTakesEffectOnNextRecord) {
  hd::LoopStatistics stats;
  stats.record(5'000, 100, true);
  stats.request_reset();
  EXPECT_EQ(stats.snapshot().ticks, 1u);
  stats.record(7, 8, false);
  const auto s = stats.snapshot();
  EXPECT_EQ(s.ticks, 1u);
  EXPECT_EQ(s.overruns, 0u);
  EXPECT_EQ(s.wake_latency.max(), 7);
}

TEST(LoopStatistics, SnapshotsTakenDuringRecordingAreConsistent) {
  hd::LoopStatistics stats;
  std::atomic<bool> stop{false};
  constexpr std::uint64_t kTicks = 1'000'000;
  std::thread loop([&] {
    for (std::uint64_t k = 0; k < kTicks; ++k) {
      stats.record(static_cast<std::int64_t>(k % 5000), static_cast<std::int64_t>(k % 700),
                   k % 100 == 0);
    }
    stop.store(true);
  });
  int snapshots = 0;
  bool consistent = true;
  std::uint64_t last_ticks = 0;
  while (!stop.load() || snapshots == 0) {
    const auto s = stats.snapshot();
    const auto& wb = s.wake_latency.buckets();
    const auto& eb = s.execution.buckets();
    const std::uint64_t wake_sum = std::accumulate(wb.begin(), wb.end(), std::uint64_t{0});
    const std::uint64_t exec_sum = std::accumulate(eb.begin(), eb.end(), std::uint64_t{0});
    consistent = consistent && wake_sum == s.ticks && exec_sum == s.ticks &&
                 s.wake_latency.count() == s.ticks && s.execution.count() == s.ticks &&
                 s.overruns == (s.ticks + 99) / 100 && s.ticks >= last_ticks;
    last_ticks = s.ticks;
    ++snapshots;
  }
  loop.join();
  EXPECT_TRUE(consistent);
  EXPECT_EQ(stats.snapshot().ticks, kTicks);
  EXPECT_GT(snapshots, 0);
}
