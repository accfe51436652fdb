#include "hystbench/daemon/loop/latency_histogram.hpp"

#include <algorithm>
#include <cmath>

namespace hystbench::daemon {

void LatencyHistogram::record(std::int64_t ns) noexcept {
  ++counts_[bucket_of(ns)];
  ++count_;
  min_ = std::min(min_, ns);
  max_ = std::max(max_, ns);
  sum_ += ns;
}

double LatencyHistogram::mean() const noexcept {
  return count_ ? static_cast<double>(sum_) / static_cast<double>(count_) : 0.0;
}

std::int64_t LatencyHistogram::percentile(double p) const noexcept {
  if (count_ == 0) return 0;
  p = std::clamp(std::isnan(p) ? 0.0 : p, 0.0, 100.0);
  const auto rank = std::clamp<std::uint64_t>(
      static_cast<std::uint64_t>(std::ceil(p / 100.0 * static_cast<double>(count_))), 1, count_);
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < kBuckets; ++i) {
    seen += counts_[i];
    if (seen >= rank) {
      if (i == kOverflowBucket) return max_;
      const std::int64_t mid = bucket_lower(i) + (bucket_width(i) - 1) / 2;
      return std::clamp(mid, min_, max_);
    }
  }
  return max_;  // not reached: the buckets add up to count_
}

LatencySummary LatencyHistogram::summary() const noexcept {
  LatencySummary s;
  s.count = count_;
  s.min_ns = min();
  s.p50_ns = percentile(50.0);
  s.p99_ns = percentile(99.0);
  s.max_ns = max();
  s.mean_ns = mean();
  return s;
}

LatencyHistogram LatencyHistogram::from_parts(const std::array<std::uint64_t, kBuckets>& counts,
                                              std::uint64_t count, std::int64_t min,
                                              std::int64_t max, std::int64_t sum) noexcept {
  LatencyHistogram h;
  h.counts_ = counts;
  h.count_ = count;
  h.min_ = min;
  h.max_ = max;
  h.sum_ = sum;
  return h;
}

}  // namespace hystbench::daemon
