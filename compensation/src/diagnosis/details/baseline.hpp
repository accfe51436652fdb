#pragma once
// The diagnosis baseline (internals): a classical PI identified on the fit part, or the
// structure of a given model to refit the extensions from.
#include <string>

#include "diagnosis/details/extension_fit.hpp"

namespace hystbench::compensation::details {

struct PiBaseline {
  ExtensionSpec spec;  ///< the baseline
  ExtensionFit fit;
  /// The finest order tried: the extensions start from it, so that their gains are not
  /// limited by a play resolution the baseline did not need only because a larger unmodelled
  /// effect hid it (more plays alone gain at most the parsimony margin: the baseline tried them).
  ExtensionSpec finest_spec;
  ExtensionFit finest_fit;
  std::string description;  ///< e.g. "classical PI ... 16 plays uniform on 0..75 V ..."
};

/// Classical PI, plays uniform on half the input span, order (8..32) chosen by held-out error
/// (the smallest within 1 % of the best).
PiBaseline fit_pi_baseline(const DiagnosisRecord& r);

/// The structure of a given model (thresholds, dead zones, creep lags, delay, dynamics) for
/// refitting; a classical PI of the same number of plays when the designs cannot represent it.
ExtensionSpec spec_of_model(const ActuatorModel& model, const DiagnosisRecord& r);

/// Short description of a model, e.g. "mpi, 12 plays, 2+2 dead zones, creep 4 lags, delay 1
/// sample".
std::string describe_model(const ActuatorModel& model);

}  // namespace hystbench::compensation::details
