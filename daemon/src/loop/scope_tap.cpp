#include "hystbench/daemon/loop/scope_tap.hpp"

#include <stdexcept>

namespace hystbench::daemon {

namespace {
std::uint32_t checked_decimation(std::uint32_t decimation) {
  if (decimation == 0) throw std::invalid_argument("scope tap: decimation must be >= 1");
  return decimation;
}
}  // namespace

ScopeTap::ScopeTap(std::uint32_t decimation, std::size_t capacity)
    : decimation_(checked_decimation(decimation)), ring_(capacity) {}

}  // namespace hystbench::daemon
