#include "hystbench/daemon/daemon_settings.hpp"

#include <algorithm>
#include <cmath>

namespace hystbench::daemon {

BenchSettings bench_settings_from(const DaemonConfig& c) {
  BenchSettings s;
  s.loop.rate_hz = c.loop.rate_hz;
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
  // The loopback driver's actuator is the [actuator] table unless the driver table names one.
  if (c.driver.type == "loopback" && !s.driver_params.contains("actuator")) {
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
  s.identify_model = c.identify.model;
  s.identify_operators = c.identify.operators;
  s.identify_dead_zones = c.identify.dead_zones;
  s.identify_u_min = c.identify.offset_v - c.identify.amplitude_v;
  s.identify_u_max = c.identify.offset_v + c.identify.amplitude_v;
  s.identify_major_loop_hz = c.identify.frequency_hz;
  s.identify_major_loop_cycles = c.identify.cycles;
  s.identify_precondition_s = c.identify.precondition_s;
  s.identify_settle_s = c.identify.settle_s;
  s.identify_heldout_fraction = c.identify.heldout_fraction;
  s.identify_fit_rate_hz = c.identify.fit_rate_hz;
  s.pid_derived = !c.pid.kp && !c.pid.ki && !c.pid.kd;
  s.pid = {c.pid.kp.value_or(0.0),
           c.pid.ki.value_or(0.0),
           c.pid.kd.value_or(0.0),
           c.pid.derivative_filter_hz,
           c.pid.u_fb_min,
           c.pid.u_fb_max,
           c.pid.output_filter_hz.value_or(0.0)};
  s.pid_bandwidth_hz = c.pid.bandwidth_hz.value_or(0.0);
  s.pid_output_filter_hz = c.pid.output_filter_hz;
  s.config_json = to_json(c);
  return s;
}

}  // namespace hystbench::daemon
