#pragma once
// The candidates that may be named first (diagnosis internals): significant, min_gain over the
// reference and carrying over to the records left out whole.
#include <vector>

#include "diagnosis/details/naming/decision.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// The candidates that may be named (significant, min_gain over decision.reference, carrying
/// over), largest gain first; says why each other one is not (and notes a candidate that does
/// not carry over). At the noise floor every candidate's reason is that floor.
std::vector<const CandidateReport*> eligible_candidates(Diagnosis& d, const Decision& decision,
                                                        const DiagnosisOptions& options);

}  // namespace hystbench::compensation::details::diagnosis
