#pragma once
// The candidates tested against the reference (diagnosis internals): each cause's test
// (causes/), run in candidate_causes() order into the diagnosis's CandidateReports.
#include <vector>

#include "diagnosis/details/candidates.hpp"
#include "diagnosis/details/extension_fit.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

using TestFunction = details::CandidateOutcome (*)(const details::CandidateContext&);

/// The test of cause c (causes/<cause>.cpp); nullptr for none.
TestFunction test_of(Cause c);

/// Tests every candidate against the context's reference into d.candidates (their gains over
/// d's baseline); returns each one's extension fit, in candidate order (for the joint extended
/// model).
std::vector<details::ExtensionFit> test_candidates(Diagnosis& d,
                                                   const details::CandidateContext& ctx,
                                                   const DiagnosisOptions& options);

}  // namespace hystbench::compensation::details::diagnosis
