#pragma once
// The simulated actuator, or a simulated stage of several axes, advancing with the wall clock,
// for the device simulators: before each request the plant is stepped at its own sample rate
// up to now with the outputs it had, then the request may change an axis's output (sample and
// hold, as a real DAQ or amplifier). Long gaps are capped at max_catch_up_s of simulated time.
// Units: V in, µm out; `axis` in [0, axes()).
#include <algorithm>
#include <cstdint>
#include <ctime>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "hystbench/sim/simulated_stage.hpp"

namespace hystbench::apps {

class RealtimePlant {
 public:
  /// A stage of one axis: exactly the simulated actuator of `config`.
  RealtimePlant(const sim::SimulatedActuatorConfig& config, double rate_hz,
                double max_catch_up_s = 1.0)
      : RealtimePlant(one_axis(config), rate_hz, max_catch_up_s) {}
  RealtimePlant(const sim::SimulatedStageConfig& config, double rate_hz,
                double max_catch_up_s = 1.0)
      : stage_(config, 1.0 / rate_hz),
        period_ns_(static_cast<std::int64_t>(1e9 / rate_hz)),
        max_steps_(static_cast<std::uint64_t>(max_catch_up_s * rate_hz)),
        output_v_(stage_.axes()),
        position_um_(stage_.axes()) {
    for (std::size_t i = 0; i < axes(); ++i) output_v_[i] = input_min(i);
    stage_.reset(output_v_);
    stage_.step(output_v_, position_um_);
    last_ns_ = now_ns();
  }
  static std::int64_t now_ns() {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
  }
  /// Steps the plant up to now with the held outputs.
  void advance() {
    const std::int64_t now = now_ns();
    auto steps = static_cast<std::uint64_t>((now - last_ns_) / period_ns_);
    last_ns_ += static_cast<std::int64_t>(steps) * period_ns_;
    if (steps > max_steps_) {
      steps = max_steps_;
      last_ns_ = now;
    }
    for (std::uint64_t i = 0; i < steps; ++i) stage_.step(output_v_, position_um_);
    samples_ += steps;
  }
  std::size_t axes() const { return stage_.axes(); }
  void set_output(double v, std::size_t axis = 0) {
    output_v_[axis] = std::clamp(v, input_min(axis), input_max(axis));
  }
  double output_v(std::size_t axis = 0) const { return output_v_[axis]; }
  double position_um(std::size_t axis = 0) const { return position_um_[axis]; }
  std::uint64_t samples() const { return samples_; }
  double input_min(std::size_t axis = 0) const { return stage_.axis(axis).input_min(); }
  double input_max(std::size_t axis = 0) const { return stage_.axis(axis).input_max(); }

 private:
  static sim::SimulatedStageConfig one_axis(const sim::SimulatedActuatorConfig& config) {
    sim::SimulatedStageConfig stage;
    stage.axes.push_back({"x", config});
    stage.coupling.enabled = false;
    return stage;
  }

  sim::SimulatedStage stage_;
  std::int64_t period_ns_;
  std::uint64_t max_steps_;
  std::int64_t last_ns_ = 0;
  std::vector<double> output_v_;
  std::vector<double> position_um_;
  std::uint64_t samples_ = 0;
};

/// The device simulators' plant: the stage of `stage_file` ("xy": SimulatedStageConfig::xy(),
/// else a JSON file in the [driver.loopback.stage] form) when given, else the actuator of
/// `actuator_file` (a JSON file in the sim format; the default actuator when empty). Throws
/// naming what is wrong with the file.
inline std::unique_ptr<RealtimePlant> make_plant(const std::string& stage_file,
                                                 const std::string& actuator_file, double rate_hz) {
  if (stage_file == "xy") {
    return std::make_unique<RealtimePlant>(sim::SimulatedStageConfig::xy(), rate_hz);
  }
  if (!stage_file.empty()) {
    std::ifstream in(stage_file);
    if (!in) throw std::runtime_error("cannot open the file (give \"xy\" or a JSON file)");
    return std::make_unique<RealtimePlant>(sim::stage_from_json(nlohmann::json::parse(in)),
                                           rate_hz);
  }
  sim::SimulatedActuatorConfig cfg;
  if (!actuator_file.empty()) {
    std::ifstream in(actuator_file);
    cfg = sim::from_json(nlohmann::json::parse(in));
  }
  return std::make_unique<RealtimePlant>(cfg, rate_hz);
}

}  // namespace hystbench::apps
