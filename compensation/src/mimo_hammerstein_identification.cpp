// The Hammerstein identification of several inputs: a classical PI operator per input before
// the linear block, fitted by alternating least squares with its dynamics, and the coupling
// shares a model explains.
#include <algorithm>
#include <cmath>
#include <optional>

#include "details/mimo_frequency_fit.hpp"
#include "details/periodic_dft.hpp"
#include "hystbench/compensation/mimo_identification.hpp"
#include "hystbench/compensation/play_operator.hpp"

namespace hystbench::compensation {

namespace {

using details::mimo::cross_spectra;
using details::mimo::fit_on;
using details::mimo::heldout_split;
using details::mimo::kOrderTolerance;
using details::mimo::overall;
using details::mimo::residues;
using details::mimo::rms_on;
using details::mimo::select;
using details::mimo::Selection;

// The alternating fit of the operators' weights (thresholds given) and the dynamics of `order`
// on the realizations and bins of `sel`. basis[r][j] holds input j's play outputs
// (operators x (P N)) in realization r.
HammersteinMimoModel alternate(const PeriodicSpectra& s,
                               const std::vector<std::vector<Eigen::MatrixXd>>& basis,
                               const std::vector<std::vector<double>>& thresholds,
                               std::size_t order, std::size_t rounds, const Selection& sel) {
  const std::size_t m = s.inputs(), p = s.outputs(), nr = s.u.size();
  const std::size_t n = s.period, np = s.transient_periods + s.periods_used;
  // Each play's averaged spectrum: spec[r][j] is operators x K.
  std::vector<std::vector<Eigen::MatrixXcd>> spec(nr, std::vector<Eigen::MatrixXcd>(m));
  for (std::size_t r = 0; r < nr; ++r) {
    for (std::size_t j = 0; j < m; ++j) {
      spec[r][j] = details::averaged_dft(basis[r][j], n, np, s.transient_periods, s.bins);
    }
  }
  std::vector<Eigen::VectorXd> w(m);
  for (std::size_t j = 0; j < m; ++j) {
    w[j] = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(thresholds[j].size()));
    w[j](0) = 1.0;  // the input as it is: the play of threshold 0
  }
  const auto operator_outputs = [&] {
    std::vector<Eigen::MatrixXd> v(nr);
    for (std::size_t r = 0; r < nr; ++r) {
      v[r].resize(static_cast<Eigen::Index>(m), basis[r][0].cols());
      for (std::size_t j = 0; j < m; ++j)
        v[r].row(static_cast<Eigen::Index>(j)) = w[j].transpose() * basis[r][j];
    }
    return v;
  };
  MimoLinearModel g = fit_on(with_inputs(s, operator_outputs()), order, sel);
  for (std::size_t round = 0; round < rounds; ++round) {
    // The weights with the dynamics fixed: y_i = sum_j sum_l w_jl G_ij R_jl.
    Eigen::Index nw = 0;
    std::vector<Eigen::Index> at(m);
    for (std::size_t j = 0; j < m; ++j) at[j] = nw, nw += w[j].size();
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(nw, nw);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(nw);
    Eigen::MatrixXcd phi(static_cast<Eigen::Index>(p), nw);
    for (std::size_t k = 0; k < s.bins.size(); ++k) {
      if (!sel.uses_bin(k)) continue;
      const Eigen::MatrixXcd gk = g.response(s.z(k));
      const auto kk = static_cast<Eigen::Index>(k);
      for (const auto r : sel.realizations) {
        for (std::size_t j = 0; j < m; ++j) {
          phi.middleCols(at[j], w[j].size()) =
              gk.col(static_cast<Eigen::Index>(j)) * spec[r][j].col(kk).transpose();
        }
        a += (phi.adjoint() * phi).real();
        b += (phi.adjoint() * s.y[r].col(kk)).real();
      }
    }
    a.diagonal().array() += 1e-12 * a.diagonal().cwiseAbs().maxCoeff();
    const Eigen::VectorXd x = a.ldlt().solve(b);
    if (!x.allFinite()) break;
    for (std::size_t j = 0; j < m; ++j) {
      w[j] = x.segment(at[j], w[j].size());
      const double total = w[j].sum();  // the dynamics carry the gain: the weights sum to 1
      if (std::abs(total) > 1e-12) w[j] /= total;
    }
    // The poles kept within the rounds (the residues alone are cheap), refitted after them.
    const PeriodicSpectra sv = with_inputs(s, operator_outputs());
    g = round + 1 < rounds ? residues(sv, cross_spectra(sv, sel), g.poles())
                           : fit_on(sv, order, sel);
  }
  std::vector<std::optional<ActuatorModel>> ops(m);
  for (std::size_t j = 0; j < m; ++j) {
    ops[j] = classical_pi_operator(PiParameters{
        thresholds[j], std::vector<double>(w[j].data(), w[j].data() + w[j].size()), 0.0});
  }
  return HammersteinMimoModel(std::move(ops), std::move(g), s.dt);
}

// Steady-state rms over outputs of a Hammerstein model on `sel`.
double hammerstein_rms(const HammersteinMimoModel& model, const PeriodicSpectra& s,
                       const std::vector<Eigen::MatrixXd>& u, const Selection& sel) {
  std::vector<Eigen::MatrixXd> v(u.size());
  for (std::size_t r = 0; r < u.size(); ++r) v[r] = model.operator_outputs(u[r]);
  return overall(rms_on(model.dynamics(), with_inputs(s, v), sel));
}

}  // namespace

HammersteinFitResult identify_mimo_hammerstein(const PeriodicRecord& record,
                                               const HammersteinFitOptions& options) {
  const PeriodicSpectra s = periodic_spectra(record);
  HammersteinFitResult result;
  // The dynamics' orders take most of the time: 0-80 %, the operators the rest.
  constexpr double kLinearShare = 0.8;
  MimoFitOptions linear = options.linear;
  if (options.linear.progress && options.operators > 0) {
    linear.progress = [&](double f, const std::string& what) {
      options.linear.progress(kLinearShare * f, what);
    };
  }
  result.linear = identify_mimo_linear(s, linear);
  std::vector<std::optional<ActuatorModel>> none(s.inputs());
  result.model = HammersteinMimoModel(none, result.linear.model, s.dt);
  result.fit_rms = result.linear.fit_rms;
  const auto [train, test] = heldout_split(s, result.heldout);
  for (const auto& sc : result.linear.scores) {
    if (sc.order == result.linear.order) result.heldout_linear = sc.heldout_rms;
  }
  result.heldout_hammerstein = result.heldout_linear;
  if (options.operators == 0) return result;
  const std::size_t m = s.inputs(), nr = record.u.size();
  std::vector<std::vector<double>> thresholds(m);
  for (std::size_t j = 0; j < m; ++j) {
    double lo = record.u[0](static_cast<Eigen::Index>(j), 0), hi = lo;
    for (const auto& u : record.u) {
      lo = std::min(lo, u.row(static_cast<Eigen::Index>(j)).minCoeff());
      hi = std::max(hi, u.row(static_cast<Eigen::Index>(j)).maxCoeff());
    }
    thresholds[j] = uniform_thresholds(options.operators, 0.5 * (hi - lo));
  }
  std::vector<std::vector<Eigen::MatrixXd>> basis(nr, std::vector<Eigen::MatrixXd>(m));
  for (std::size_t r = 0; r < nr; ++r) {
    for (std::size_t j = 0; j < m; ++j) {
      const auto row = record.u[r].row(static_cast<Eigen::Index>(j));
      Eigen::MatrixXd plays(static_cast<Eigen::Index>(options.operators), row.size());
      for (std::size_t l = 0; l < options.operators; ++l) {
        PlayOperator play(thresholds[j][l], row(0));
        for (Eigen::Index t = 0; t < row.size(); ++t)
          plays(static_cast<Eigen::Index>(l), t) = play.step(row(t));
      }
      basis[r][j] = std::move(plays);
    }
  }
  const auto report = [&](double f, const std::string& what) {
    if (options.linear.progress)
      options.linear.progress(kLinearShare + (1.0 - kLinearShare) * f, what);
  };
  report(0.0, "hysteresis operators per input");
  const HammersteinMimoModel held =
      alternate(s, basis, thresholds, result.linear.order, options.rounds, train);
  result.heldout_hammerstein = hammerstein_rms(held, s, record.u, test);
  result.hysteresis_kept =
      result.heldout_hammerstein <= (1.0 - kOrderTolerance) * result.heldout_linear;
  if (result.hysteresis_kept) {
    report(0.5, "hysteresis operators on all of it");
    result.model =
        alternate(s, basis, thresholds, result.linear.order, options.rounds, select(s, {}));
    std::vector<Eigen::MatrixXd> v(nr);
    for (std::size_t r = 0; r < nr; ++r) v[r] = result.model.operator_outputs(record.u[r]);
    result.fit_rms = rms_on(result.model.dynamics(), with_inputs(s, v), select(s, {}));
  }
  report(1.0, "done");
  return result;
}

Eigen::MatrixXd coupling_shares(const MimoLinearModel& dynamics, const PeriodicSpectra& spectra) {
  const auto m = static_cast<Eigen::Index>(spectra.inputs());
  const auto p = static_cast<Eigen::Index>(spectra.outputs());
  Eigen::MatrixXd explained = Eigen::MatrixXd::Zero(p, m);
  Eigen::VectorXd total = Eigen::VectorXd::Zero(p);
  for (std::size_t k = 0; k < spectra.bins.size(); ++k) {
    const Eigen::MatrixXcd g = dynamics.response(spectra.z(k));
    const auto kk = static_cast<Eigen::Index>(k);
    for (std::size_t r = 0; r < spectra.u.size(); ++r) {
      for (Eigen::Index j = 0; j < m; ++j)
        explained.col(j) += (g.col(j) * spectra.u[r](j, kk)).cwiseAbs2();
      total += spectra.y[r].col(kk).cwiseAbs2();
    }
  }
  for (Eigen::Index i = 0; i < p; ++i) {
    if (total(i) > 0.0) explained.row(i) /= total(i);
  }
  return explained;
}

Eigen::MatrixXd coupling_shares(const HammersteinMimoModel& model, const PeriodicRecord& record) {
  const PeriodicSpectra s = periodic_spectra(record);
  std::vector<Eigen::MatrixXd> v(record.u.size());
  for (std::size_t r = 0; r < v.size(); ++r) v[r] = model.operator_outputs(record.u[r]);
  // The shares of the outputs' power: the inputs through their operators, the outputs as measured.
  return coupling_shares(model.dynamics(), with_inputs(s, v));
}

}  // namespace hystbench::compensation
