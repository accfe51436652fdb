#include "hystbench/sim/rate_widened_play.hpp"

#include <cmath>
#include <stdexcept>

namespace hystbench::sim {

RateWidenedPlay::RateWidenedPlay(double widening_s, double filter_s, double dt_s)
    : widening_s_(widening_s) {
  if (!(std::isfinite(widening_s) && widening_s >= 0.0)) {
    throw std::invalid_argument("widening_s must be finite and >= 0");
  }
  if (!(std::isfinite(filter_s) && filter_s >= 0.0)) {
    throw std::invalid_argument("filter_s must be finite and >= 0");
  }
  if (!(std::isfinite(dt_s) && dt_s > 0.0)) throw std::invalid_argument("dt_s must be > 0");
  rate_.configure(filter_s, dt_s, compensation::RateLaw::kMagnitude);
}

}  // namespace hystbench::sim
