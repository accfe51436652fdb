// The live view's scope feed (http/scope_feed.hpp): drains the tap into numbered samples, hands
// each reader what came after its cursor as one JSON frame, starts a new reader a backlog back,
// and moves a reader that fell behind its history up to the newest.
#include "hystbench/daemon/http/scope_feed.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

namespace hd = hystbench::daemon;
using nlohmann::json;

namespace {

constexpr double kRate = 1000.0;  // the loop's; the tap takes every 10th tick: 100 samples/s

void offer(hd::ScopeTap& tap, std::uint64_t from, std::uint64_t count) {
  for (std::uint64_t n = from; n < from + count; ++n) {
    hd::ScopeSample s;
    s.tick = 10 * n;
    s.time_ns = static_cast<std::int64_t>(10 * n) * 1000000;  // 1 ms a tick
    s.running = n % 2 == 0;
    s.y[0] = 0.5 * static_cast<double>(n) + 1e-7;  // shown to 0.1 nm
    s.yr[0] = s.running ? 0.5 * static_cast<double>(n) : NAN;
    s.u[0] = -1.0;
    tap.offer(s);
  }
}

json frame(hd::ScopeFeed& feed, std::uint64_t& cursor) {
  const std::string text = feed.frame_after(cursor, std::chrono::milliseconds(2000));
  return text.empty() ? json() : json::parse(text);
}

hd::ScopeFeedOptions options() {
  hd::ScopeFeedOptions o;
  o.loop_rate_hz = kRate;
  o.history_s = 2.0;  // 200 samples
  o.backlog_s = 0.5;  // 50 samples
  o.poll_interval = std::chrono::milliseconds(2);
  return o;
}

}  // namespace

TEST(ScopeFeed, HandsEachReaderWhatCameAfterItsCursor) {
  hd::ScopeTap tap(10, 1024);
  hd::ScopeFeed feed(tap, options());
  feed.start();
  offer(tap, 0, 30);
  std::uint64_t cursor = 0;
  json f = frame(feed, cursor);
  ASSERT_TRUE(f.is_object());
  EXPECT_EQ(f["seq"], 0);
  EXPECT_DOUBLE_EQ(f["dt"].get<double>(), 0.01);
  EXPECT_DOUBLE_EQ(f["t0"].get<double>(), 0.0);
  EXPECT_EQ(f["axes"], json::array({""}));
  // Whatever the drain had by then: the rest comes in the next frame, nothing twice.
  std::size_t seen = f["y"][0].size();
  while (seen < 30) {
    json next = frame(feed, cursor);
    ASSERT_TRUE(next.is_object());
    EXPECT_EQ(next["seq"], seen);
    EXPECT_NEAR(next["t0"].get<double>(), 0.01 * static_cast<double>(seen), 1e-12);
    seen += next["y"][0].size();
  }
  EXPECT_EQ(seen, 30u);
  EXPECT_EQ(cursor, 30u);
  // Values as the page shows them: rounded to 0.1 nm, a missing reference as null.
  json again;
  std::uint64_t from_start = 0;
  again = frame(feed, from_start);
  EXPECT_DOUBLE_EQ(again["y"][0][1].get<double>(), 0.5);
  EXPECT_TRUE(again["yr"][0][1].is_null());
  EXPECT_DOUBLE_EQ(again["yr"][0][2].get<double>(), 1.0);
  // Nothing new: an empty answer after the wait.
  EXPECT_TRUE(feed.frame_after(cursor, std::chrono::milliseconds(30)).empty());
}

TEST(ScopeFeed, ANewReaderStartsABacklogBackAndALateOneCatchesUp) {
  hd::ScopeTap tap(10, 1024);
  hd::ScopeFeed feed(tap, options());
  feed.start();
  offer(tap, 0, 120);
  while (feed.newest() < 120) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  EXPECT_EQ(feed.start_cursor(), 70u);  // 50 samples back
  std::uint64_t late = 3;
  offer(tap, 120, 200);  // 320 in all: sample 3 left the 200-sample history long ago
  while (feed.newest() < 320) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  json f = frame(feed, late);
  EXPECT_EQ(f["seq"], 270);
  EXPECT_EQ(late, 320u);
}

TEST(ScopeFeed, StopWakesAWaitingReader) {
  hd::ScopeTap tap(10, 64);
  hd::ScopeFeed feed(tap, options());
  feed.start();
  std::uint64_t cursor = 0;
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    feed.stop();
  });
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(feed.frame_after(cursor, std::chrono::seconds(30)).empty());
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(10));
  stopper.join();
}

TEST(ScopeFeed, RefusesOptionsOutOfRange) {
  hd::ScopeTap tap(10, 64);
  auto o = options();
  o.backlog_s = 3.0;  // more than the history
  EXPECT_THROW(hd::ScopeFeed(tap, o), std::invalid_argument);
  o = options();
  o.axes.clear();
  EXPECT_THROW(hd::ScopeFeed(tap, o), std::invalid_argument);
}
