#include "hystbench/compensation/model_check.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <vector>

#include "details/validate.hpp"
#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::compensation {
namespace {

constexpr double kTriangleHz = 1.0;          // slow: the static map, not the dynamics
constexpr double kMargin = 0.05;             // of the output range, each side
constexpr std::size_t kMaxSamples = 200000;  // a finer sample period checks fewer periods' worth

ModelCheck failure(std::string part, std::string reason) {
  ModelCheck c;
  c.passed = false;
  c.part = std::move(part);
  c.reason = std::move(reason);
  return c;
}

// The unit triangle 0 -> 1 -> 0 over n samples, at sample k (periodic).
double triangle(std::size_t k, std::size_t n) {
  const double phase = static_cast<double>(k % n) / static_cast<double>(n);
  return phase < 0.5 ? 2.0 * phase : 2.0 - 2.0 * phase;
}

// What construction leaves open: the input range (public), the hysteresis's invertibility. A
// delay, a creep bank or a mode that is not sound (a mode with f_n or zeta <= 0 is not stable)
// is refused when it is set.
ModelCheck check_parameters(const ActuatorModel& model) {
  if (!model.valid()) return failure("hysteresis", "the model has no hysteresis part");
  if (!(std::isfinite(model.input_min) && std::isfinite(model.input_max) &&
        model.input_max > model.input_min)) {
    return failure("input_range", "its input range [" + significant(model.input_min, 3) + ", " +
                                      significant(model.input_max, 3) + "] is not an interval");
  }
  const Invertibility inv = model.hysteresis().invertibility();
  if (!inv.invertible) return failure("hysteresis", inv.reason);
  return {};
}

// The static model (hysteresis and creep) over one input triangle u_min -> u_max -> u_min,
// after one such triangle: the lowest and highest output of its major loop.
std::pair<double, double> output_range(ActuatorModel model, std::size_t per_period) {
  std::vector<double> u(2 * per_period);
  for (std::size_t k = 0; k < u.size(); ++k) {
    u[k] = model.input_min + triangle(k, per_period) * (model.input_max - model.input_min);
  }
  const std::vector<double> y = model.simulate(u, model.sample_period());
  const auto [lo, hi] = std::minmax_element(y.begin() + per_period, y.end());
  return {*lo, *hi};
}

}  // namespace

ModelCheck check_model(const ActuatorModel& model, double dt_s) {
  details::require(std::isfinite(dt_s) && dt_s > 0.0, "sample period must be > 0");
  ModelCheck parameters = check_parameters(model);
  if (!parameters.passed) return parameters;
  try {
    ActuatorModel statics = model;  // the inverse is quasi-static: delay and dynamics apart
    statics.set_delay(0.0);
    statics.set_dynamics(std::nullopt);
    statics.configure(dt_s);
    const auto per_period = std::clamp<std::size_t>(
        static_cast<std::size_t>(std::lround(1.0 / (kTriangleHz * dt_s))), 100, kMaxSamples / 2);
    const auto [lo, hi] = output_range(statics, per_period);
    const double range = hi - lo;
    if (!(std::isfinite(range) && range > 0.0)) {
      return failure("hysteresis", "its output does not rise over its input range (from " +
                                       significant(lo, 3) + " to " + significant(hi, 3) + ")");
    }
    std::vector<double> targets(2 * per_period);
    for (std::size_t k = 0; k < targets.size(); ++k) {
      targets[k] = lo + range * (kMargin + (1.0 - 2.0 * kMargin) * triangle(k, per_period));
    }
    std::unique_ptr<InverseModel> inverse = make_inverse(statics);
    statics.reset(statics.input_min);
    inverse->reset(statics.input_min);
    const std::vector<double> drive = invert_sequence(*inverse, targets);
    double sum = 0.0, worst = 0.0;
    for (std::size_t k = 0; k < drive.size(); ++k) {
      const double e = (statics.step(drive[k]) - targets[k]) / range * 100.0;
      if (k < per_period) continue;  // the first period starts from a relaxed state
      sum += e * e;
      worst = std::max(worst, std::isfinite(e) ? std::abs(e) : INFINITY);
    }
    ModelCheck c;
    c.inverse_rms_percent = std::sqrt(sum / static_cast<double>(per_period));
    c.inverse_max_percent = worst;
    if (!(c.inverse_rms_percent <= ModelCheck::kMaxRmsPercent &&
          c.inverse_max_percent <= ModelCheck::kMaxMaxPercent)) {
      c.passed = false;
      c.part = "inverse";
      c.reason =
          "its inverse does not reach its own output over its input range: driven by it, "
          "the model misses a 1 Hz triangle over 90 % of its range by " +
          fixed(c.inverse_rms_percent, 3) + " % rms, " + fixed(c.inverse_max_percent, 3) + " % max";
    }
    return c;
  } catch (const NotInvertibleError& e) {
    return failure("hysteresis", e.why().reason);
  } catch (const std::exception& e) {
    return failure("inverse", std::string("its inverse cannot be built: ") + e.what());
  }
}

nlohmann::json to_json(const ModelCheck& check) {
  nlohmann::json j = {{"passed", check.passed}};
  if (!check.part.empty()) j["part"] = check.part;
  if (!check.reason.empty()) j["reason"] = check.reason;
  if (std::isfinite(check.inverse_rms_percent))
    j["inverse_rms_percent"] = check.inverse_rms_percent;
  if (std::isfinite(check.inverse_max_percent))
    j["inverse_max_percent"] = check.inverse_max_percent;
  return j;
}

std::string describe(const ModelCheck& check) {
  if (!check.passed) return "failed: " + check.reason;
  return "passed (driven by its inverse it tracks a triangle over 90 % of its range at " +
         fixed(check.inverse_rms_percent, 3) + " % rms)";
}

}  // namespace hystbench::compensation
