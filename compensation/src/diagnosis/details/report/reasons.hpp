#pragma once
// The reasons the report gives (diagnosis internals): why a candidate is not named, and the lists
// those reasons and the verdict name. Not real-time: allocates strings.
#include <string>
#include <vector>

#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// "a, b and c".
std::string joined(const std::vector<std::string>& names);

/// Each record left out whole and the candidate's gain there: "run 1 1.3, run 2 1.2".
std::string left_out_summary(const CandidateReport& c);

/// Why a candidate is not named: what it adds to the model holding `before` (added_rms, [unit])
/// is within the noise (less than `allowance`).
std::string within_noise(const std::string& before, double added_rms, double allowance,
                         const std::string& unit);

}  // namespace hystbench::compensation::details::diagnosis
