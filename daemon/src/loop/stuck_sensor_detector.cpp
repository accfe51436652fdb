#include "hystbench/daemon/loop/stuck_sensor_detector.hpp"

#include <algorithm>
#include <cmath>

namespace hystbench::daemon {

namespace {
/// Counts of movement required right after a reversal, where the gain is about half its mean.
constexpr double kCountsAfterReversal = 2.0;
}  // namespace

StuckSensorDetector::StuckSensorDetector(StuckSensorOptions options) noexcept
    : options_(options), latency_ticks_(options.latency_ticks) {
  span_v_ = options_.output_span_v;
  if (options_.resolution_um > 0.0 && options_.gain_um_per_v > 0.0) {
    span_v_ =
        std::max(span_v_, kCountsAfterReversal * options_.resolution_um / options_.gain_um_per_v);
  }
}

void StuckSensorDetector::reset(std::uint64_t latency_ticks) noexcept {
  have_ = false;
  latency_ticks_ = latency_ticks;
}

void StuckSensorDetector::advance(double u) noexcept {
  if (moved_) {
    ++since_moved_;
  } else {
    moved_ = std::abs(u - u_changed_) >= span_v_;
  }
}

void StuckSensorDetector::stale(double u) noexcept {
  if (options_.ticks != 0 && have_) advance(u);
}

bool StuckSensorDetector::update(double u, double y, std::uint64_t response_ticks) noexcept {
  if (options_.ticks == 0) return false;
  if (!have_ || y != y_) {
    have_ = true;
    y_ = y;
    u_changed_ = u;
    moved_ = false;
    since_moved_ = 0;
    return false;
  }
  advance(u);
  return moved_ && since_moved_ >= options_.ticks + latency_ticks_ + response_ticks;
}

}  // namespace hystbench::daemon
