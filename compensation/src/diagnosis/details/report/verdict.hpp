#pragma once
// The verdict's text (diagnosis internals): one paragraph, from what was decided (Decision: its
// case, the named cause and the figures it was named on) and, once the other causes are named,
// the list of them with what each adds. Not real-time: allocates strings.
#include <string>

#include "diagnosis/details/naming/decision.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// The verdict for `decision` (its verdict_case()): why none, or the cause named and why. d holds
/// the baseline's and the candidates' figures; unit is the output's.
std::string verdict_text(const Diagnosis& d, const Decision& decision,
                         const DiagnosisOptions& options, const std::string& unit);

/// The causes named after the first (d.causes beyond the first, at least one), each with what it
/// adds, to append to the verdict; shape is the shape cause the others were judged on top of.
std::string also_named_text(const Diagnosis& d, Cause shape, const std::string& unit);

}  // namespace hystbench::compensation::details::diagnosis
