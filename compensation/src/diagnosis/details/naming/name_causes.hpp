#pragma once
// Naming the causes and building the extended model (diagnosis internals): once the verdict
// has chosen the first cause, every other candidate is tried on top of the causes before it and
// named where it adds enough (Diagnosis::causes), its extension joining the extended model where
// it lowers the held-out error (Diagnosis::extended_parts). Not real-time: refits per candidate.
#include "diagnosis/details/naming/decision.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// d.cause (not none) and the candidates' not_named set for the candidates that cannot be named:
/// names every other cause (Diagnosis::causes) and builds the extended model, the named cause's
/// extension joined by every other significant one that lowers the held-out error on top of it
/// (Diagnosis::extended_parts).
void name_causes_and_extend(Diagnosis& d, const Naming& x);

/// The extended model: the baseline's when no cause is named.
void extend_by_nothing(Diagnosis& d);

}  // namespace hystbench::compensation::details::diagnosis
