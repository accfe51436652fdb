#pragma once
// A prediction's residual and its profiles (diagnosis internals): the mean residual binned
// against time, input level, direction, rate and time since the last reversal or step, which the
// candidates' statistics read. Not real-time: allocates per call.
#include <span>
#include <vector>

#include "details/diagnosis_signals.hpp"
#include "diagnosis/details/record.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// y - prediction over the record [output unit].
std::vector<double> residual_of(const details::DiagnosisRecord& r,
                                std::span<const double> prediction);

/// The profiles of residual e (of the whole record, [output unit]): "time", "input",
/// "direction", "rate" and "since_event" (the residual signed by the last input change), over the
/// scored samples.
std::vector<ResidualProfile> residual_profiles(const details::DiagnosisRecord& r,
                                               std::span<const double> e,
                                               const details::InputEvents& ev);

}  // namespace hystbench::compensation::details::diagnosis
