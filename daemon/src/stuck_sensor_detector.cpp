#include "hystbench/daemon/stuck_sensor_detector.hpp"

#include <algorithm>

namespace hystbench::daemon {

bool StuckSensorDetector::update(double u, double y) noexcept {
  if (options_.ticks == 0) return false;
  if (!have_ || y != y_) {
    have_ = true;
    y_ = y;
    u_lo_ = u_hi_ = u;
    repeats_ = 0;
    return false;
  }
  ++repeats_;
  u_lo_ = std::min(u_lo_, u);
  u_hi_ = std::max(u_hi_, u);
  return repeats_ >= options_.ticks && u_hi_ - u_lo_ >= options_.output_span_v;
}

}  // namespace hystbench::daemon
