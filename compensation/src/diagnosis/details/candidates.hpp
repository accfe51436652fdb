#pragma once
// The candidate causes of the diagnosis (internals), one file each: every candidate computes
// a statistic from the baseline residual (with a significance threshold) and fits its extended
// model (the baseline structure plus the effect) on the fit part of the record.
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "details/diagnosis_signals.hpp"
#include "diagnosis/details/extension_fit.hpp"
#include "diagnosis/details/number_text.hpp"
#include "diagnosis/details/record.hpp"

namespace hystbench::compensation::details {

struct CandidateContext {
  const DiagnosisRecord& record;
  /// The baseline structure every extension starts from, and that structure fitted here
  /// (without a given model this fit IS the baseline).
  const ExtensionSpec& base;
  const ExtensionFit& base_fit;
  std::span<const double> baseline_prediction;
  std::span<const double> residual;  ///< y - baseline prediction
  const InputEvents& events;
  const std::vector<ResidualProfile>& profiles;
  const FrequencyResponse& response;
  double noise_rms = 0.0;
  /// With base a joint model (causes named on top of the reference): the reference's own delay
  /// [samples], below which base's delay is not the diagnosis's to move. Negative otherwise.
  double reference_delay_samples = -1.0;
  /// With base a joint model: the held-out gain a part added on top of it must reach to be named.
  /// A candidate that falls just short of it may refine its fit at a cost; 0 on the reference.
  double added_gain_needed = 0.0;
  /// loop_shape may swap the baseline's operator (a given baseline, DiagnosisOptions).
  bool swap_operator = false;

  const ResidualProfile& profile(const std::string& variable) const;
};

struct CandidateOutcome {
  double statistic = 0.0;
  double threshold = 0.0;
  std::string evidence;   ///< what the residual shows, one line
  std::string extension;  ///< what the extended model adds, with fitted values
  ExtensionFit fit;       ///< predicted and scored
};

CandidateOutcome test_asymmetry(const CandidateContext& c);
CandidateOutcome test_loop_shape(const CandidateContext& c);
CandidateOutcome test_rate_dependence(const CandidateContext& c);
CandidateOutcome test_creep(const CandidateContext& c);
CandidateOutcome test_dynamics(const CandidateContext& c);
CandidateOutcome test_delay(const CandidateContext& c);
CandidateOutcome test_drift(const CandidateContext& c);

/// A joint model on a plane whose shape loop_shape fixed (spec_of_model), refitted with its cells
/// free beside the parts joined on it; std::nullopt for another spec, or where the refit does
/// not fit the fit part better.
std::optional<ExtensionFit> refit_plane_cells(const DiagnosisRecord& r, const ExtensionFit& joint);

/// test_creep's statistic alone (no fit): read again on a joint model's residual.
double creep_statistic(const CandidateContext& c);

/// The resonance of `spec` (which has dynamics) found again with the hysteresis weights free,
/// projected from the better of its own and the peak of the measured `response`, when it lies
/// off that peak (15 % in frequency, 2x in damping): a lag its phase stood in for pulled it
/// there, and the part joined after it (a delay) takes that lag. std::nullopt on the
/// peak, or without one.
std::optional<DynamicsParameters> refit_resonance(const DiagnosisRecord& r,
                                                  const ExtensionSpec& spec,
                                                  const FrequencyResponse& response);

/// The resonance of `spec` (which has dynamics) projected again, from where it is, with every
/// other part's weights free: a part added on top of a mode fitted without it (a rate law, whose
/// widening the mode's phase stood in for) is judged with the mode as fitted for it. Only for a
/// mode on the measured `response`'s peak (as refit_resonance): one pulled off it stood in for a
/// lag, which a delay, not the part added, takes. Only where DesignRows serve the trials: each
/// would otherwise step the record again (docs/measurements.md, Diagnosis, holds the cost).
/// std::nullopt off the peak, without one, or where the rows do not serve.
/// DiagnosisSeveralCauses.NamesAWideningLawBesideALightlyDampedMode holds the projection.
std::optional<DynamicsParameters> project_resonance(const DiagnosisRecord& r,
                                                    const ExtensionSpec& spec,
                                                    const FrequencyResponse& response);

/// Index of the first of `fits` (simplest first) whose fit-part rms is within `parsimony` (a
/// fraction) of the lowest: the simplest that fits about as well. fits not empty.
std::size_t simplest_within(const std::vector<ExtensionFit>& fits, double parsimony);

}  // namespace hystbench::compensation::details
