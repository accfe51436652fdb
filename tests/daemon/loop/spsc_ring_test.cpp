#include "hystbench/daemon/loop/spsc_ring.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <iostream>
#include <thread>
#include <vector>

namespace hd = hystbench::daemon;

namespace {

// A record that shows torn copies: every field is derived from seq.
struct Item {
  std::uint64_t seq = 0;
  std::uint64_t twice = 0;
  std::uint64_t inverted = ~std::uint64_t{0};
  bool intact() const { return twice == 2 * seq && inverted == ~seq; }
};
Item item(std::uint64_t seq) { return {seq, 2 * seq, ~seq}; }

}  // namespace

TEST(SpscRing, FixedCapacityRefusesWhenFullAndKeepsOrder) {
  hd::SpscRing<int, 8> ring;
  EXPECT_EQ(ring.capacity(), 8u);
  for (int i = 0; i < 8; ++i) EXPECT_TRUE(ring.try_push(i));
  EXPECT_FALSE(ring.try_push(99));
  EXPECT_EQ(ring.size_approx(), 8u);
  int v = -1;
  for (int i = 0; i < 8; ++i) {
    ASSERT_TRUE(ring.try_pop(v));
    EXPECT_EQ(v, i);
  }
  EXPECT_FALSE(ring.try_pop(v));
  EXPECT_TRUE(ring.empty_approx());
}

TEST(SpscRing, DynamicCapacityRoundsUpToPowerOfTwo) {
  hd::SpscRing<int> ring(100);
  EXPECT_EQ(ring.capacity(), 128u);
  EXPECT_EQ(hd::SpscRing<int>(2).capacity(), 2u);
  EXPECT_THROW(hd::SpscRing<int>(1), std::invalid_argument);
  EXPECT_THROW(hd::SpscRing<int>(0), std::invalid_argument);
}

TEST(SpscRing, PopBatchWrapsAroundTheEnd) {
  hd::SpscRing<int> ring(8);
  std::vector<int> out(8);
  int next_in = 0;
  int next_out = 0;
  for (int round = 0; round < 50; ++round) {
    const int burst = 1 + round % 8;
    for (int i = 0; i < burst; ++i) ASSERT_TRUE(ring.try_push(next_in++));
    const std::size_t n = ring.pop_batch(std::span<int>(out.data(), 5));
    EXPECT_EQ(n, std::min<std::size_t>(5, static_cast<std::size_t>(next_in - next_out)));
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(out[i], next_out++);
    next_out += static_cast<int>(ring.pop_batch(std::span<int>(out.data(), 8)));
    ASSERT_EQ(next_out, next_in);
  }
  EXPECT_EQ(ring.pop_batch(std::span<int>(out.data(), 0)), 0u);
}

TEST(SpscRing, TwoThreadsDeliverMillionsInOrderWithoutLossWhenProducerWaits) {
  constexpr std::uint64_t kItems = 5'000'000;
  hd::SpscRing<Item> ring(1024);
  std::uint64_t full_spins = 0;
  const auto start = std::chrono::steady_clock::now();
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kItems; ++i) {
      while (!ring.try_push(item(i))) {
        ++full_spins;
        std::this_thread::yield();
      }
    }
  });
  std::vector<Item> batch(256);
  std::uint64_t expected = 0;
  bool ok = true;
  while (expected < kItems && ok) {
    const std::size_t n = ring.pop_batch(batch);
    if (n == 0) std::this_thread::yield();
    for (std::size_t i = 0; i < n; ++i) {
      ok = ok && batch[i].seq == expected && batch[i].intact();
      ++expected;
    }
  }
  producer.join();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_TRUE(ok) << "out of order or torn record near " << expected;
  EXPECT_EQ(expected, kItems);
  Item extra;
  EXPECT_FALSE(ring.try_pop(extra));
  std::cout << "[ measure  ] SpscRing<24-byte record>: " << kItems / seconds / 1e6
            << " M records/s between two threads (" << full_spins << " full spins)\n";
}

TEST(SpscRing, DropsAreExactlyWhatDidNotFitWhenConsumerIsIdle) {
  hd::SpscRing<Item> ring(64);
  std::uint64_t dropped = 0;
  for (std::uint64_t i = 0; i < 1000; ++i) dropped += ring.try_push(item(i)) ? 0 : 1;
  EXPECT_EQ(dropped, 1000u - 64u);
  Item out;
  for (std::uint64_t i = 0; i < 64; ++i) {
    ASSERT_TRUE(ring.try_pop(out));
    EXPECT_EQ(out.seq, i);  // the oldest are kept, the newest refused
  }
}

TEST(SpscRing, SlowConsumerSeesOrderedSubsequenceAndDropsAddUp) {
  constexpr std::uint64_t kItems = 2'000'000;
  hd::SpscRing<Item> ring(256);
  std::uint64_t dropped = 0;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kItems; ++i) dropped += ring.try_push(item(i)) ? 0 : 1;
    done.store(true);
  });
  std::uint64_t received = 0;
  std::uint64_t last = 0;
  bool ordered = true;
  std::vector<Item> batch(16);
  for (;;) {
    const bool finished = done.load();
    const std::size_t n = ring.pop_batch(batch);
    for (std::size_t i = 0; i < n; ++i) {
      ordered = ordered && batch[i].intact() && (received == 0 || batch[i].seq > last);
      last = batch[i].seq;
      ++received;
    }
    if (n == 0 && finished) break;
    if (received % 4096 == 0) std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
  producer.join();
  EXPECT_TRUE(ordered);
  EXPECT_EQ(received + dropped, kItems);
}
