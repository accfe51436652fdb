#pragma once
// The last fault of one driver stack, stored on the real-time path and put in words later.
// Each layer (a driver, a wrapper such as GpioDriver, the framework's Driver) reports its own
// cause enum with one number that details it (an errno, a count, a duration in ns); the layer
// that reported it turns it into words for `status`. store() is wait-free and allocates nothing;
// describe() is not real-time. Readers in other threads may see a cause with the previous detail
// for an instant (the three fields are separate atomics).
#include <atomic>
#include <cstdint>
#include <string>

namespace hystbench::drivers {

/// A layer that reports faults and can say what they mean.
class FaultSource {
 public:
  /// `cause` (this layer's enum as an int, never 0) in words; `detail` as stored with it.
  virtual std::string describe_fault(int cause, std::int64_t detail) const = 0;

 protected:
  ~FaultSource() = default;
};

class FaultLog {
 public:
  /// Makes `cause` of `source` the last fault (`cause` an enum whose 0 means none).
  template <typename Cause>
  void store(const FaultSource& source, Cause cause, std::int64_t detail = 0) noexcept {
    detail_.store(detail, std::memory_order_relaxed);
    cause_.store(static_cast<int>(cause), std::memory_order_relaxed);
    source_.store(&source, std::memory_order_release);
  }
  void clear() noexcept { source_.store(nullptr, std::memory_order_release); }
  /// The last fault in words; "" when there was none since clear().
  std::string describe() const {
    const FaultSource* s = source_.load(std::memory_order_acquire);
    const int cause = cause_.load(std::memory_order_relaxed);
    return s == nullptr || cause == 0
               ? std::string()
               : s->describe_fault(cause, detail_.load(std::memory_order_relaxed));
  }

 private:
  std::atomic<const FaultSource*> source_{nullptr};
  std::atomic<int> cause_{0};
  std::atomic<std::int64_t> detail_{0};
};

}  // namespace hystbench::drivers
