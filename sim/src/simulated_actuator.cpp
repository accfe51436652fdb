#include "hystbench/sim/simulated_actuator.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"

namespace hystbench::sim {

namespace {

namespace hc = compensation;

void validate_sample_period(double dt_s) {
  if (!(std::isfinite(dt_s) && dt_s > 0.0)) throw std::invalid_argument("dt_s: must be > 0");
}

hc::ModifiedPiParameters modified_pi_parameters(const SimulatedActuatorConfig::Hysteresis& h) {
  hc::ModifiedPiParameters p;
  p.play = {h.play_thresholds_v, h.play_weights_um_per_v, h.play_offset_um};
  p.dead_zone = {h.dead_zone_thresholds_um, h.dead_zone_weights};
  p.center = h.dead_zone_center_um;
  return p;
}

/// A straight line through the hysteresis' periodic major-loop end points.
std::unique_ptr<hc::HysteresisModel> linear_equivalent(const hc::ModifiedPiParameters& p,
                                                       const SimulatedActuatorConfig::Input& in) {
  hc::ModifiedPiModel loop(p);
  loop.reset(in.min_v);
  loop.step(in.max_v);
  const double y_bottom = loop.step(in.min_v);
  const double y_top = loop.step(in.max_v);
  const double gain = (y_top - y_bottom) / (in.max_v - in.min_v);
  return std::make_unique<hc::PiModel>(hc::PiParameters{{0.0}, {gain}, y_bottom - gain * in.min_v});
}

std::unique_ptr<hc::HysteresisModel> make_hysteresis(const SimulatedActuatorConfig& c,
                                                     double dt_s) {
  hc::ModifiedPiParameters mpi = modified_pi_parameters(c.hysteresis);
  if (!c.hysteresis.enabled) return linear_equivalent(mpi, c.input);
  if (!c.rate_dependence.enabled) return std::make_unique<hc::ModifiedPiModel>(std::move(mpi));
  hc::RateDependentPiParameters p{std::move(mpi), c.rate_dependence.rate_coefficients,
                                  c.rate_dependence.max_rate_v_per_s};
  p.rate_law = c.rate_dependence.rate_law;
  return std::make_unique<hc::RateDependentPiModel>(std::move(p), dt_s);
}

}  // namespace

compensation::ActuatorModel make_truth_model(const SimulatedActuatorConfig& config, double dt_s) {
  validate(config);
  validate_sample_period(dt_s);
  hc::ActuatorModel model(make_hysteresis(config, dt_s));
  if (config.creep.enabled) {
    model.set_creep(
        hc::CreepParameters{config.creep.time_constants_s, config.creep.gains_um_per_v});
  }
  if (config.dynamics.enabled) {
    model.set_dynamics(hc::DynamicsParameters{config.dynamics.natural_frequency_hz,
                                              config.dynamics.damping_ratio});
  }
  if (config.delay.enabled) model.set_delay(config.delay.delay_s);
  model.configure(dt_s);
  model.input_min = config.input.min_v;
  model.input_max = config.input.max_v;
  return model;
}

SimulatedActuator::SimulatedActuator(const SimulatedActuatorConfig& config, double dt_s)
    : config_(config),
      dt_s_(dt_s),
      truth_(make_truth_model(config, dt_s)),
      dac_(config.dac),
      adc_(config.adc),
      drift_(config.thermal_drift, dt_s),
      noise_rng_(config.sensor_noise.seed) {
  reset(config_.input.min_v);
}

double SimulatedActuator::condition_input(double u_volts) const noexcept {
  double u = std::isfinite(u_volts) ? u_volts : applied_input_;
  if (config_.input_saturation.enabled) u = std::clamp(u, config_.input.min_v, config_.input.max_v);
  return dac_.apply(u);
}

double SimulatedActuator::clamp_displacement(double x_um) const noexcept {
  if (!config_.displacement_saturation.enabled) return x_um;
  return std::clamp(x_um, config_.displacement_saturation.min_um,
                    config_.displacement_saturation.max_um);
}

double SimulatedActuator::step(double u_volts) noexcept {
  applied_input_ = condition_input(u_volts);
  true_position_ = clamp_displacement(truth_.step(applied_input_) + drift_.step());
  double measured = true_position_;
  if (config_.sensor_noise.enabled) {
    measured += config_.sensor_noise.rms_um * unit_normal_(noise_rng_);
  }
  return adc_.apply(measured);
}

void SimulatedActuator::reset(double u0) noexcept {
  applied_input_ = std::isfinite(u0) ? u0 : config_.input.min_v;
  applied_input_ = condition_input(applied_input_);
  truth_.reset(applied_input_);
  drift_.reset();
  noise_rng_.seed(config_.sensor_noise.seed);
  unit_normal_.reset();
  true_position_ = clamp_displacement(truth_.peek_static(applied_input_));
}

}  // namespace hystbench::sim
