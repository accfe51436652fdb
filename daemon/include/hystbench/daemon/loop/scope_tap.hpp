#pragma once
// The loop's scope tap: every decimation-th tick's sample (each axis's reading, reference and
// output) copied into a preallocated ring for a live view, run or idle. One consumer drains it.
// Real-time safety: offer() is wait-free, never allocates, locks or blocks; a full ring drops
// the sample and counts it (the view falls behind, the loop never waits). Units: µm, V, ns.
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

#include "hystbench/daemon/loop/spsc_ring.hpp"
#include "hystbench/drivers/driver_interface.hpp"

namespace hystbench::daemon {

/// One tick as the scope shows it. A reference not driven at that tick (idle, an open-loop
/// drive) is NaN.
struct ScopeSample {
  std::uint64_t tick = 0;    ///< the loop's tick counter (BenchLoop::ticks())
  std::int64_t time_ns = 0;  ///< the tick's deadline on the loop's clock
  std::uint32_t axes = 1;    ///< [1, drivers::kMaxAxes]: entries of the arrays that hold values
  bool running = false;      ///< a run drove this tick
  std::array<double, drivers::kMaxAxes> y{};   ///< measured position [µm]
  std::array<double, drivers::kMaxAxes> yr{};  ///< reference [µm], NaN when none
  std::array<double, drivers::kMaxAxes> u{};   ///< output sent to the driver [V]
};

class ScopeTap {
 public:
  /// decimation >= 1 (1 = every tick); capacity rounded up to a power of two, >= 2.
  ScopeTap(std::uint32_t decimation, std::size_t capacity);
  ScopeTap(const ScopeTap&) = delete;
  ScopeTap& operator=(const ScopeTap&) = delete;

  /// Loop thread: whether tick `tick` is one the scope takes. Real-time safe.
  bool due(std::uint64_t tick) const noexcept { return tick % decimation_ == 0; }
  /// Loop thread: copies the sample in, or counts it dropped when the ring is full. Real-time
  /// safe.
  void offer(const ScopeSample& sample) noexcept {
    if (!ring_.try_push(sample)) dropped_.fetch_add(1, std::memory_order_relaxed);
  }
  /// Consumer thread: moves up to out.size() samples out, oldest first; returns how many.
  std::size_t drain(std::span<ScopeSample> out) noexcept { return ring_.pop_batch(out); }

  std::uint32_t decimation() const noexcept { return decimation_; }
  /// The decimation that gives about scope_rate_hz samples per second from a loop at
  /// loop_rate_hz: every tick when the loop is slower. Both rates > 0.
  static std::uint32_t decimation_for(double loop_rate_hz, double scope_rate_hz) noexcept;
  /// Samples the ring could not take (any thread).
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  std::uint32_t decimation_;
  SpscRing<ScopeSample> ring_;
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace hystbench::daemon
