#pragma once
// Bounded single-producer / single-consumer lock-free ring of fixed-size records.
// One thread may push, one (other) thread may pop; each side owns one atomic index on its own
// cache line and keeps a private copy of the other's, so the common case touches no shared line.
// Real-time safety: try_push()/try_pop()/pop_batch() are wait-free, never allocate, never block
// and never make a system call. All storage is allocated (and zero-filled, so the pages are
// touched before mlockall / first use) in the constructor.
// Capacity: a power of two >= 2, fixed at compile time (SpscRing<T, N>) or at construction
// (SpscRing<T> / SpscRing<T, kDynamicCapacity>, rounded up to a power of two).
#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <memory>
#include <new>
#include <span>
#include <stdexcept>
#include <type_traits>

namespace hystbench::daemon {

inline constexpr std::size_t kCacheLineSize = 64;
inline constexpr std::size_t kDynamicCapacity = 0;

template <typename T, std::size_t N = kDynamicCapacity>
class SpscRing {
  static_assert(std::is_trivially_copyable_v<T>, "SpscRing holds trivially copyable records");
  static_assert(N == kDynamicCapacity || (N >= 2 && std::has_single_bit(N)),
                "SpscRing capacity must be a power of two >= 2");

 public:
  /// Fixed capacity N.
  SpscRing() noexcept requires(N != kDynamicCapacity) = default;
  /// Capacity chosen at run time: rounded up to a power of two, in [2, 2^40].
  /// Throws std::invalid_argument outside that range.
  explicit SpscRing(std::size_t capacity) requires(N == kDynamicCapacity)
      : mask_(checked_capacity(capacity) - 1), storage_(std::make_unique<T[]>(mask_ + 1)) {}

  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  std::size_t capacity() const noexcept { return mask_ + 1; }

  /// Producer only. Copies `value` in; false (nothing stored) when the ring is full.
  bool try_push(const T& value) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - producer_.head_cache > mask_) {
      producer_.head_cache = head_.load(std::memory_order_acquire);
      if (tail - producer_.head_cache > mask_) return false;
    }
    data()[tail & mask_] = value;
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Producer only. Copies every one of `values` in, or none when they do not all fit: a
  /// consumer sees them all at once (a row of several records stays whole).
  bool try_push_all(std::span<const T> values) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail + values.size() - producer_.head_cache > mask_ + 1) {
      producer_.head_cache = head_.load(std::memory_order_acquire);
      if (tail + values.size() - producer_.head_cache > mask_ + 1) return false;
    }
    T* buffer = data();
    for (std::size_t i = 0; i < values.size(); ++i) buffer[(tail + i) & mask_] = values[i];
    tail_.store(tail + values.size(), std::memory_order_release);
    return true;
  }

  /// Consumer only. Moves the oldest record to `out`; false when the ring is empty.
  bool try_pop(T& out) noexcept { return pop_batch(std::span<T>(&out, 1)) == 1; }

  /// Consumer only. Moves up to out.size() oldest records to `out`, in order; returns how many.
  std::size_t pop_batch(std::span<T> out) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    std::size_t available = consumer_.tail_cache - head;
    if (available < out.size()) {
      consumer_.tail_cache = tail_.load(std::memory_order_acquire);
      available = consumer_.tail_cache - head;
    }
    const std::size_t n = std::min(available, out.size());
    const T* buffer = data();
    for (std::size_t i = 0; i < n; ++i) out[i] = buffer[(head + i) & mask_];
    if (n != 0) head_.store(head + n, std::memory_order_release);
    return n;
  }

  /// Records in the ring right now; exact from either side when the other is idle, otherwise a
  /// value that was true at some instant during the call.
  std::size_t size_approx() const noexcept {
    const std::size_t head = head_.load(std::memory_order_acquire);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    return tail - head;
  }
  bool empty_approx() const noexcept { return size_approx() == 0; }

 private:
  static std::size_t checked_capacity(std::size_t capacity) {
    if (capacity < 2 || capacity > (std::size_t{1} << 40)) {
      throw std::invalid_argument("SpscRing capacity must be in [2, 2^40]");
    }
    return std::bit_ceil(capacity);
  }

  static constexpr bool kFixed = N != kDynamicCapacity;
  using Storage = std::conditional_t<kFixed, std::array<T, (kFixed ? N : 1)>, std::unique_ptr<T[]>>;

  T* data() noexcept {
    if constexpr (kFixed) {
      return storage_.data();
    } else {
      return storage_.get();
    }
  }
  const T* data() const noexcept { return const_cast<SpscRing*>(this)->data(); }

  // Written by the consumer, read by the producer.
  alignas(kCacheLineSize) std::atomic<std::size_t> head_{0};
  // Consumer-private copy of tail_.
  alignas(kCacheLineSize) struct { std::size_t tail_cache = 0; } consumer_;
  // Written by the producer, read by the consumer.
  alignas(kCacheLineSize) std::atomic<std::size_t> tail_{0};
  // Producer-private copy of head_.
  alignas(kCacheLineSize) struct { std::size_t head_cache = 0; } producer_;
  // Read-only after construction.
  alignas(kCacheLineSize) std::size_t mask_ = kFixed ? N - 1 : 0;
  Storage storage_{};
};

}  // namespace hystbench::daemon
