// The loop's output history (loop/output_history.hpp): the last outputs in tick order, and a
// copy beside a writer that never holds a value the writer overwrote meanwhile.
#include "hystbench/daemon/loop/output_history.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

namespace hd = hystbench::daemon;

TEST(OutputHistory, CopiesTheTicksSinceAskedInTickOrder) {
  hd::OutputHistory h(8);
  std::vector<double> out;
  EXPECT_EQ(h.copy_since(0, out), 0u);
  EXPECT_TRUE(out.empty());
  for (int k = 0; k < 3; ++k) h.push(10.0 + k);
  EXPECT_EQ(h.written(), 3u);
  EXPECT_EQ(h.copy_since(1, out), 1u);
  EXPECT_EQ(out, (std::vector<double>{11.0, 12.0}));
  EXPECT_EQ(h.copy_since(3, out), 3u);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(h.copy_since(7, out), 3u);  // not written yet: from the end
  EXPECT_TRUE(out.empty());
}

TEST(OutputHistory, AFullHistoryKeepsItsNewestTicks) {
  hd::OutputHistory h(4);
  for (int k = 0; k < 10; ++k) h.push(k);
  std::vector<double> out;
  // Ticks 6..9 are held; the oldest of them is the slot the next push writes, left out.
  const std::uint64_t first = h.copy_since(0, out);
  EXPECT_EQ(first, 7u);
  EXPECT_EQ(out, (std::vector<double>{7.0, 8.0, 9.0}));
}

TEST(OutputHistory, ACopyBesideTheWriterHoldsOnlyTheTicksItNames) {
  // The writer pushes tick k's number as its value, wrapping the small ring again and again
  // (a pause now and then, so that some copies finish before it laps them); every copy must
  // hold first, first + 1, ... with no value of a later lap.
  hd::OutputHistory h(4096);
  std::atomic<bool> enough{false};
  std::thread writer([&] {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    for (std::uint64_t k = 0; !enough; ++k) {
      h.push(static_cast<double>(k));
      if (k % 1024 == 0) {
        std::this_thread::yield();
        if (std::chrono::steady_clock::now() > give_up) enough = true;
      }
    }
  });
  std::vector<double> out;
  std::uint64_t copies = 0, checked = 0;
  while (!enough) {
    const std::uint64_t first = h.copy_since(0, out);
    for (std::size_t i = 0; i < out.size(); ++i) {
      ASSERT_EQ(out[i], static_cast<double>(first + i)) << "copy " << copies << ", value " << i;
    }
    if (first > 0) checked += out.size();  // the ring had wrapped
    ++copies;
    if (checked >= 10'000'000) enough = true;
  }
  writer.join();
  EXPECT_GE(checked, 10'000'000u) << copies << " copies";
}
