#include "hystbench/daemon/loop/latency_histogram.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace hd = hystbench::daemon;
using H = hd::LatencyHistogram;

TEST(LatencyHistogram, BucketsTileTheRangeWithBoundedRelativeWidth) {
  EXPECT_EQ(H::bucket_of(-5), 0u);
  EXPECT_EQ(H::bucket_of(0), 0u);
  EXPECT_EQ(H::bucket_of(15), 15u);
  std::int64_t expected_lower = 0;
  for (std::size_t i = 0; i < H::kOverflowBucket; ++i) {
    ASSERT_EQ(H::bucket_lower(i), expected_lower) << "bucket " << i;
    const std::int64_t width = H::bucket_width(i);
    ASSERT_GE(width, 1);
    ASSERT_LE(static_cast<double>(width - 1), H::bucket_lower(i) / 16.0 + 1e-9) << "bucket " << i;
    ASSERT_EQ(H::bucket_of(expected_lower), i);
    ASSERT_EQ(H::bucket_of(expected_lower + width - 1), i);
    expected_lower += width;
  }
  EXPECT_EQ(expected_lower, std::int64_t{1} << H::kMaxTrackedBits);
  EXPECT_EQ(H::bucket_of(expected_lower), H::kOverflowBucket);
  EXPECT_EQ(H::bucket_of(std::int64_t{1} << 62), H::kOverflowBucket);
  // The tracked range covers 100 ns .. 100 ms.
  EXPECT_LT(H::bucket_of(100'000'000), H::kOverflowBucket);
}

TEST(LatencyHistogram, PercentilesOfKnownInputsAreWithinBucketResolution) {
  std::vector<std::int64_t> values;
  std::mt19937_64 rng(7);
  std::lognormal_distribution<double> dist(std::log(20'000.0), 1.0);  // ~20 µs, long tail
  for (int i = 0; i < 200'000; ++i) values.push_back(static_cast<std::int64_t>(dist(rng)));
  H h;
  for (const auto v : values) h.record(v);
  std::sort(values.begin(), values.end());
  auto exact = [&](double p) {
    const auto rank = static_cast<std::size_t>(std::ceil(p / 100.0 * values.size()));
    return values[std::max<std::size_t>(rank, 1) - 1];
  };
  for (const double p : {1.0, 10.0, 50.0, 90.0, 99.0, 99.9}) {
    const double truth = static_cast<double>(exact(p));
    EXPECT_NEAR(static_cast<double>(h.percentile(p)), truth, truth / 32.0 + 1.0) << "p" << p;
  }
  EXPECT_EQ(h.count(), values.size());
  EXPECT_EQ(h.min(), values.front());
  EXPECT_EQ(h.max(), values.back());
  EXPECT_EQ(h.percentile(0.0), values.front());
  EXPECT_EQ(h.percentile(100.0), values.back());
}

TEST(LatencyHistogram, SmallValuesAreExactAndSummaryAddsUp) {
  H h;
  for (std::int64_t v = 1; v <= 10; ++v) h.record(v);
  const auto s = h.summary();
  EXPECT_EQ(s.count, 10u);
  EXPECT_EQ(s.min_ns, 1);
  EXPECT_EQ(s.p50_ns, 5);
  EXPECT_EQ(s.p99_ns, 10);
  EXPECT_EQ(s.max_ns, 10);
  EXPECT_DOUBLE_EQ(s.mean_ns, 5.5);
}

TEST(LatencyHistogram, OverflowAndEmpty) {
  H h;
  EXPECT_EQ(h.percentile(50), 0);
  EXPECT_EQ(h.summary().max_ns, 0);
  h.record(3'000'000'000);  // 3 s: overflow bucket, exact max kept
  h.record(10);
  EXPECT_EQ(h.buckets()[H::kOverflowBucket], 1u);
  EXPECT_EQ(h.percentile(100), 3'000'000'000);
  EXPECT_EQ(h.percentile(50), 10);
  h.clear();
  EXPECT_EQ(h.count(), 0u);
}
