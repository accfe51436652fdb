#include "hystbench/daemon/loop/loop_statistics.hpp"

#include <limits>
#include <nlohmann/json.hpp>
#include <thread>

namespace hystbench::daemon {

namespace {

constexpr auto kRelaxed = std::memory_order_relaxed;

// Single writer: a relaxed load + store is enough (and cheaper than a read-modify-write).
template <typename T>
void bump(std::atomic<T>& a, T by = 1) noexcept {
  a.store(a.load(kRelaxed) + by, kRelaxed);
}

}  // namespace

void LoopStatistics::AtomicHistogram::clear() noexcept {
  for (auto& c : counts) c.store(0, kRelaxed);
  count.store(0, kRelaxed);
  min.store(std::numeric_limits<std::int64_t>::max(), kRelaxed);
  max.store(std::numeric_limits<std::int64_t>::min(), kRelaxed);
  sum.store(0, kRelaxed);
}

void LoopStatistics::AtomicHistogram::add(std::int64_t ns) noexcept {
  bump(counts[LatencyHistogram::bucket_of(ns)]);
  bump(count);
  if (ns < min.load(kRelaxed)) min.store(ns, kRelaxed);
  if (ns > max.load(kRelaxed)) max.store(ns, kRelaxed);
  bump(sum, ns);
}

LatencyHistogram LoopStatistics::AtomicHistogram::load() const noexcept {
  std::array<std::uint64_t, LatencyHistogram::kBuckets> c;
  for (std::size_t i = 0; i < c.size(); ++i) c[i] = counts[i].load(kRelaxed);
  return LatencyHistogram::from_parts(c, count.load(kRelaxed), min.load(kRelaxed),
                                      max.load(kRelaxed), sum.load(kRelaxed));
}

LoopStatistics::LoopStatistics() noexcept { clear(); }

void LoopStatistics::clear() noexcept {
  wake_.clear();
  exec_.clear();
  ticks_.store(0, kRelaxed);
  overruns_.store(0, kRelaxed);
  skipped_.store(0, kRelaxed);
}

void LoopStatistics::record(std::int64_t wake_latency_ns, std::int64_t exec_ns, bool overrun,
                            std::uint64_t skipped) noexcept {
  // Seqlock writer: odd sequence while the data changes.
  const std::uint64_t seq = sequence_.load(kRelaxed);
  sequence_.store(seq + 1, kRelaxed);
  std::atomic_thread_fence(std::memory_order_release);
  if (reset_requested_.load(kRelaxed)) {
    reset_requested_.store(false, kRelaxed);
    clear();
  }
  wake_.add(wake_latency_ns);
  exec_.add(exec_ns);
  bump(ticks_);
  if (overrun) bump(overruns_);
  if (skipped != 0) bump(skipped_, skipped);
  sequence_.store(seq + 2, std::memory_order_release);
}

LoopStatisticsSnapshot LoopStatistics::snapshot() const noexcept {
  LoopStatisticsSnapshot s;
  for (;;) {
    const std::uint64_t before = sequence_.load(std::memory_order_acquire);
    if ((before & 1) == 0) {
      s.wake_latency = wake_.load();
      s.execution = exec_.load();
      s.ticks = ticks_.load(kRelaxed);
      s.overruns = overruns_.load(kRelaxed);
      s.skipped = skipped_.load(kRelaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (sequence_.load(kRelaxed) == before) return s;
    }
    // A record() is in progress (it takes well under a microsecond): try again.
    std::this_thread::yield();
  }
}

nlohmann::json to_json(const LatencySummary& s) {
  return {{"count", s.count}, {"min", s.min_ns}, {"p50", s.p50_ns},
          {"p99", s.p99_ns},  {"max", s.max_ns}, {"mean", s.mean_ns}};
}

nlohmann::json to_json(const LoopStatisticsSnapshot& s) {
  return {{"ticks", s.ticks},
          {"overruns", s.overruns},
          {"skipped", s.skipped},
          {"wake_latency_ns", to_json(s.wake_latency.summary())},
          {"exec_ns", to_json(s.execution.summary())}};
}

}  // namespace hystbench::daemon
