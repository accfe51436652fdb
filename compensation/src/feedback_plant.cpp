#include "hystbench/compensation/feedback_plant.hpp"

#include <cmath>
#include <string>

#include "details/validate.hpp"

namespace hystbench::compensation {

std::vector<MeasuredResponse> responses_through_model(std::span<const MeasuredResponse> measured,
                                                      std::span<const ResponseSegment> segments,
                                                      const ActuatorModel& model,
                                                      std::span<const double> drive,
                                                      double rate_hz) {
  details::require(measured.size() == segments.size(),
                   "feedback plant: one segment per measured response");
  details::require(!drive.empty(), "feedback plant: no drive");
  ActuatorModel static_part = model;
  static_part.set_dynamics(std::nullopt);
  static_part.set_delay(0.0);
  const std::vector<double> y = static_part.simulate(drive, 1.0 / rate_hz);
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
    const MeasuredResponse m =
        estimate_response(drive.subspan(s.first, n), std::span<const double>(y).subspan(s.first, n),
                          s.period, lines, rate_hz);
    MeasuredResponse r = measured[i];
    for (std::size_t j = 0; j < r.size(); ++j) {
      const double mag = std::abs(m.response[j]);
      details::require(mag > 0.0, what + ": the model does not respond at " +
                                      details::fmt(r.frequency_hz[j]) + " Hz");
      r.response[j] /= m.response[j];
      r.noise[j] /= mag;
    }
    r.label = measured[i].label;
    out.push_back(std::move(r));
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
