#include "hystbench/daemon/config/daemon_settings.hpp"

#include <algorithm>
#include <cmath>

#include "hystbench/sim/simulated_stage_config.hpp"

namespace hystbench::daemon {

BenchSettings bench_settings_from(const DaemonConfig& c) {
  BenchSettings s;
  s.loop.rate_hz = c.loop.rate_hz;
  s.loop.clock = c.loop.clock == "simulated" ? LoopClock::kSimulated : LoopClock::kWall;
  s.loop.realtime.fifo = c.loop.realtime;
  s.loop.realtime.priority = c.loop.priority;
  s.loop.realtime.cpu = c.loop.cpu;
  s.loop.realtime.lock_memory = c.loop.lock_memory;
  s.loop.overrun_budget = c.loop.overrun_budget;
  s.loop.limits = {c.limits.u_min, c.limits.u_max, c.limits.slew_v_per_s};
  s.loop.fatal_on_limit = c.limits.fatal_on_limit;
  if (c.loop.stuck_sensor_ms > 0.0) {
    s.loop.stuck_sensor.ticks = static_cast<std::uint64_t>(
        std::max(2.0, std::round(c.loop.stuck_sensor_ms * 1e-3 * c.loop.rate_hz)));
  }
  s.loop.stuck_sensor.output_span_v = c.loop.stuck_sensor_span * (c.limits.u_max - c.limits.u_min);
  if (c.limits.y_min && c.limits.y_max && c.limits.u_max > c.limits.u_min) {
    s.loop.stuck_sensor.gain_um_per_v =
        std::abs(*c.limits.y_max - *c.limits.y_min) / (c.limits.u_max - c.limits.u_min);
  }
  s.driver_type = c.driver.type;
  s.driver_params = c.driver.params();
  // The loopback driver's actuator is the [actuator] table unless the driver table names one
  // or simulates a stage of several axes, whose names the bench takes; another driver of
  // several axes names them in its `axes` key (its configure checks them).
  if (c.driver.type == "loopback" && s.driver_params.contains("stage")) {
    for (const auto& axis : sim::stage_from_json(s.driver_params["stage"]).axes) {
      s.axes.push_back(axis.name);
    }
    if (s.axes.size() == 1) s.axes.clear();
  } else if (const auto axes = s.driver_params.find("axes");
             axes != s.driver_params.end() && axes->is_array() && axes->size() > 1) {
    for (const auto& name : *axes) {
      if (name.is_string()) s.axes.push_back(name.get<std::string>());
    }
  } else if (c.driver.type == "loopback" && !s.driver_params.contains("actuator")) {
    s.driver_params["actuator"] = c.actuator;
  }
  s.log_dir = c.daemon.log_dir;
  s.model_dir = c.daemon.model_dir;
  s.log_ring_capacity = c.loop.ring_capacity;
  s.feedforward_bandwidth_hz = c.loop.feedforward_bandwidth_hz;
  if (c.limits.y_min && c.limits.y_max) {
    s.y_min = *c.limits.y_min;
    s.y_max = *c.limits.y_max;
  }
  s.identify = c.identify;
  s.pid = c.pid;
  s.config_json = to_json(c);
  return s;
}

}  // namespace hystbench::daemon
