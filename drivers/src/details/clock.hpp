#pragma once
// The monotonic clock in nanoseconds (vDSO: no system call, real-time safe).
#include <cstdint>
#include <ctime>

namespace hystbench::drivers::details {

inline std::int64_t monotonic_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

}  // namespace hystbench::drivers::details
