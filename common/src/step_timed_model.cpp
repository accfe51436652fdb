#include "hystbench/common/step_timed_model.hpp"

#include <algorithm>
#include <string>

#include "hystbench/compensation/number_text.hpp"
#include "hystbench/compensation/step_timing.hpp"

namespace hystbench::common {

namespace hc = compensation;
using nlohmann::json;

json time_on_steps(hc::ActuatorModel& model, std::span<const double> u, std::span<const double> y,
                   double dt_s, double exchange_s) {
  if (!model.dynamics()) return nullptr;
  const hc::DynamicsParameters before = *model.dynamics();
  const double delay_before = (model.delay_s() + exchange_s) / dt_s;
  const auto timing = hc::fit_step_timing(
      u, y, dt_s, {before.natural_frequency_hz, before.damping_ratio, delay_before});
  if (!timing) return nullptr;
  hc::DynamicsParameters after = before;
  after.natural_frequency_hz = timing->natural_frequency_hz;
  after.damping_ratio = timing->damping_ratio;
  model.set_dynamics(after);
  model.set_delay(std::max(0.0, timing->delay_samples * dt_s - exchange_s));
  return {{"steps", timing->steps},
          {"rms_um", timing->rms},
          {"natural_frequency_hz", after.natural_frequency_hz},
          {"damping_ratio", after.damping_ratio},
          {"delay_samples", timing->delay_samples},
          {"from_record",
           {{"natural_frequency_hz", before.natural_frequency_hz},
            {"damping_ratio", before.damping_ratio},
            {"delay_samples", delay_before}}}};
}

std::string timing_text(const json& t) {
  return "timed on " + std::to_string(t["steps"].get<std::size_t>()) +
         " step responses: " + hc::significant(t["natural_frequency_hz"].get<double>(), 4) +
         " Hz, damping " + hc::significant(t["damping_ratio"].get<double>(), 3) + ", delay " +
         hc::significant(t["delay_samples"].get<double>(), 3) + " samples";
}

}  // namespace hystbench::common
