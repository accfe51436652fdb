#pragma once
// What the candidates are judged against (diagnosis internals): the baseline (a given model, or a
// classical PI identified on the fit part), its residual and noise, and the reference prediction
// whose residual the candidates' statistics read (the baseline's, or the given model's structure
// refitted here when its parameters do not match the record). Not real-time.
#include <span>
#include <vector>

#include "details/diagnosis_signals.hpp"
#include "diagnosis/details/extension_fit.hpp"
#include "diagnosis/details/record.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// The baseline structure every extension starts from, and that structure fitted here.
struct Baseline {
  details::ExtensionSpec spec;
  details::ExtensionFit fit;
};

/// The baseline (the given model, or a classical PI identified here) into d: its description,
/// prediction and errors; with a given model also the refit's held-out error. Throws
/// std::invalid_argument for an empty given model.
Baseline fit_baseline(Diagnosis& d, const details::DiagnosisRecord& r,
                      const DiagnosisOptions& options);

/// The baseline's residual y - prediction [output unit]; sets d's noise rms, how it was
/// estimated and the input's period.
std::vector<double> residual_and_noise(Diagnosis& d, const details::DiagnosisRecord& r);

/// d.coherent_share from d.frequency_response (left as it is when the output has no power).
void set_coherent_share(Diagnosis& d);

/// A given model whose structure, refitted here, gains min_gain: its parameters do not match.
bool given_model_stale(const Diagnosis& d, const DiagnosisOptions& options);

/// The prediction whose residual the candidates' statistics read.
struct Reference {
  std::vector<double> residual;  ///< y - prediction [output unit]
  std::vector<ResidualProfile> profiles;
  FrequencyResponse response;
  std::span<const double> prediction;
};

/// The baseline's (its residual e, profiles and response), or the refit's when a given model no
/// longer matches this record. The prediction refers to d's or base_fit's: both outlive it.
Reference reference_of(const Diagnosis& d, const details::DiagnosisRecord& r,
                       const details::ExtensionFit& base_fit, const details::InputEvents& ev,
                       std::vector<double> e, const DiagnosisOptions& options);

}  // namespace hystbench::compensation::details::diagnosis
