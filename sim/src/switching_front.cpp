#include "hystbench/sim/switching_front.hpp"

#include <stdexcept>

namespace hystbench::sim {

SwitchingFront::SwitchingFront(double lag_v, double exponent, double dt_s) : exponent_(exponent) {
  if (!(std::isfinite(lag_v) && lag_v > 0.0)) {
    throw std::invalid_argument("switching_lag_v: must be > 0");
  }
  if (!(std::isfinite(exponent) && exponent >= 1.0 && exponent <= 4.0)) {
    throw std::invalid_argument("switching_exponent: must be in [1, 4]");
  }
  if (!(std::isfinite(dt_s) && dt_s > 0.0)) throw std::invalid_argument("dt_s: must be > 0");
  k_dt_ = 1000.0 / std::pow(lag_v, exponent) * dt_s;
  decay_ = std::exp(-k_dt_);
}

}  // namespace hystbench::sim
