#pragma once
// The diagnosis's decision (diagnosis internals): from the candidates' reports, the first cause
// and the verdict, the report's notes, then the other causes named and the extended model built
// (name_causes_and_extend). Not real-time: refits candidates on top of the shape and each other.
#include <vector>

#include "details/diagnosis_signals.hpp"
#include "diagnosis/details/extension_fit.hpp"
#include "diagnosis/details/record.hpp"
#include "diagnosis/details/reference.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// What the decision reads besides d (whose candidates are tested, and scored across records
/// when there are several).
struct DecisionInputs {
  const details::DiagnosisRecord& r;
  const std::vector<details::ExtensionFit>& fits;  ///< each candidate's, in candidate order
  const details::InputEvents& ev;
  const Reference& ref;                  ///< what the candidates' statistics read
  double reference_delay_samples = 0.0;  ///< the baseline structure's own delay [samples]
};

/// Decides d.cause, d.verdict, d.noise_allowance_rms and the notes; names every cause
/// (d.causes, each candidate's named / not_named) and builds the extended model.
void decide(Diagnosis& d, const DecisionInputs& in, const DiagnosisOptions& options);

}  // namespace hystbench::compensation::details::diagnosis
