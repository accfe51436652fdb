#include "hystbench/daemon/loop/target_window.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace hd = hystbench::daemon;

// The window holds the newest `capacity` targets, oldest first, across the moves of its buffer.
TEST(TargetWindow, HoldsTheNewestTargetsOldestFirstAcrossBufferMoves) {
  hd::TargetWindow w;
  w.allocate(4);
  EXPECT_TRUE(w.view().empty());
  for (int k = 0; k < 23; ++k) {
    w.push(static_cast<double>(k));
    const auto v = w.view();
    const int size = k + 1 < 4 ? k + 1 : 4;
    ASSERT_EQ(static_cast<int>(v.size()), size) << k;
    for (int j = 0; j < size; ++j) EXPECT_EQ(v[j], static_cast<double>(k - size + 1 + j)) << k;
  }
  w.clear();
  EXPECT_TRUE(w.view().empty());
}

TEST(TargetWindow, WithoutCapacityItHoldsNothing) {
  hd::TargetWindow w;
  w.push(1.0);
  EXPECT_EQ(w.capacity(), 0u);
  EXPECT_TRUE(w.view().empty());
}

// advance(): the first tick fills the window with this tick's target and the ones ahead; each
// later tick adds the one capacity() - 1 ticks ahead, so view()[0] is always this tick's.
TEST(TargetWindow, AdvanceKeepsThisTicksTargetFirstAndTheOnesAheadBehindIt) {
  hd::TargetWindow w;
  w.allocate(3);
  const double dt = 0.5;
  auto target_at = [](double t) noexcept { return 10.0 * t; };
  for (int k = 0; k < 9; ++k) {
    const double t = k * dt;
    const auto v = w.advance(t, dt, target_at);
    ASSERT_EQ(v.size(), 3u) << k;
    for (int j = 0; j < 3; ++j) EXPECT_DOUBLE_EQ(v[j], target_at(t + j * dt)) << k << " " << j;
  }
}
