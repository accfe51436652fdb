#include "hystbench/compensation/dynamics_inversion.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "details/validate.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::compensation {

DynamicsInversion::DynamicsInversion(const ActuatorModel& model, double dt_s, double bandwidth_hz)
    : dt_(dt_s) {
  details::require(std::isfinite(dt_s) && dt_s > 0.0, "dynamics inversion needs a period > 0");
  delay_samples_ = model.delay_s() / dt_s;  // a fraction of a sample is previewed too
  lead_s_ = delay_samples_ * dt_s;
  if (model.dynamics()) {
    p_ = *model.dynamics();
    dynamics_ = true;
    const double wn = 2.0 * std::numbers::pi * p_.natural_frequency_hz;
    c1_ = 2.0 * p_.damping_ratio / wn;
    c2_ = 1.0 / (wn * wn);
    if (p_.feedforward_bandwidth_hz > 0.0) {
      bandwidth_hz_ = p_.feedforward_bandwidth_hz;
    } else if (bandwidth_hz > 0.0) {
      bandwidth_hz_ = bandwidth_hz;
    } else {
      bandwidth_hz_ = std::min(0.25 / dt_s, 2.0 * p_.natural_frequency_hz);
    }
    h_s_ = std::max(dt_s, 1.0 / (std::numbers::pi * bandwidth_hz_));
    inv_2h_ = 1.0 / (2.0 * h_s_);
    inv_h2_ = 1.0 / (h_s_ * h_s_);
    // The model's dynamics are discretised for a zero-order-held input and report the position
    // at the end of the held sample: the held value best stands for the continuous input half a
    // sample before the output it makes (a half-sample error of the lead is tens of times the
    // tracking error at 500 Hz: DynamicsInversion's tests check the lead).
    lead_s_ -= 0.5 * dt_s;
  }
  preview_ = std::max(0, static_cast<int>(std::ceil((lead_s_ + h_s_) / dt_s - 1e-9)));
}

std::string DynamicsInversion::describe() const {
  std::string s;
  if (delay_samples_ > 0) {
    s += "delay " + significant(delay_samples_, 6) + " samples (reference previewed)";
  }
  if (dynamics_) {
    if (!s.empty()) s += ", ";
    s += "dynamics " + significant(p_.natural_frequency_hz, 6) + " Hz / " +
         significant(p_.damping_ratio, 6) + " (reference derivatives, rolled off above " +
         significant(bandwidth_hz_, 6) + " Hz)";
  }
  return s.empty() ? "nothing (a static model)" : s;
}

}  // namespace hystbench::compensation
