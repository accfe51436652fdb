#pragma once
// The other causes judged on top of the loop's shape (diagnosis internals). A classical PI
// follows neither a bent loop (a Preisach density, a saturating top) nor an asymmetric one, and
// what it misses there inflates every other candidate's gain: when a shape cause is eligible,
// the other causes are tested again on top of its extension, and the strongest that counts may
// be named first, beyond the shape. Not real-time: refits per candidate.
#include <vector>

#include "details/diagnosis_signals.hpp"
#include "diagnosis/details/extension_fit.hpp"
#include "diagnosis/details/naming/decision.hpp"
#include "diagnosis/details/record.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// When a shape cause is eligible (and the baseline is not at the noise floor): sets
/// decision.shape, tests the other causes that carry over on top of its extension (fits: each
/// candidate's, in candidate order) into decision.on_shape, notes their gains in d, and sets
/// decision.beyond to the strongest that counts (by ranks_before).
void test_on_shape(Diagnosis& d, const details::DiagnosisRecord& r,
                   const std::vector<details::ExtensionFit>& fits, const details::InputEvents& ev,
                   const DiagnosisOptions& options, Decision& decision);

}  // namespace hystbench::compensation::details::diagnosis
