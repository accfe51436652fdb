#pragma once
// The plant the feedback sees. Its output corrects the feedforward's target (compensator.hpp),
// which the feedforward turns into drive through the model's inverse (`inverse+pid`) or the
// linear map (`pid`). So the loop holds the actuator divided by what the feedforward inverts:
// each measured response over the model's static part's response (hysteresis, creep, rate law;
// not its delay or dynamics, which the target's correction does not pass) to the same drive,
// line by line; or over the linear map's gain. Near 1 where the model holds the actuator's local
// slope, whatever that slope is along the loop. Pure maths; allocates: not real-time.
#include <cstddef>
#include <span>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/measured_response.hpp"

namespace hystbench::compensation {

/// measured[i] (measured over segments[i] of `drive`, sampled at rate_hz) over the response of
/// model's static part, relaxed at drive[0] and stepped through the whole drive. Throws
/// std::invalid_argument for mismatched sizes or a segment beyond the drive.
std::vector<MeasuredResponse> responses_through_model(std::span<const MeasuredResponse> measured,
                                                      std::span<const ResponseSegment> segments,
                                                      const ActuatorModel& model,
                                                      std::span<const double> drive,
                                                      double rate_hz);

/// How much steeper the stage climbs along its loop than it answers a small signal at rest, as
/// the model's static part holds it. A loop through the linear map sees the actuator's slope
/// itself, which a hysteresis loop moves by up to a factor of two along its branches, while the
/// measured responses (small signals at rest) show the slope of a minor loop. The model's
/// steepest branch: its largest slope over 1 % of the input range, on the second period of a
/// 1 Hz triangle over its whole range, inside the range's central 90 %. Its slope at rest: its
/// response at the lowest line to the drive each response was measured with (as
/// responses_through_model). `response` is the measured response steepest along the loop (its
/// lowest line times `ratio`), `ratio` = steepest branch / that response's model slope at rest,
/// at least 1 (1 too where the model has no input range).
struct MotionScale {
  std::size_t response = 0;
  double ratio = 1.0;
};
MotionScale motion_scale(std::span<const MeasuredResponse> measured,
                         std::span<const ResponseSegment> segments, const ActuatorModel& model,
                         std::span<const double> drive, double rate_hz);

/// measured over a linear map's gain (> 0) [output unit / input unit].
std::vector<MeasuredResponse> responses_through_gain(std::span<const MeasuredResponse> measured,
                                                     double gain);

}  // namespace hystbench::compensation
