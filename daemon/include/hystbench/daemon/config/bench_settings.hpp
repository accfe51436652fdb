#pragma once
// What the bench runs with: the loop's options, the driver, the folders, the reference range
// without a model and the defaults of identify, track's feedback and preconditioning. Built from
// the configuration file by bench_settings_from() (daemon_settings.hpp) or by a test directly.
// Plain data, read by the service and the run builders; never changed while the bench runs.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hystbench/daemon/config/config.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/sim/identification_excitation.hpp"

namespace hystbench::daemon {

struct BenchSettings {
  BenchLoopOptions loop;
  std::string driver_type = "loopback";
  /// A stage's axis names, in the driver's order (the loopback's [driver.loopback.stage]); empty:
  /// one axis. The driver must serve as many.
  std::vector<std::string> axes;
  nlohmann::json driver_params = nlohmann::json::object();
  std::string log_dir = "/var/lib/hystbench/logs";
  std::string model_dir = "/var/lib/hystbench/models";
  std::size_t log_ring_capacity = std::size_t{1} << 16;
  /// Reference range without a model [µm]; with a model its major loop defines the range.
  double y_min = 0.0;
  double y_max = 0.0;
  /// identify's defaults (a request overrides model, operators, dead_zones and the span): the
  /// configuration's [identify] section, the same struct and defaults, so tests identify as the
  /// daemon does.
  IdentifySection identify;
  /// The excitation's other segments (minor loops, rates, holds, reversals); `identify` sets
  /// its major-loop and preconditioning options. The standard one by default.
  sim::IdentificationExcitationOptions identify_excitation;
  /// track's feedback: the configuration's [pid] section (no gains = designed per run on the
  /// stage's measured frequency responses, compensation::design_loop, unless a request gives kp,
  /// ki or kd; given ones are checked against its targets).
  PidSection pid;
  /// Open-loop sweep to u_max and back to u_min before every track run [s], so the actuator's
  /// hysteresis state is known and the inverse starts consistent with it.
  double precondition_s = 1.0;
  /// Roll-off of the feedforward's dynamics inversion [Hz]; 0 = the default (DynamicsInversion).
  double feedforward_bandwidth_hz = 0.0;
  /// The effective configuration, returned by config.get.
  nlohmann::json config_json = nlohmann::json::object();
};

}  // namespace hystbench::daemon
