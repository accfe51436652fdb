#pragma once
// A 32-bit atomic word that threads wait on (Linux futex): the loop thread bumps it without a
// lock and wakes the waiters with one non-blocking system call (real-time safe); the control
// thread waits with a timeout. What a condition variable does, without the loop taking a mutex.
#include <atomic>
#include <chrono>
#include <cstdint>

namespace hystbench::daemon::details {

/// Blocks while `word` holds `expected`, at most `timeout`; may return early (spuriously).
void futex_wait(const std::atomic<std::uint32_t>& word, std::uint32_t expected,
                std::chrono::nanoseconds timeout) noexcept;
/// Wakes every thread blocked in futex_wait() on `word`. Real-time safe.
void futex_wake_all(std::atomic<std::uint32_t>& word) noexcept;

}  // namespace hystbench::daemon::details
