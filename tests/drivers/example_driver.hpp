#pragma once
// docs/drivers.md shows this file: a whole driver, a first-order actuator in memory whose sensor
// answers every second tick. One line in drivers/src/driver_registry.cpp would register it:
//   {"first_order", "a first-order actuator in memory", make_interface<FirstOrderDriver>},
#include <cmath>
#include <string>

#include "hystbench/drivers/driver_interface.hpp"

namespace example {
using namespace hystbench::drivers;

class FirstOrderDriver final : public DriverInterface {
 public:
  enum class Fault : int { kNone = 0, kOverTravel };

  Result on_configure(const nlohmann::json& params, double rate_hz) override {
    for (const auto& [key, value] : params.items()) {
      if (key != "gain_um_per_v")
        return Result::failure("driver.first_order." + key + ": unknown key");
    }
    gain_ = params.value("gain_um_per_v", 0.2);
    alpha_ = 1.0 - std::exp(-2.0 * M_PI * 50.0 / rate_hz);  // 50 Hz bandwidth
    return Result::success();
  }
  Result on_activate() override {
    y_ = u_ = 0.0;  // from rest
    tick_ = 0;
    return Result::success();
  }

  DriverStatus write(double output_v) noexcept override {
    u_ = output_v;
    return DriverStatus::kOk;
  }
  DriverStatus read(Measurement& out) noexcept override {
    y_ += alpha_ * (gain_ * u_ - y_);
    if (y_ > 25.0) {
      report_fault(Fault::kOverTravel, std::lround(y_));  // the framework calls on_error()
      return DriverStatus::kFault;
    }
    if (++tick_ % 2 == 1) return DriverStatus::kStale;  // the framework repeats and ages
    out.position_um = y_;
    return DriverStatus::kOk;
  }
  DriverStatus safe_state() noexcept override {
    u_ = 0.0;
    return DriverStatus::kOk;
  }

  DriverInfo info() const noexcept override {
    return {.max_rate_hz = 10000.0, .output_max_v = 150.0, .max_stale_reads = 5};
  }
  std::string_view type() const noexcept override { return "first_order"; }
  std::string describe_fault(int /*cause*/, std::int64_t um) const override {
    return "over travel: " + std::to_string(um) + " um (at most 25 um)";
  }

 private:
  double gain_ = 0.2, alpha_ = 0.0, y_ = 0.0, u_ = 0.0;
  long tick_ = 0;
};

}  // namespace example
