#pragma once
// Lock-free histogram of transaction round-trip times: record() from one thread (real-time
// safe: relaxed atomic increments), percentiles from any other. Bins: 1 µs up to 1 ms, 10 µs up
// to 10 ms, 100 µs up to 1 s, then one overflow bin. Resolution is the bin width.
#include <array>
#include <atomic>
#include <cstdint>

namespace hystbench::drivers::details {

class RttHistogram {
 public:
  void record(std::int64_t ns) noexcept {
    bins_[bin_of(ns)].fetch_add(1, std::memory_order_relaxed);
    count_.fetch_add(1, std::memory_order_relaxed);
    std::int64_t m = max_ns_.load(std::memory_order_relaxed);
    while (ns > m && !max_ns_.compare_exchange_weak(m, ns, std::memory_order_relaxed)) {
    }
  }
  std::uint64_t count() const noexcept { return count_.load(std::memory_order_relaxed); }
  std::int64_t max_ns() const noexcept { return max_ns_.load(std::memory_order_relaxed); }
  /// Upper edge of the bin holding quantile q in [0, 1] [ns]; 0 when empty.
  std::int64_t quantile_ns(double q) const noexcept {
    const std::uint64_t n = count();
    if (n == 0) return 0;
    const auto rank = static_cast<std::uint64_t>(q * static_cast<double>(n - 1)) + 1;
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < kBins; ++i) {
      seen += bins_[i].load(std::memory_order_relaxed);
      if (seen >= rank) return i + 1 == kBins ? max_ns() : upper_edge_ns(i);
    }
    return max_ns();
  }
  /// Not concurrent with record().
  void clear() noexcept {
    for (auto& b : bins_) b.store(0, std::memory_order_relaxed);
    count_.store(0, std::memory_order_relaxed);
    max_ns_.store(0, std::memory_order_relaxed);
  }

 private:
  static constexpr std::size_t kFine = 1000, kMid = 900, kCoarse = 9900;
  static constexpr std::size_t kBins = kFine + kMid + kCoarse + 1;
  static std::size_t bin_of(std::int64_t ns) noexcept {
    const std::int64_t us = ns < 0 ? 0 : ns / 1000;
    if (us < 1000) return static_cast<std::size_t>(us);
    if (us < 10000) return kFine + static_cast<std::size_t>((us - 1000) / 10);
    if (us < 1000000) return kFine + kMid + static_cast<std::size_t>((us - 10000) / 100);
    return kBins - 1;
  }
  static std::int64_t upper_edge_ns(std::size_t i) noexcept {
    if (i < kFine) return static_cast<std::int64_t>(i + 1) * 1000;
    if (i < kFine + kMid) return (1000 + static_cast<std::int64_t>(i - kFine + 1) * 10) * 1000;
    return (10000 + static_cast<std::int64_t>(i - kFine - kMid + 1) * 100) * 1000;
  }
  std::array<std::atomic<std::uint64_t>, kBins> bins_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> max_ns_{0};
};

}  // namespace hystbench::drivers::details
