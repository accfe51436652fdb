#include "hystbench/sim/major_loop_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "hystbench/sim/signal_generator.hpp"
#include "hystbench/sim/simulated_actuator.hpp"

namespace hystbench::sim {

MajorLoopMetrics measure_major_loop(const SimulatedActuatorConfig& config, double dt_s,
                                    double frequency_hz, int cycles) {
  if (!(std::isfinite(frequency_hz) && frequency_hz > 0.0)) {
    throw std::invalid_argument("frequency_hz: must be > 0");
  }
  if (cycles < 2) throw std::invalid_argument("cycles: must be >= 2");
  SimulatedActuator actuator(config, dt_s);
  const double u_mid = 0.5 * (actuator.input_min() + actuator.input_max());

  SignalSpec spec;
  spec.amplitude = 0.5 * (actuator.input_max() - actuator.input_min());
  spec.offset = u_mid;
  spec.frequency_hz = frequency_hz;
  spec.phase_rad = -0.5 * std::numbers::pi;  // starts at input_min
  spec.duration_s = cycles / frequency_hz;
  const auto u = sample_signal(*make_signal_generator(spec), dt_s);
  const auto last_cycle_begin =
      u.size() - static_cast<std::size_t>(std::llround(1.0 / (frequency_hz * dt_s)));

  MajorLoopMetrics m;
  m.min_um = std::numeric_limits<double>::infinity();
  m.max_um = -m.min_um;
  double ascending_um = std::numeric_limits<double>::quiet_NaN();
  double descending_um = ascending_um;
  double y_previous = 0.0;
  actuator.reset(u.front());
  for (std::size_t k = 0; k < u.size(); ++k) {
    actuator.step(u[k]);
    const double y = actuator.true_position();
    if (k > last_cycle_begin) {
      m.min_um = std::min(m.min_um, y);
      m.max_um = std::max(m.max_um, y);
      // Linear interpolation of the branch at the sample pair that straddles mid-input.
      const auto at_mid = [&] {
        return y_previous + (u_mid - u[k - 1]) / (u[k] - u[k - 1]) * (y - y_previous);
      };
      if (u[k - 1] < u_mid && u[k] >= u_mid) ascending_um = at_mid();
      if (u[k - 1] > u_mid && u[k] <= u_mid) descending_um = at_mid();
    }
    y_previous = y;
  }
  m.range_um = m.max_um - m.min_um;
  m.width_at_mid_um = descending_um - ascending_um;
  m.hysteresis_percent = 100.0 * m.width_at_mid_um / m.range_um;
  return m;
}

}  // namespace hystbench::sim
