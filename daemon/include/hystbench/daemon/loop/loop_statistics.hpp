#pragma once
// Timing statistics of a control loop: wake-up latency (actual - scheduled wake) and execution
// time (wake to done) as LatencyHistograms, plus tick, overrun and skipped-tick counts.
// record() is called by the loop thread only: O(1), allocation-free, lock-free (a seqlock
// around relaxed atomic stores). snapshot() may be called from any other thread at any time and
// returns a consistent copy (it retries while a record() is in progress).
#include <array>
#include <atomic>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>

#include "hystbench/daemon/loop/latency_histogram.hpp"

namespace hystbench::daemon {

struct LoopStatisticsSnapshot {
  LatencyHistogram wake_latency;  ///< [ns]
  LatencyHistogram execution;     ///< [ns]
  std::uint64_t ticks = 0;        ///< record() calls
  std::uint64_t overruns = 0;     ///< ticks whose work ran past the next deadline
  std::uint64_t skipped = 0;      ///< deadlines passed over entirely (LoopTimer::Tick::skipped)
};

class LoopStatistics {
 public:
  LoopStatistics() noexcept;
  LoopStatistics(const LoopStatistics&) = delete;
  LoopStatistics& operator=(const LoopStatistics&) = delete;

  /// Loop thread only. Real-time safe.
  void record(std::int64_t wake_latency_ns, std::int64_t exec_ns, bool overrun,
              std::uint64_t skipped = 0) noexcept;
  /// Any thread. Copies about 6 KiB; no allocation.
  LoopStatisticsSnapshot snapshot() const noexcept;
  /// Any thread: the next record() starts from empty statistics.
  void request_reset() noexcept { reset_requested_.store(true, std::memory_order_relaxed); }

 private:
  struct AtomicHistogram {
    std::array<std::atomic<std::uint64_t>, LatencyHistogram::kBuckets> counts;
    std::atomic<std::uint64_t> count;
    std::atomic<std::int64_t> min;
    std::atomic<std::int64_t> max;
    std::atomic<std::int64_t> sum;
    void clear() noexcept;
    void add(std::int64_t ns) noexcept;
    LatencyHistogram load() const noexcept;
  };
  void clear() noexcept;

  std::atomic<std::uint64_t> sequence_{0};
  AtomicHistogram wake_;
  AtomicHistogram exec_;
  std::atomic<std::uint64_t> ticks_{0};
  std::atomic<std::uint64_t> overruns_{0};
  std::atomic<std::uint64_t> skipped_{0};
  std::atomic<bool> reset_requested_{false};
};

/// {"ticks":..,"overruns":..,"skipped":..,
///  "wake_latency_ns":{"count","min","p50","p99","max","mean"}, "exec_ns":{...}}
nlohmann::json to_json(const LatencySummary& s);
nlohmann::json to_json(const LoopStatisticsSnapshot& s);

}  // namespace hystbench::daemon
