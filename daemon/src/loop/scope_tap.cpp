#include "hystbench/daemon/loop/scope_tap.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hystbench::daemon {

namespace {
std::uint32_t checked_decimation(std::uint32_t decimation) {
  if (decimation == 0) throw std::invalid_argument("scope tap: decimation must be >= 1");
  return decimation;
}
}  // namespace

std::uint32_t ScopeTap::decimation_for(double loop_rate_hz, double scope_rate_hz) noexcept {
  return static_cast<std::uint32_t>(std::max(1.0, std::round(loop_rate_hz / scope_rate_hz)));
}

ScopeTap::ScopeTap(std::uint32_t decimation, std::size_t capacity)
    : decimation_(checked_decimation(decimation)), ring_(capacity) {}

}  // namespace hystbench::daemon
