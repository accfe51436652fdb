#pragma once
// Cross-coupling as a cause in a record of several inputs: each output is modelled from its own
// input alone (the baseline: a linear block of one input) and from every input (the extension:
// one MIMO linear block for all outputs, poles shared). The cause is named for an output where
// the extension lowers the held-out error by the naming gain, and does so again with each
// realization left out in turn (fitted on the others, scored on it). Its inputs are the others
// that carry at least a twentieth of the output's power through the extension.
// Units: the record's. Pure maths; allocates; not real-time safe.
#include <functional>
#include <string>
#include <vector>

#include "hystbench/compensation/mimo_identification.hpp"

namespace hystbench::compensation {

/// The held-out gain (baseline rms / extended rms) that names the cause, on every check.
inline constexpr double kCouplingNamingGain = 1.2;
/// An input is named where it carries at least this share of the output's power.
inline constexpr double kCouplingNamedShare = 0.05;

struct OutputCoupling {
  std::size_t output = 0, own_input = 0;
  std::size_t baseline_order = 0;
  MimoLinearModel baseline;  ///< the output from its own input, fitted on all of the record
  double baseline_heldout_rms = 0.0;  ///< [output unit], steady state
  double extended_heldout_rms = 0.0;
  double gain = 0.0;                   ///< baseline / extended
  std::vector<double> shares;          ///< per input, of the output's power (extension)
  std::vector<double> left_out_gains;  ///< per realization left out (empty with one)
  std::vector<std::size_t> named_inputs;
  bool named = false;
};

struct CouplingDiagnosis {
  std::string heldout;  ///< what the held-out figures are scored on
  std::size_t extended_order = 0;
  MimoLinearModel extended;  ///< every input to every output, fitted on all of the record
  std::vector<OutputCoupling> outputs;
};

/// own_input[i]: output i's own input (an index into the inputs). Throws std::invalid_argument
/// for a bad index, or a record of one input.
CouplingDiagnosis diagnose_cross_coupling(
    const PeriodicSpectra& spectra, const std::vector<std::size_t>& own_input,
    const std::function<void(double, const std::string&)>& progress = {});

}  // namespace hystbench::compensation
