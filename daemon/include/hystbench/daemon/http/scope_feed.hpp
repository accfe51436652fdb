#pragma once
// The live view's scope: a thread drains the loop's ScopeTap every few milliseconds into a
// history of the last seconds, numbered from 0 since start; readers ask for what came after
// their cursor as one JSON frame (docs/reference/web-view.md, "The stream"), positions rounded
// to 0.1 nm and outputs to 0.1 mV. Readers never touch
// the tap, and the tap never waits for them. Thread-safe; not real-time safe.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "hystbench/daemon/loop/scope_tap.hpp"

namespace hystbench::daemon {

struct ScopeFeedOptions {
  double loop_rate_hz = 10000.0;  ///< the loop's rate: the tap's samples are decimation/rate apart
  std::vector<std::string> axes = {""};  ///< axis names in the driver's order ({""}: one axis)
  double history_s = 20.0;               ///< how far back a reader may be, > 0
  /// A new reader starts this far back, so its scope is full at once [s], <= history_s.
  double backlog_s = 5.0;
  std::chrono::milliseconds poll_interval{10};  ///< how often the tap is drained
  std::size_t max_frame_samples = 4096;         ///< samples in one frame at most
};

class ScopeFeed {
 public:
  /// The tap must outlive the feed. Throws std::invalid_argument for options out of range.
  ScopeFeed(ScopeTap& tap, ScopeFeedOptions options);
  /// Calls stop().
  ~ScopeFeed();
  ScopeFeed(const ScopeFeed&) = delete;
  ScopeFeed& operator=(const ScopeFeed&) = delete;

  void start();
  /// Ends the draining thread and wakes every waiting reader. Idempotent.
  void stop();

  /// Where a new reader starts: backlog_s before the newest sample (or the oldest kept).
  std::uint64_t start_cursor() const;
  /// Waits up to `timeout` for samples numbered >= cursor, then returns them as one frame
  /// (empty when none came or the feed stopped) and moves the cursor past them. A cursor older
  /// than the history restarts at start_cursor().
  std::string frame_after(std::uint64_t& cursor, std::chrono::milliseconds timeout);
  /// Samples numbered so far (the next one's number).
  std::uint64_t newest() const;
  bool stopped() const noexcept { return stop_.load(std::memory_order_acquire); }

 private:
  void run();
  void drain();
  std::string frame(std::uint64_t from, std::uint64_t to) const;  // mutex_ held

  ScopeTap& tap_;
  ScopeFeedOptions options_;
  double dt_s_;
  std::size_t capacity_;
  std::size_t backlog_;
  std::vector<ScopeSample> drained_;  // the draining thread's batch

  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<ScopeSample> history_;  // sample n at n % capacity_
  std::uint64_t next_ = 0;            // samples numbered so far
  std::int64_t origin_ns_ = 0;        // the first sample's time: t = 0
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace hystbench::daemon
