#pragma once
// The frequency-domain fit of a MimoLinearModel to periodic spectra (mimo_identification
// internals), shared by the linear and the Hammerstein identification: which realizations and
// bins a fit or a score uses, the cross-spectra, the Sanathanan-Koerner fit of an order, the
// residues with the poles fixed, the steady-state rms and the held-out split. Units: the
// record's. Allocates; not real-time safe.
#include <Eigen/Dense>
#include <complex>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "hystbench/compensation/mimo_identification.hpp"
#include "hystbench/compensation/mimo_linear_model.hpp"

namespace hystbench::compensation::details::mimo {

// A lower order within this fraction of the best held-out error is preferred.
inline constexpr double kOrderTolerance = 0.02;

// Which realizations and bins a fit or a score uses.
struct Selection {
  std::vector<std::size_t> realizations;
  int bin_parity = -1;  // -1: every bin; 0 / 1: the even / odd bin indices only

  bool uses_bin(std::size_t k) const {
    return bin_parity < 0 || static_cast<int>(k % 2) == bin_parity;
  }
};

// Every bin of `realizations` (all: empty); throws std::invalid_argument for one out of range.
Selection select(const PeriodicSpectra& s, const std::vector<std::size_t>& realizations);

// The cross-spectra a fit needs at bin k, summed over the selected realizations:
// uu(j, j') = sum conj(U_j) U_j', yu(i, j) = sum conj(Y_i) U_j, yy(i) = sum |Y_i|^2.
struct CrossSpectra {
  std::vector<Eigen::MatrixXcd> uu, yu;
  std::vector<Eigen::VectorXd> yy;
  std::vector<std::size_t> k;  // the bin indices used
};

CrossSpectra cross_spectra(const PeriodicSpectra& s, const Selection& sel);

// The terms (D, then each pole's) of least output error with the poles fixed, and the offset.
MimoLinearModel residues(const PeriodicSpectra& s, const CrossSpectra& c,
                         const std::vector<std::complex<double>>& poles);

// The model of `order` fitted on `sel` (Sanathanan-Koerner, then the residues); throws
// std::invalid_argument for an order below 1 or above what the selected bins carry.
MimoLinearModel fit_on(const PeriodicSpectra& s, std::size_t order, const Selection& sel);

// Steady-state rms of y - G u per output on `sel` [output unit].
Eigen::VectorXd rms_on(const MimoLinearModel& model, const PeriodicSpectra& s,
                       const Selection& sel);

// The held-out split of identify_*: the last realization where there are several, else the
// odd bins; `what` names the held-out part.
std::pair<Selection, Selection> heldout_split(const PeriodicSpectra& s, std::string& what);

// The rms over outputs of per-output rms values.
double overall(const Eigen::VectorXd& per_output);

}  // namespace hystbench::compensation::details::mimo
