#pragma once
// The output the loop wrote to axis 0, one value per tick that exchanged with the driver (a
// run's, an idle one's, a fault's safe output), over the last capacity() ticks: the bench
// replays the active model over it, so that a run's model starts in the state the actuator's
// history left, not relaxed at the present output.
//
// Threads: push() is the loop thread's and real-time safe (one relaxed store per value);
// written() and copy_since() are for any other thread, beside it: a value the loop overwrites
// while it is copied is left out of the copy (copy_since() says where the copy begins).
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace hystbench::daemon {

class OutputHistory {
 public:
  /// Holds the last `capacity` values (>= 1; allocates capacity values, 8 bytes each).
  explicit OutputHistory(std::size_t capacity);

  /// The tick's output [V]. Loop thread; real-time safe.
  void push(double u) noexcept {
    const std::uint64_t w = written_.load(std::memory_order_relaxed);
    slots_[w % capacity_].store(u, std::memory_order_relaxed);
    written_.store(w + 1, std::memory_order_release);
  }
  /// Values pushed since construction (the next one's tick number).
  std::uint64_t written() const noexcept { return written_.load(std::memory_order_acquire); }
  std::size_t capacity() const noexcept { return capacity_; }
  /// The values of ticks [first, end) into `out` (replaced), where first = max(from, the oldest
  /// tick still held) and end = written() when the copy began; returns first. Not real-time safe.
  std::uint64_t copy_since(std::uint64_t from, std::vector<double>& out) const;

 private:
  std::size_t capacity_;
  std::unique_ptr<std::atomic<double>[]> slots_;
  std::atomic<std::uint64_t> written_{0};
};

}  // namespace hystbench::daemon
