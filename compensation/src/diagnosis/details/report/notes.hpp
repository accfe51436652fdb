#pragma once
// The report's notes (diagnosis internals): caveats on the verdict and on the record, each one
// sentence appended to Diagnosis::notes. Not real-time: allocates strings.
#include <string>

#include "details/diagnosis_signals.hpp"
#include "diagnosis/details/naming/decision.hpp"
#include "diagnosis/details/record.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// Notes where the verdict is not clean: a candidate gaining more than the named one without a
/// significant statistic, or no cause while the baseline's error is above the noise floor.
void note_unclean_verdict(Diagnosis& d, const Decision& decision, const DiagnosisOptions& options);

/// Notes how much of the output's power something other than this input drives (the caller
/// calls it when d.coherent_share is low).
void note_incoherent_output(Diagnosis& d, const details::DiagnosisRecord& r,
                            const std::string& unit);

/// Notes on the record: a given model that does not match it, what its excitation cannot show
/// (no holds, one loop only, no steps).
void note_record(Diagnosis& d, const details::DiagnosisRecord& r, const details::InputEvents& ev,
                 const DiagnosisOptions& options);

/// A runner-up that explains the same as the named cause (within the noise of it) and about as
/// well (kAmbiguity) leaves the choice between them open: noted, unless the first cause was named
/// beyond the shape.
void note_ambiguity(Diagnosis& d, const Decision& decision);

}  // namespace hystbench::compensation::details::diagnosis
