#include "hystbench/sim/simulated_actuator.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "hystbench/sim/logarithmic_creep.hpp"

namespace hystbench::sim {

namespace {

namespace hc = compensation;
using Config = SimulatedActuatorConfig;

void validate_sample_period(double dt_s) {
  if (!(std::isfinite(dt_s) && dt_s > 0.0)) throw std::invalid_argument("dt_s: must be > 0");
}

hc::ModifiedPiParameters modified_pi_parameters(const Config::Hysteresis& h) {
  hc::ModifiedPiParameters p;
  p.play = {h.play_thresholds_v, h.play_weights_um_per_v, h.play_offset_um};
  p.dead_zone = {h.dead_zone_thresholds_um, h.dead_zone_weights};
  p.center = h.dead_zone_center_um;
  return p;
}

/// The rate-independent static map of a kind-preisach hysteresis at input u, with the relays in
/// the state `relays` holds.
double preisach_map(const Config::Hysteresis& h, double u_min, double relays_um, double u) {
  return h.offset_um + h.reversible_um_per_v * (u - u_min) + relays_um;
}

/// The periodic major loop's end points (bottom, top) of the enabled hysteresis's static map.
std::pair<double, double> major_loop_ends(const Config& c) {
  if (c.hysteresis.kind == HysteresisKind::kModifiedPi) {
    hc::ModifiedPiModel loop(modified_pi_parameters(c.hysteresis));
    loop.reset(c.input.min_v);
    loop.step(c.input.max_v);
    const double bottom = loop.step(c.input.min_v);
    return {bottom, loop.step(c.input.max_v)};
  }
  PreisachHysteresis loop(preisach_parameters(c));
  loop.step(c.input.max_v);
  const double bottom =
      preisach_map(c.hysteresis, c.input.min_v, loop.step(c.input.min_v), c.input.min_v);
  return {bottom,
          preisach_map(c.hysteresis, c.input.min_v, loop.step(c.input.max_v), c.input.max_v)};
}

/// A straight line through the hysteresis' periodic major-loop end points.
std::unique_ptr<hc::HysteresisModel> linear_equivalent(const Config& c) {
  const auto [bottom, top] = major_loop_ends(c);
  const double gain = (top - bottom) / (c.input.max_v - c.input.min_v);
  return std::make_unique<hc::PiModel>(
      hc::PiParameters{{0.0}, {gain}, bottom - gain * c.input.min_v});
}

/// The hysteresis as a model: the modified PI (rate-dependent with play weights), or the linear
/// map when hysteresis is off; null for a Preisach hysteresis.
std::unique_ptr<hc::HysteresisModel> make_model(const Config& c, double dt_s) {
  if (!c.hysteresis.enabled) return linear_equivalent(c);
  if (c.hysteresis.kind == HysteresisKind::kPreisach) return nullptr;
  hc::ModifiedPiParameters mpi = modified_pi_parameters(c.hysteresis);
  if (!c.rate_dependence.enabled) return std::make_unique<hc::ModifiedPiModel>(std::move(mpi));
  hc::RateDependentPiParameters p{std::move(mpi), c.rate_dependence.rate_coefficients,
                                  c.rate_dependence.max_rate_v_per_s};
  p.rate_law = c.rate_dependence.rate_law;
  auto model = std::make_unique<hc::RateDependentPiModel>(std::move(p), dt_s);
  return model;
}

std::vector<Mode> modes_of(const Config::Dynamics& d) {
  std::vector<Mode> modes;
  for (std::size_t i = 0; i < d.natural_frequencies_hz.size(); ++i) {
    modes.push_back({d.natural_frequencies_hz[i], d.damping_ratios[i], d.mode_gains[i]});
  }
  return modes;
}

}  // namespace

compensation::ActuatorModel make_truth_model(const SimulatedActuatorConfig& config, double dt_s) {
  validate(config);
  validate_sample_period(dt_s);
  const auto no_model = [](const std::string& what) {
    throw std::invalid_argument(what +
                                ": no model family contains this truth (use "
                                "SimulatedActuatorConfig::modified_pi_truth())");
  };
  if (config.hysteresis.enabled && config.hysteresis.kind == HysteresisKind::kPreisach) {
    no_model("hysteresis.kind = \"preisach\"");
  }
  if (config.creep.enabled && config.creep.law == CreepLaw::kLogarithmic) {
    no_model("creep.law = \"logarithmic\"");
  }
  if (config.dynamics.enabled && config.dynamics.natural_frequencies_hz.size() > 1) {
    no_model("dynamics with more than one mode");
  }
  if (config.sensor_filter.enabled) no_model("sensor_filter.enabled");
  hc::ActuatorModel model(make_model(config, dt_s));
  if (config.creep.enabled) {
    model.set_creep(
        hc::CreepParameters{config.creep.time_constants_s, config.creep.gains_um_per_v});
  }
  if (config.dynamics.enabled) {
    // One mode of gain g: a model's dynamics have unit gain, so the gain must be 1 (validated).
    model.set_dynamics(hc::DynamicsParameters{config.dynamics.natural_frequencies_hz.front(),
                                              config.dynamics.damping_ratios.front()});
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
      dac_(config.dac),
      adc_(config.adc),
      drift_(config.thermal_drift, dt_s),
      noise_rng_(config.sensor_noise.seed) {
  validate(config_);
  validate_sample_period(dt_s_);
  const Config& c = config_;
  if (c.delay.enabled) {
    delay_ = hc::DelayLine(static_cast<std::size_t>(std::lround(c.delay.delay_s / dt_s_)));
  }
  model_ = make_model(c, dt_s_);
  if (!model_) {
    preisach_.emplace(preisach_parameters(c));
    if (c.rate_dependence.enabled && c.rate_dependence.mechanism == RateMechanism::kSwitchingFront)
      front_.emplace(c.rate_dependence.switching_lag_v, c.rate_dependence.switching_exponent,
                     dt_s_);
    if (c.rate_dependence.enabled &&
        c.rate_dependence.mechanism == RateMechanism::kSwitchingThresholds) {
      widened_.emplace(c.rate_dependence.threshold_rate_s, c.rate_dependence.threshold_filter_s,
                       dt_s_);
    }
  }
  if (c.creep.enabled && c.creep.law == CreepLaw::kInputLags) {
    input_creep_ = hc::CreepOperatorBank(
        hc::CreepParameters{c.creep.time_constants_s, c.creep.gains_um_per_v}, dt_s_);
  }
  if (c.creep.enabled && c.creep.law == CreepLaw::kLogarithmic) {
    displacement_creep_ = hc::CreepOperatorBank(
        logarithmic_creep_bank(c.creep.fraction_per_decade, c.creep.longest_s), dt_s_);
  }
  if (c.dynamics.enabled) {
    const std::vector<Mode> modes = modes_of(c.dynamics);
    modes_ = ModalDynamics(modes, dt_s_);
  }
  if (c.sensor_filter.enabled) {
    sensor_.emplace(
        hc::DynamicsParameters{c.sensor_filter.cutoff_hz, c.sensor_filter.damping_ratio}, dt_s_);
  }
  // The creep acts on the displacement from the relaxed bottom of the range.
  if (preisach_) {
    preisach_->reset(c.input.min_v);
    creep_reference_um_ = preisach_map(c.hysteresis, c.input.min_v, 0.0, c.input.min_v);
  } else {
    model_->reset(c.input.min_v);
    creep_reference_um_ = model_->peek(c.input.min_v);
  }
  reset(config_.input.min_v);
}

SimulatedActuator::~SimulatedActuator() = default;

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

double SimulatedActuator::static_map(double ud) noexcept {
  if (model_) return model_->step(ud);
  const double front = front_ ? front_->step(ud) : widened_ ? widened_->step(ud) : ud;
  return preisach_map(config_.hysteresis, config_.input.min_v, preisach_->step(front), ud);
}

double SimulatedActuator::stroke(double u_volts) noexcept {
  applied_input_ = condition_input(u_volts);
  const double ud = delay_.push(applied_input_);
  double y = static_map(ud);
  if (!input_creep_.empty()) y += input_creep_.step(ud);
  if (!displacement_creep_.empty()) y += displacement_creep_.step(y - creep_reference_um_);
  stroke_um_ = y;
  return y;
}

double SimulatedActuator::measure(double x_um) noexcept {
  const double previous = true_position_;
  true_position_ = clamp_displacement(x_um + drift_.step());
  // The sensor sees the position move during the sample, not held at its end: its filter takes
  // the sample's mean (the trapezoid), so it adds its own lag and not half a sample's lead.
  double measured = sensor_ ? sensor_->step(0.5 * (previous + true_position_)) : true_position_;
  if (config_.sensor_noise.enabled) {
    measured += config_.sensor_noise.rms_um * unit_normal_(noise_rng_);
  }
  return adc_.apply(measured);
}

double SimulatedActuator::step(double u_volts) noexcept {
  return measure(structure(stroke(u_volts)));
}

void SimulatedActuator::settle_measurement(double x_um) noexcept {
  true_position_ = clamp_displacement(x_um);
  if (sensor_) sensor_->reset(true_position_);
}

void SimulatedActuator::reset(double u0) noexcept {
  applied_input_ = std::isfinite(u0) ? u0 : config_.input.min_v;
  applied_input_ = condition_input(applied_input_);
  const double u = applied_input_;
  delay_.reset(u);
  double y = 0.0;
  if (model_) {
    model_->reset(u);
    y = model_->peek(u);
  } else {
    if (front_) front_->reset(u);
    if (widened_) widened_->reset(u);
    preisach_->reset(u);
    y = preisach_map(config_.hysteresis, config_.input.min_v, preisach_->output(), u);
  }
  if (!input_creep_.empty()) {
    input_creep_.reset(u);
    y += input_creep_.peek(u);
  }
  if (!displacement_creep_.empty()) {
    displacement_creep_.reset(y - creep_reference_um_);
    y += displacement_creep_.peek(y - creep_reference_um_);
  }
  stroke_um_ = y;
  modes_.reset(y);
  drift_.reset();
  noise_rng_.seed(config_.sensor_noise.seed);
  unit_normal_.reset();
  settle_measurement(y);
}

}  // namespace hystbench::sim
