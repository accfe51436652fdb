#pragma once
// Fixed-bucket log-linear histogram of durations in nanoseconds: exact below 16 ns, then 16
// buckets per octave (each at most 1/16 = 6.25 % of its value wide) up to 2^27 ns = 134 ms;
// longer values share one overflow bucket (the exact maximum is kept). record() is O(1),
// allocation-free and real-time safe; the object is a plain value (copy it to snapshot).
// Percentiles are reported as the middle of their bucket clamped to [min, max], so they are
// within half a bucket (3.2 %) of the true order statistic.
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace hystbench::daemon {

struct LatencySummary {
  std::uint64_t count = 0;
  std::int64_t min_ns = 0;  ///< all zero when count == 0
  std::int64_t p50_ns = 0;
  std::int64_t p99_ns = 0;
  std::int64_t max_ns = 0;
  double mean_ns = 0.0;
};

class LatencyHistogram {
 public:
  static constexpr int kSubBucketBits = 4;
  static constexpr std::int64_t kSubBuckets = std::int64_t{1} << kSubBucketBits;
  static constexpr int kMaxTrackedBits = 27;  ///< values >= 2^27 ns go to the overflow bucket
  static constexpr std::size_t kOverflowBucket =
      static_cast<std::size_t>((kMaxTrackedBits - kSubBucketBits + 1) * kSubBuckets);
  static constexpr std::size_t kBuckets = kOverflowBucket + 1;

  /// Bucket of a value; negative values count as 0.
  static constexpr std::size_t bucket_of(std::int64_t ns) noexcept {
    if (ns < kSubBuckets) return ns < 0 ? 0 : static_cast<std::size_t>(ns);
    if (ns >= (std::int64_t{1} << kMaxTrackedBits)) return kOverflowBucket;
    const int msb = std::bit_width(static_cast<std::uint64_t>(ns)) - 1;
    const int shift = msb - kSubBucketBits;
    return static_cast<std::size_t>((shift + 1) * kSubBuckets + ((ns >> shift) - kSubBuckets));
  }
  /// Smallest value in bucket i.
  static constexpr std::int64_t bucket_lower(std::size_t i) noexcept {
    const auto k = static_cast<std::int64_t>(i);
    if (k < kSubBuckets) return k;
    const std::int64_t shift = k / kSubBuckets - 1;
    return (kSubBuckets + k % kSubBuckets) << shift;
  }
  /// Number of distinct values bucket i holds (the overflow bucket: 0, unbounded).
  static constexpr std::int64_t bucket_width(std::size_t i) noexcept {
    if (i == kOverflowBucket) return 0;
    const auto k = static_cast<std::int64_t>(i);
    return k < kSubBuckets ? 1 : std::int64_t{1} << (k / kSubBuckets - 1);
  }

  void record(std::int64_t ns) noexcept;
  void clear() noexcept { *this = LatencyHistogram(); }

  std::uint64_t count() const noexcept { return count_; }
  std::int64_t min() const noexcept { return count_ ? min_ : 0; }
  std::int64_t max() const noexcept { return count_ ? max_ : 0; }
  double mean() const noexcept;
  /// p in [0, 100]: the smallest bucket value v with at least ceil(p% of count) samples <= v
  /// (middle of the bucket, clamped to [min, max]); 0 when empty.
  std::int64_t percentile(double p) const noexcept;
  LatencySummary summary() const noexcept;
  const std::array<std::uint64_t, kBuckets>& buckets() const noexcept { return counts_; }

  /// Builds a histogram from raw parts (used by snapshots of atomic copies).
  static LatencyHistogram from_parts(const std::array<std::uint64_t, kBuckets>& counts,
                                     std::uint64_t count, std::int64_t min, std::int64_t max,
                                     std::int64_t sum) noexcept;

 private:
  std::array<std::uint64_t, kBuckets> counts_{};
  std::uint64_t count_ = 0;
  std::int64_t min_ = std::numeric_limits<std::int64_t>::max();
  std::int64_t max_ = std::numeric_limits<std::int64_t>::min();
  std::int64_t sum_ = 0;
};

}  // namespace hystbench::daemon
