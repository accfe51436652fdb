#pragma once
// A model's dynamics and delay timed again on a record's step responses (step_timing.hpp), as
// identify does for its extension and `diagnose --save-extended` for the model it saves: a fit
// over the whole record lets a delay stand partly for the loop's shape the model misses, and
// gives whole samples where a fast reference's feedforward needs a fraction. Not real-time.
#include <nlohmann/json.hpp>
#include <span>
#include <string>

#include "hystbench/compensation/actuator_model.hpp"

namespace hystbench::common {

/// Times `model`'s dynamics and delay on the record (u, y every dt_s) and sets them. The record's
/// delay holds `exchange_s` of the driver's latency, which the model's does not. Returns what
/// changed: steps, rms_um, natural_frequency_hz, damping_ratio, delay_samples and from_record
/// (the values before); null when the model has no dynamics or the record no step.
nlohmann::json time_on_steps(compensation::ActuatorModel& model, std::span<const double> u,
                             std::span<const double> y, double dt_s, double exchange_s);

/// "timed on 2 step responses: 802 Hz, damping 0.0591, delay 0.515 samples".
std::string timing_text(const nlohmann::json& timing);

}  // namespace hystbench::common
