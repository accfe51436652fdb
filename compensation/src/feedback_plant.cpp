#include "hystbench/compensation/feedback_plant.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "details/validate.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::compensation {

namespace {

// The static part of model (no delay, no dynamics), configured at dt_s.
ActuatorModel static_part(const ActuatorModel& model) {
  ActuatorModel s = model;
  s.set_dynamics(std::nullopt);
  s.set_delay(0.0);
  return s;
}

// The model's response m to the drive over each measured response's segment, at its lines.
std::vector<MeasuredResponse> model_responses(std::span<const MeasuredResponse> measured,
                                              std::span<const ResponseSegment> segments,
                                              const ActuatorModel& model,
                                              std::span<const double> drive, double rate_hz) {
  details::require(measured.size() == segments.size(),
                   "feedback plant: one segment per measured response");
  details::require(!drive.empty(), "feedback plant: no drive");
  const std::vector<double> y = static_part(model).simulate(drive, 1.0 / rate_hz);
  std::vector<MeasuredResponse> out;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    const ResponseSegment& s = segments[i];
    const std::string what = "feedback plant: response " + std::to_string(i);
    details::require(
        s.period > 0 && s.periods >= 2 && s.first + s.period * s.periods <= drive.size(),
        what + ": its segment lies beyond the drive");
    std::vector<std::size_t> lines;
    for (const double f : measured[i].frequency_hz) {
      lines.push_back(
          static_cast<std::size_t>(std::lround(f * static_cast<double>(s.period) / rate_hz)));
    }
    const std::size_t n = s.period * s.periods;
    MeasuredResponse m =
        estimate_response(drive.subspan(s.first, n), std::span<const double>(y).subspan(s.first, n),
                          s.period, lines, rate_hz);
    for (std::size_t j = 0; j < m.size(); ++j) {
      details::require(std::abs(m.response[j]) > 0.0,
                       what + ": the model does not respond at " +
                           significant(measured[i].frequency_hz[j], 6) + " Hz");
    }
    out.push_back(std::move(m));
  }
  return out;
}

// The model's static part's largest slope along its loop (MotionScale) [output / input unit]; 0
// without an input range.
double steepest_branch_slope(const ActuatorModel& model, double rate_hz) {
  const double lo = model.input_min, hi = model.input_max;
  if (!(hi > lo)) return 0.0;
  const auto period = static_cast<std::size_t>(std::max(200.0, std::round(rate_hz)));
  std::vector<double> u(2 * period);
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double phase = static_cast<double>(k % period) / static_cast<double>(period);
    u[k] = lo + (hi - lo) * (phase < 0.5 ? 2.0 * phase : 2.0 - 2.0 * phase);
  }
  const std::vector<double> y = static_part(model).simulate(u, 1.0 / rate_hz);
  const double step = 0.01 * (hi - lo), edge = 0.05 * (hi - lo);
  double steepest = 0.0;
  std::size_t from = period;
  for (std::size_t k = period + 1; k < u.size(); ++k) {
    const double du = u[k] - u[from];
    if (std::abs(du) < step) continue;
    const double mid = 0.5 * (u[k] + u[from]);
    if (mid > lo + edge && mid < hi - edge) steepest = std::max(steepest, (y[k] - y[from]) / du);
    from = k;
  }
  return steepest;
}

}  // namespace

std::vector<MeasuredResponse> responses_through_model(std::span<const MeasuredResponse> measured,
                                                      std::span<const ResponseSegment> segments,
                                                      const ActuatorModel& model,
                                                      std::span<const double> drive,
                                                      double rate_hz) {
  const std::vector<MeasuredResponse> m =
      model_responses(measured, segments, model, drive, rate_hz);
  std::vector<MeasuredResponse> out;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    MeasuredResponse r = measured[i];
    for (std::size_t j = 0; j < r.size(); ++j) {
      r.response[j] /= m[i].response[j];
      r.noise[j] /= std::abs(m[i].response[j]);
    }
    out.push_back(std::move(r));
  }
  return out;
}

MotionScale motion_scale(std::span<const MeasuredResponse> measured,
                         std::span<const ResponseSegment> segments, const ActuatorModel& model,
                         std::span<const double> drive, double rate_hz) {
  MotionScale out;
  const double steepest = steepest_branch_slope(model, rate_hz);
  if (!(steepest > 0.0) || measured.empty()) return out;
  const std::vector<MeasuredResponse> m =
      model_responses(measured, segments, model, drive, rate_hz);
  double moving_gain = 0.0;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    const double ratio = std::max(1.0, steepest / std::abs(m[i].response.front()));
    const double gain = ratio * std::abs(measured[i].response.front());
    if (gain > moving_gain) {
      moving_gain = gain;
      out = {i, ratio};
    }
  }
  return out;
}

std::vector<MeasuredResponse> responses_through_gain(std::span<const MeasuredResponse> measured,
                                                     double gain) {
  details::require(std::isfinite(gain) && gain > 0.0, "feedback plant: the gain must be > 0");
  std::vector<MeasuredResponse> out(measured.begin(), measured.end());
  for (MeasuredResponse& r : out) {
    for (auto& x : r.response) x /= gain;
    for (auto& x : r.noise) x /= gain;
  }
  return out;
}

}  // namespace hystbench::compensation
