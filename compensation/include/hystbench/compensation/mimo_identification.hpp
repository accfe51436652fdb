#pragma once
// Periodic multi-input records (multisines: realizations of several periods each) and the
// identification of a MimoLinearModel from them in the frequency domain.
//  - periodic_spectra(): the first period of each realization is a transient and is dropped;
//    the others are averaged and read at the excited DFT bins; the noise on that average comes
//    from the differences between periods.
//  - fit_mimo_linear(): one common denominator for every entry, fitted by Sanathanan-Koerner
//    iterations (a linearised output error re-weighted by the last denominator) on the
//    realizations' cross-spectra; its roots, reflected into the unit circle, are the poles, and
//    the residues are the least-squares output error with those poles fixed.
//  - identify_mimo_linear(): the order chosen on held-out data, then fitted on all of it.
// Units: the record's. Pure maths; allocates; not real-time safe.
#include <Eigen/Dense>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "hystbench/compensation/hammerstein_mimo_model.hpp"
#include "hystbench/compensation/mimo_linear_model.hpp"

namespace hystbench::compensation {

/// R realizations of P periods of N samples; u[r] is m x (P N), y[r] is p x (P N).
struct PeriodicRecord {
  std::size_t period = 0;   ///< N, samples per period, >= 4
  std::size_t periods = 0;  ///< P, >= 1
  double dt = 0.0;          ///< sample period [s], > 0
  std::vector<Eigen::MatrixXd> u, y;
};

struct PeriodicSpectra {
  std::size_t period = 0;
  double dt = 0.0;
  std::size_t transient_periods = 0;  ///< dropped at the start of each realization
  std::size_t periods_used = 0;       ///< averaged after them
  std::vector<std::size_t> bins;      ///< excited DFT bins: f = bin / (N dt) [Hz]
  /// Per realization, the averaged period's DFT at the bins (unnormalised): m x K and p x K.
  std::vector<Eigen::MatrixXcd> u, y;
  /// p x K: the variance of y's averaged DFT from the differences between the periods (with
  /// one period used, from all periods, the transient's difference included: an upper bound).
  Eigen::MatrixXd noise_var;
  Eigen::VectorXd u_mean, y_mean;  ///< the steady state's means, over the realizations

  std::size_t inputs() const { return u.empty() ? 0 : static_cast<std::size_t>(u[0].rows()); }
  std::size_t outputs() const { return y.empty() ? 0 : static_cast<std::size_t>(y[0].rows()); }
  /// z = exp(j 2 pi bin / N) of bin index k.
  std::complex<double> z(std::size_t k) const;
};

/// Throws std::invalid_argument for an empty or ragged record, or one with no excited bin.
/// A bin is excited where the inputs' power is at least 1e-3 of the strongest bin's (-30 dB).
PeriodicSpectra periodic_spectra(const PeriodicRecord& record);

/// Steady-state rms of y - G u over the excited bins of `realizations` (all: empty), per output
/// [output unit]: Parseval on the averaged period (the unexcited bins' output not counted).
Eigen::VectorXd steady_state_rms(const MimoLinearModel& model, const PeriodicSpectra& spectra,
                                 const std::vector<std::size_t>& realizations = {});

/// The model of `order` (>= 1) fitted on `realizations` (all: empty) of the spectra. Throws
/// std::invalid_argument for a bad order.
MimoLinearModel fit_mimo_linear(const PeriodicSpectra& spectra, std::size_t order,
                                const std::vector<std::size_t>& realizations = {});

struct MimoFitOptions {
  /// The candidate orders; the one of lowest held-out error wins (a lower one within 2 % of it
  /// is preferred). Empty: 2, 4, ..., 40.
  std::vector<std::size_t> orders;
  /// Progress: fraction done in [0, 1] and what is being done.
  std::function<void(double, const std::string&)> progress;
};

struct MimoOrderScore {
  std::size_t order = 0;
  double heldout_rms = 0.0;  ///< steady-state rms over outputs [output unit]
};

struct MimoFitResult {
  MimoLinearModel model;  ///< the chosen order, fitted on every realization
  std::size_t order = 0;
  std::string heldout;  ///< what was held out: "realization R" or "odd bins"
  std::vector<MimoOrderScore> scores;
  Eigen::VectorXd fit_rms;  ///< per output, steady state, on every realization
};

/// The order chosen on held-out data: the last realization where there are two or more, else
/// every other excited bin (the model is smooth across bins; its fit on the others is scored
/// on them). Then the chosen order is fitted on all of it.
MimoFitResult identify_mimo_linear(const PeriodicSpectra& spectra,
                                   const MimoFitOptions& options = {});

/// The spectra of other inputs to the same record (an operator's outputs, m' x (P N) per
/// realization), read at the same bins and periods as `spectra`'s.
PeriodicSpectra with_inputs(const PeriodicSpectra& spectra, const std::vector<Eigen::MatrixXd>& v);

struct HammersteinFitOptions {
  MimoFitOptions linear;      ///< the linear block's order candidates and the progress
  std::size_t operators = 8;  ///< play operators per input (0: none tried)
  std::size_t rounds = 10;    ///< alternations of the dynamics' and the operators' fits
};

struct HammersteinFitResult {
  HammersteinMimoModel model;        ///< the operators where they lowered the held-out error
  MimoFitResult linear;              ///< the linear block alone, its order chosen on held-out data
  std::string heldout;               ///< what was held out (as linear.heldout)
  double heldout_linear = 0.0;       ///< steady-state rms on it [output unit]
  double heldout_hammerstein = 0.0;  ///< the same with the operators
  bool hysteresis_kept = false;      ///< the operators lowered it by 2 % or more
  Eigen::VectorXd fit_rms;           ///< per output, steady state, on every realization
};

/// The linear block (identify_mimo_linear), then a classical PI operator per input with
/// thresholds uniform on half the input's span, fitted by alternating least squares with the
/// dynamics (the order kept): the operators' weights with the dynamics fixed, the dynamics on
/// the operators' outputs. Kept where they lower the held-out error, then fitted on all of it.
HammersteinFitResult identify_mimo_hammerstein(const PeriodicRecord& record,
                                               const HammersteinFitOptions& options = {});

/// The spectra of some inputs and outputs only (indices into spectra's), the bins kept.
PeriodicSpectra subset(const PeriodicSpectra& spectra, const std::vector<std::size_t>& inputs,
                       const std::vector<std::size_t>& outputs);

/// The share of each output's power (over the excited bins of the steady state) that each
/// input explains through the model: p x m, each in [0, 1] (rows need not sum to one: inputs
/// correlate, and the model misses some).
Eigen::MatrixXd coupling_shares(const HammersteinMimoModel& model, const PeriodicRecord& record);
/// The same for a linear block on spectra whose inputs are the block's inputs.
Eigen::MatrixXd coupling_shares(const MimoLinearModel& dynamics, const PeriodicSpectra& spectra);

}  // namespace hystbench::compensation
