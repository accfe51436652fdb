#pragma once
// The simulated actuator advancing with the wall clock, for the device simulators: before each
// request the plant is stepped at its own sample rate up to now with the output it had, then the
// request may change the output (sample and hold, as a real DAQ or amplifier). Long gaps are
// capped at max_catch_up_s of simulated time.
#include <algorithm>
#include <cstdint>
#include <ctime>
#include <memory>

#include "hystbench/sim/simulated_actuator.hpp"

namespace hystbench::apps {

class RealtimePlant {
 public:
  RealtimePlant(const sim::SimulatedActuatorConfig& config, double rate_hz,
                double max_catch_up_s = 1.0)
      : actuator_(config, 1.0 / rate_hz),
        period_ns_(static_cast<std::int64_t>(1e9 / rate_hz)),
        max_steps_(static_cast<std::uint64_t>(max_catch_up_s * rate_hz)) {
    output_v_ = actuator_.input_min();
    actuator_.reset(output_v_);
    position_um_ = actuator_.step(output_v_);
    last_ns_ = now_ns();
  }
  static std::int64_t now_ns() {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
  }
  /// Steps the plant up to now with the held output.
  void advance() {
    const std::int64_t now = now_ns();
    auto steps = static_cast<std::uint64_t>((now - last_ns_) / period_ns_);
    last_ns_ += static_cast<std::int64_t>(steps) * period_ns_;
    if (steps > max_steps_) {
      steps = max_steps_;
      last_ns_ = now;
    }
    for (std::uint64_t i = 0; i < steps; ++i) position_um_ = actuator_.step(output_v_);
    samples_ += steps;
  }
  void set_output(double v) { output_v_ = std::clamp(v, input_min(), input_max()); }
  double output_v() const { return output_v_; }
  double position_um() const { return position_um_; }
  std::uint64_t samples() const { return samples_; }
  double input_min() const { return actuator_.input_min(); }
  double input_max() const { return actuator_.input_max(); }

 private:
  sim::SimulatedActuator actuator_;
  std::int64_t period_ns_;
  std::uint64_t max_steps_;
  std::int64_t last_ns_ = 0;
  double output_v_ = 0.0;
  double position_um_ = 0.0;
  std::uint64_t samples_ = 0;
};

}  // namespace hystbench::apps
