#include "hystbench/compensation/mimo_diagnosis.hpp"

#include <algorithm>
#include <stdexcept>

namespace hystbench::compensation {

namespace {

std::vector<std::size_t> all_but(std::size_t n, std::size_t left_out) {
  std::vector<std::size_t> v;
  for (std::size_t r = 0; r < n; ++r) {
    if (r != left_out) v.push_back(r);
  }
  return v;
}

}  // namespace

CouplingDiagnosis diagnose_cross_coupling(
    const PeriodicSpectra& spectra, const std::vector<std::size_t>& own_input,
    const std::function<void(double, const std::string&)>& progress) {
  const std::size_t m = spectra.inputs(), p = spectra.outputs(), nr = spectra.u.size();
  if (m < 2) throw std::invalid_argument("cross-coupling: a record of one input has none");
  if (own_input.size() != p)
    throw std::invalid_argument("cross-coupling: one own input per output");
  for (const auto j : own_input) {
    if (j >= m) throw std::invalid_argument("cross-coupling: no input " + std::to_string(j));
  }
  const auto report = [&](double f, const std::string& what) {
    if (progress) progress(f, what);
  };
  // Baselines first (each a block of one input), then the extension: 40 % and 40 %, folds 20 %.
  CouplingDiagnosis d;
  std::vector<PeriodicSpectra> own;  // each output with its own input only
  std::vector<MimoFitResult> baselines;
  for (std::size_t i = 0; i < p; ++i) {
    MimoFitOptions o;
    o.progress = [&](double f, const std::string& what) {
      report(0.4 * (static_cast<double>(i) + f) / static_cast<double>(p),
             "output " + std::to_string(i + 1) + " from its own input: " + what);
    };
    own.push_back(subset(spectra, {own_input[i]}, {i}));
    baselines.push_back(identify_mimo_linear(own.back(), o));
  }
  MimoFitOptions o;
  o.progress = [&](double f, const std::string& what) {
    report(0.4 + 0.4 * f, "every input: " + what);
  };
  const MimoFitResult ext = identify_mimo_linear(spectra, o);
  d.heldout = ext.heldout;
  d.extended_order = ext.order;
  d.extended = ext.model;
  // Shares of each output's power per input, through the extension fitted on all of it.
  const Eigen::MatrixXd shares = coupling_shares(ext.model, spectra);
  // One realization: the extension's held-out error on the odd bins, fitted on the even (one
  // figure for all outputs together).
  double one_realization_rms = ext.scores.empty() ? 0.0 : ext.scores.back().heldout_rms;
  for (const auto& s : ext.scores) {
    if (s.order == ext.order) one_realization_rms = s.heldout_rms;
  }
  for (std::size_t i = 0; i < p; ++i) {
    OutputCoupling c;
    c.output = i;
    c.own_input = own_input[i];
    c.baseline_order = baselines[i].order;
    c.baseline = baselines[i].model;
    for (const auto& s : baselines[i].scores) {
      if (s.order == baselines[i].order) c.baseline_heldout_rms = s.heldout_rms;
    }
    if (nr < 2) c.extended_heldout_rms = one_realization_rms;
    for (std::size_t j = 0; j < m; ++j) {
      c.shares.push_back(shares(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)));
      if (j != own_input[i] && c.shares.back() >= kCouplingNamedShare) c.named_inputs.push_back(j);
    }
    d.outputs.push_back(std::move(c));
  }
  // Each realization left out in turn: both models at their orders, fitted on the others. The
  // last realization left out is the extension's held-out figure (identify's test realization).
  for (std::size_t r = 0; nr >= 2 && r < nr; ++r) {
    report(0.8 + 0.2 * static_cast<double>(r) / static_cast<double>(nr),
           "realization " + std::to_string(r) + " left out");
    const std::vector<std::size_t> train = all_but(nr, r);
    const Eigen::VectorXd e =
        steady_state_rms(fit_mimo_linear(spectra, ext.order, train), spectra, {r});
    for (std::size_t i = 0; i < p; ++i) {
      const double b =
          steady_state_rms(fit_mimo_linear(own[i], baselines[i].order, train), own[i], {r})(0);
      const double x = e(static_cast<Eigen::Index>(i));
      if (r + 1 == nr) d.outputs[i].extended_heldout_rms = x;
      d.outputs[i].left_out_gains.push_back(x > 0.0 ? b / x : 0.0);
    }
  }
  for (auto& c : d.outputs) {
    c.gain = c.extended_heldout_rms > 0.0 ? c.baseline_heldout_rms / c.extended_heldout_rms : 0.0;
    double worst = c.gain;
    for (const double g : c.left_out_gains) worst = std::min(worst, g);
    c.named = worst >= kCouplingNamingGain && !c.named_inputs.empty();
  }
  report(1.0, "done");
  return d;
}

}  // namespace hystbench::compensation
