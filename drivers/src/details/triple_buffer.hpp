#pragma once
// Wait-free single-producer single-consumer exchange of the latest value (triple buffering):
// the producer never waits for the consumer and the consumer never sees a torn value, so a
// low-priority I/O thread can feed a real-time loop without priority inversion.
// publish() from one thread, take() from one other thread; T must be trivially copyable.
#include <atomic>
#include <cstdint>
#include <type_traits>

namespace hystbench::drivers::details {

template <typename T>
class TripleBuffer {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  /// Producer: makes `value` the latest one.
  void publish(const T& value) noexcept {
    slots_[back_] = value;
    back_ = middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel) &
            kIndex;
  }
  /// Consumer: the latest value into `out`; true when it is new since the previous take().
  bool take(T& out) noexcept {
    bool fresh = false;
    if (middle_.load(std::memory_order_relaxed) & kFresh) {
      front_ = middle_.exchange(front_, std::memory_order_acq_rel) & kIndex;
      fresh = true;
    }
    out = slots_[front_];
    return fresh;
  }
  /// Not thread-safe: both sides idle. Every slot becomes `value`, nothing fresh.
  void reset(const T& value) noexcept {
    for (T& s : slots_) s = value;
    back_ = 0;
    middle_.store(1, std::memory_order_release);
    front_ = 2;
  }

 private:
  static constexpr std::uint8_t kIndex = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;
  T slots_[3]{};
  std::uint8_t back_ = 0;                // producer's slot
  std::atomic<std::uint8_t> middle_{1};  // handed over, with the fresh bit
  std::uint8_t front_ = 2;               // consumer's slot
};

}  // namespace hystbench::drivers::details
