#include "hystbench/compensation/mimo_identification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "details/mimo_frequency_fit.hpp"
#include "details/parallel_tasks.hpp"

namespace hystbench::compensation::details::mimo {

namespace {

using cd = std::complex<double>;

// Sanathanan-Koerner: at most this many re-weightings, stopped when the denominator's
// coefficients move less than this (relative).
constexpr int kSkIterations = 30;
constexpr double kSkTolerance = 1e-6;
// A root this close to the real axis (relative to its modulus) is a real pole.
constexpr double kRealPole = 1e-9;
// Poles are kept at most this far out (a reflected or marginal root).
constexpr double kMaxPoleRadius = 0.9999;

// The denominator a(z) = 1 + sum_l a_l z^-l at z.
cd denominator(const Eigen::VectorXd& a, cd z) {
  cd v = 1.0, zl = 1.0;
  const cd zi = 1.0 / z;
  for (Eigen::Index l = 0; l < a.size(); ++l) {
    zl *= zi;
    v += a(l) * zl;
  }
  return v;
}

/// The weighted lag sums T(d) = sum_k w_k z_k^d S(k), d in [-n, n], of each cross-spectrum.
struct LagSums {
  std::vector<Eigen::MatrixXcd> uu, yu;  ///< at index d + n
  std::vector<Eigen::VectorXd> yy;       ///< at index d + n
  Eigen::Index n = 0;

  Eigen::Index lag(Eigen::Index d) const { return d + n; }
};

// The lag sums of the cross-spectra c with the bin weights w, for order n.
LagSums lag_sums(const PeriodicSpectra& s, const CrossSpectra& c, const std::vector<double>& w,
                 Eigen::Index n) {
  const auto m = static_cast<Eigen::Index>(s.inputs()), p = static_cast<Eigen::Index>(s.outputs());
  const Eigen::Index lags = 2 * n + 1;  // d = -n .. n at index d + n
  const auto bins = static_cast<Eigen::Index>(c.k.size());
  // One product for every lag and entry: the weights (lag x bin) times the cross-spectra stacked
  // one bin a row, uu's entries, then yu's, then yy's.
  Eigen::MatrixXcd weights(lags, bins);
  Eigen::MatrixXcd spectra(bins, m * m + p * m + p);
  for (Eigen::Index q = 0; q < bins; ++q) {
    const auto qi = static_cast<std::size_t>(q);
    const cd z = s.z(c.k[qi]);
    cd zd = std::pow(z, -static_cast<double>(n));
    for (Eigen::Index d = 0; d < lags; ++d) {
      weights(d, q) = w[qi] * zd;
      zd *= z;
    }
    spectra.row(q).head(m * m) = c.uu[qi].reshaped().transpose();
    spectra.row(q).segment(m * m, p * m) = c.yu[qi].reshaped().transpose();
    spectra.row(q).tail(p) = c.yy[qi].transpose().cast<cd>();
  }
  const Eigen::MatrixXcd sums = weights * spectra;
  LagSums t{std::vector<Eigen::MatrixXcd>(lags), std::vector<Eigen::MatrixXcd>(lags),
            std::vector<Eigen::VectorXd>(lags), n};
  for (Eigen::Index d = 0; d < lags; ++d) {
    const auto di = static_cast<std::size_t>(d);
    t.uu[di] = sums.row(d).head(m * m).reshaped(m, m);
    t.yu[di] = sums.row(d).segment(m * m, p * m).reshaped(p, m);
    // w and yy are real: sum w Re(z^d) yy = Re(sum w z^d yy).
    t.yy[di] = sums.row(d).tail(p).transpose().real();
  }
  return t;
}

// The numerators' block (j, l) l = 0..n of the normal equations, the same for every output.
Eigen::MatrixXd numerator_block(const LagSums& t, Eigen::Index m) {
  const Eigen::Index N = t.n;
  const Eigen::Index nb = m * (N + 1);
  Eigen::MatrixXd mbb(nb, nb);
  for (Eigen::Index j = 0; j < m; ++j) {
    for (Eigen::Index l = 0; l <= N; ++l) {
      for (Eigen::Index j2 = 0; j2 < m; ++j2) {
        for (Eigen::Index l2 = 0; l2 <= N; ++l2) {
          mbb(j * (N + 1) + l, j2 * (N + 1) + l2) = t.uu[t.lag(l - l2)](j, j2).real();
        }
      }
    }
  }
  return mbb;
}

/// The denominator with the numerators eliminated, and what gives them back:
/// b_i = M_bb^-1 rb_i - x_i a, rows (j, l).
struct Elimination {
  Eigen::VectorXd a;
  std::vector<Eigen::MatrixXd> x;   ///< per output: M_bb^-1 M_ab^T
  std::vector<Eigen::VectorXd> rb;  ///< per output: the numerators' right-hand side
};

// The denominator's normal equations, the numerators eliminated output by output, solved.
Elimination eliminate_numerators(const LagSums& t, const Eigen::LDLT<Eigen::MatrixXd>& bb,
                                 Eigen::Index m, Eigen::Index p) {
  const Eigen::Index N = t.n;
  const Eigen::Index nb = m * (N + 1);
  Eigen::MatrixXd reduced = Eigen::MatrixXd::Zero(N, N);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(N);
  Elimination e{Eigen::VectorXd(), std::vector<Eigen::MatrixXd>(static_cast<std::size_t>(p)),
                std::vector<Eigen::VectorXd>(static_cast<std::size_t>(p))};
  for (Eigen::Index i = 0; i < p; ++i) {
    Eigen::MatrixXd maa(N, N), mab(N, nb);
    Eigen::VectorXd ra(N), rb(nb);
    for (Eigen::Index l = 1; l <= N; ++l) {
      for (Eigen::Index l2 = 1; l2 <= N; ++l2) maa(l - 1, l2 - 1) = t.yy[t.lag(l - l2)](i);
      for (Eigen::Index j = 0; j < m; ++j) {
        for (Eigen::Index l2 = 0; l2 <= N; ++l2) {
          mab(l - 1, j * (N + 1) + l2) = -t.yu[t.lag(l - l2)](i, j).real();
        }
      }
      ra(l - 1) = -t.yy[t.lag(l)](i);
    }
    for (Eigen::Index j = 0; j < m; ++j) {
      for (Eigen::Index l = 0; l <= N; ++l) rb(j * (N + 1) + l) = t.yu[t.lag(-l)](i, j).real();
    }
    const Eigen::MatrixXd x = bb.solve(mab.transpose());
    reduced += maa - mab * x;
    rhs += ra - x.transpose() * rb;
    e.x[static_cast<std::size_t>(i)] = x;
    e.rb[static_cast<std::size_t>(i)] = rb;
  }
  e.a = reduced.ldlt().solve(rhs);
  return e;
}

// The output error sum_k sum_r sum_i |Y - B/a U|^2 of the rational model with denominator a and
// numerators b (one per output, rows (j, l)) of order n.
double output_error(const PeriodicSpectra& s, const CrossSpectra& c, const Eigen::VectorXd& a,
                    const std::vector<Eigen::VectorXd>& b, Eigen::Index N) {
  const auto m = static_cast<Eigen::Index>(s.inputs()), p = static_cast<Eigen::Index>(s.outputs());
  double cost = 0.0;
  Eigen::VectorXcd zl(N + 1);  // z^-l, l = 0..N
  Eigen::VectorXcd g(m);       // row i of G at z
  for (std::size_t q = 0; q < c.k.size(); ++q) {
    const cd z_inverse = 1.0 / s.z(c.k[q]);
    zl(0) = 1.0;
    for (Eigen::Index l = 1; l <= N; ++l) zl(l) = zl(l - 1) * z_inverse;
    // dot() conjugates its left side: real coefficients there, the powers of z on the right.
    const cd den_inverse = 1.0 / (1.0 + a.cast<cd>().dot(zl.tail(N)));
    for (Eigen::Index i = 0; i < p; ++i) {
      for (Eigen::Index j = 0; j < m; ++j) {
        g(j) = b[static_cast<std::size_t>(i)].segment(j * (N + 1), N + 1).cast<cd>().dot(zl) *
               den_inverse;
      }
      // |Y - g U|^2 summed over r: yy - 2 Re(sum_j g_j conj(yu_ij)... ) + g^H uu^T g.
      const cd cross = (g.array() * c.yu[q].row(i).transpose().array()).sum();
      const cd quad = (g.conjugate().transpose() * c.uu[q].transpose() * g)(0, 0);
      cost += c.yy[q](i) - 2.0 * cross.real() + quad.real();
    }
  }
  return cost;
}

// One Sanathanan-Koerner step: the denominator minimising
//   sum_k w_k sum_r sum_i |a(z_k) Y_ir - sum_j B_ij(z_k) U_jr|^2,
// the numerators (order n, with feedthrough) eliminated. Only the weighted lag sums
// T(d) = sum_k w_k z_k^d S(k), d in [-n, n], of each cross-spectrum enter.
// Returns the denominator's coefficients and the output error sum_k sum_r sum_i |Y - B/a U|^2 of
// the rational model it and its eliminated numerators make.
std::pair<Eigen::VectorXd, double> sk_step(const PeriodicSpectra& s, const CrossSpectra& c,
                                           const std::vector<double>& w, std::size_t n) {
  const auto m = static_cast<Eigen::Index>(s.inputs()), p = static_cast<Eigen::Index>(s.outputs());
  const auto N = static_cast<Eigen::Index>(n);
  const LagSums t = lag_sums(s, c, w, N);
  const Eigen::LDLT<Eigen::MatrixXd> bb(numerator_block(t, m));
  const Elimination e = eliminate_numerators(t, bb, m, p);
  // The numerators b_i = M_bb^-1 rb_i - x_i a, rows (j, l), and the model's output error:
  // sum |Y_i - g_i U|^2 = yy_i - 2 Re(g_i^H conj(yu_i)^T... ) + g_i^H uu g_i per bin, g = B/a.
  std::vector<Eigen::VectorXd> b(static_cast<std::size_t>(p));
  for (Eigen::Index i = 0; i < p; ++i) {
    const auto ii = static_cast<std::size_t>(i);
    b[ii] = bb.solve(e.rb[ii]) - e.x[ii] * e.a;
  }
  return {e.a, output_error(s, c, e.a, b, N)};
}

// The stable poles of a(z), pairs once with Im > 0.
std::vector<cd> poles_of(const Eigen::VectorXd& a) {
  const Eigen::Index n = a.size();
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index l = 0; l < n; ++l) companion(0, l) = -a(l);
  for (Eigen::Index l = 1; l < n; ++l) companion(l, l - 1) = 1.0;
  const Eigen::VectorXcd roots =
      Eigen::EigenSolver<Eigen::MatrixXd>(companion, false).eigenvalues();
  std::vector<cd> poles;
  for (const cd r0 : roots) {
    cd r = r0;
    if (std::abs(r) >= 1.0) r = 1.0 / std::conj(r);  // reflected: same magnitude response
    if (std::abs(r) > kMaxPoleRadius) r *= kMaxPoleRadius / std::abs(r);
    if (std::abs(r.imag()) <= kRealPole * std::max(std::abs(r), 1e-12)) {
      poles.emplace_back(r.real(), 0.0);
    } else if (r.imag() > 0.0) {
      poles.push_back(r);
    }
  }
  return poles;
}

}  // namespace

Selection select(const PeriodicSpectra& s, const std::vector<std::size_t>& realizations) {
  Selection sel{realizations, -1};
  if (sel.realizations.empty()) {
    for (std::size_t r = 0; r < s.u.size(); ++r) sel.realizations.push_back(r);
  }
  for (const auto r : sel.realizations) {
    if (r >= s.u.size())
      throw std::invalid_argument("MIMO fit: no realization " + std::to_string(r));
  }
  return sel;
}

CrossSpectra cross_spectra(const PeriodicSpectra& s, const Selection& sel) {
  CrossSpectra c;
  const auto m = static_cast<Eigen::Index>(s.inputs()), p = static_cast<Eigen::Index>(s.outputs());
  for (std::size_t k = 0; k < s.bins.size(); ++k) {
    if (!sel.uses_bin(k)) continue;
    Eigen::MatrixXcd uu = Eigen::MatrixXcd::Zero(m, m), yu = Eigen::MatrixXcd::Zero(p, m);
    Eigen::VectorXd yy = Eigen::VectorXd::Zero(p);
    const auto kk = static_cast<Eigen::Index>(k);
    for (const auto r : sel.realizations) {
      const Eigen::VectorXcd u = s.u[r].col(kk), y = s.y[r].col(kk);
      uu += u.conjugate() * u.transpose();
      yu += y.conjugate() * u.transpose();
      yy += y.cwiseAbs2();
    }
    c.uu.push_back(std::move(uu));
    c.yu.push_back(std::move(yu));
    c.yy.push_back(std::move(yy));
    c.k.push_back(k);
  }
  return c;
}

// The terms (D, then each pole's) of least output error with the poles fixed, and the offset.
MimoLinearModel residues(const PeriodicSpectra& s, const CrossSpectra& c,
                         const std::vector<cd>& poles) {
  const auto m = static_cast<Eigen::Index>(s.inputs()), p = static_cast<Eigen::Index>(s.outputs());
  const Eigen::Index nq = MimoLinearModel::basis(poles, cd(1.0, 0.0)).size();
  const Eigen::Index n = m * nq;  // unknowns per output: (j, q)
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, p);
  Eigen::MatrixXd pp_re(nq, nq), pp_im(nq, nq);
  for (std::size_t q = 0; q < c.k.size(); ++q) {
    const Eigen::VectorXcd psi = MimoLinearModel::basis(poles, s.z(c.k[q]));
    // pp = conj(psi_q) psi_q', kept as its real and imaginary parts:
    // Re(pp u) = Re(pp) Re(u) - Im(pp) Im(u).
    const Eigen::VectorXd re = psi.real(), im = psi.imag();
    pp_re.noalias() = re * re.transpose();
    pp_re.noalias() += im * im.transpose();
    pp_im.noalias() = re * im.transpose();
    pp_im.noalias() -= im * re.transpose();
    for (Eigen::Index j = 0; j < m; ++j) {
      for (Eigen::Index j2 = 0; j2 < m; ++j2) {
        const cd u = c.uu[q](j, j2);
        a.block(j * nq, j2 * nq, nq, nq) += u.real() * pp_re - u.imag() * pp_im;
      }
      for (Eigen::Index i = 0; i < p; ++i) {
        rhs.block(j * nq, i, nq, 1) += (psi.conjugate() * std::conj(c.yu[q](i, j))).real();
      }
    }
  }
  // A tiny ridge: a term the bins cannot tell from another stays small instead of exploding.
  const double ridge = 1e-12 * a.diagonal().cwiseAbs().maxCoeff();
  a.diagonal().array() += ridge;
  const Eigen::MatrixXd theta = a.ldlt().solve(rhs);  // (j, q) x i
  std::vector<Eigen::MatrixXd> terms(static_cast<std::size_t>(nq), Eigen::MatrixXd::Zero(p, m));
  for (Eigen::Index q = 0; q < nq; ++q) {
    for (Eigen::Index i = 0; i < p; ++i) {
      for (Eigen::Index j = 0; j < m; ++j) {
        terms[static_cast<std::size_t>(q)](i, j) = theta(j * nq + q, i);
      }
    }
  }
  MimoLinearModel model(poles, terms, Eigen::VectorXd::Zero(p));
  // The offset: what the steady state's mean output holds beyond the model's DC gain.
  const Eigen::VectorXd offset = s.y_mean - model.response(cd(1.0, 0.0)).real() * s.u_mean;
  return MimoLinearModel(poles, std::move(terms), offset);
}

MimoLinearModel fit_on(const PeriodicSpectra& s, std::size_t order, const Selection& sel) {
  if (order < 1) throw std::invalid_argument("MIMO fit: an order of at least 1");
  const CrossSpectra c = cross_spectra(s, sel);
  if (c.k.size() < order + 1) {
    throw std::invalid_argument("MIMO fit: order " + std::to_string(order) + " needs more than " +
                                std::to_string(c.k.size()) + " excited bins");
  }
  std::vector<double> w(c.k.size(), 1.0);
  Eigen::VectorXd a = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(order)), best = a;
  double best_cost = std::numeric_limits<double>::infinity();
  // The iterations need not fall monotonically: the one of least output error is kept.
  for (int it = 0; it < kSkIterations; ++it) {
    const auto [next, cost] = sk_step(s, c, w, order);
    if (!next.allFinite() || !std::isfinite(cost)) break;
    const double change = (next - a).norm() / std::max(1.0, next.norm());
    a = next;
    if (cost < best_cost) best_cost = cost, best = a;
    for (std::size_t q = 0; q < c.k.size(); ++q)
      w[q] = 1.0 / std::norm(denominator(a, s.z(c.k[q])));
    if (change < kSkTolerance) break;
  }
  return residues(s, c, poles_of(best));
}

Eigen::VectorXd rms_on(const MimoLinearModel& model, const PeriodicSpectra& s,
                       const Selection& sel) {
  const auto p = static_cast<Eigen::Index>(s.outputs());
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(p);
  for (std::size_t k = 0; k < s.bins.size(); ++k) {
    if (!sel.uses_bin(k)) continue;
    const Eigen::MatrixXcd g = model.response(s.z(k));
    const auto kk = static_cast<Eigen::Index>(k);
    for (const auto r : sel.realizations) {
      sum += (s.y[r].col(kk) - g * s.u[r].col(kk)).cwiseAbs2();
    }
  }
  // Parseval, one-sided: mean square = 2 sum |E_k|^2 / N^2, over the realizations.
  const double n = static_cast<double>(s.period);
  const double scale = 2.0 / (n * n * static_cast<double>(sel.realizations.size()));
  return (sum * scale).cwiseSqrt();
}

// The held-out split of identify_*: the last realization where there are several, else the
// odd bins.
std::pair<Selection, Selection> heldout_split(const PeriodicSpectra& s, std::string& what) {
  Selection train = select(s, {}), test = train;
  const std::size_t nr = s.u.size();
  if (nr >= 2) {
    train.realizations.pop_back();
    test.realizations = {nr - 1};
    what = "realization " + std::to_string(nr - 1);
  } else {
    train.bin_parity = 0;
    test.bin_parity = 1;
    what = "odd bins";
  }
  return {train, test};
}

double overall(const Eigen::VectorXd& per_output) {
  return std::sqrt(per_output.squaredNorm() / static_cast<double>(per_output.size()));
}

}  // namespace hystbench::compensation::details::mimo

namespace hystbench::compensation {

namespace {

using details::mimo::fit_on;
using details::mimo::heldout_split;
using details::mimo::kOrderTolerance;
using details::mimo::overall;
using details::mimo::rms_on;
using details::mimo::select;
using details::mimo::Selection;

}  // namespace

Eigen::VectorXd steady_state_rms(const MimoLinearModel& model, const PeriodicSpectra& spectra,
                                 const std::vector<std::size_t>& realizations) {
  return rms_on(model, spectra, select(spectra, realizations));
}

MimoLinearModel fit_mimo_linear(const PeriodicSpectra& spectra, std::size_t order,
                                const std::vector<std::size_t>& realizations) {
  return fit_on(spectra, order, select(spectra, realizations));
}

MimoFitResult identify_mimo_linear(const PeriodicSpectra& spectra, const MimoFitOptions& options) {
  std::vector<std::size_t> orders = options.orders;
  if (orders.empty()) {
    for (std::size_t n = 2; n <= 40; n += 2) orders.push_back(n);
  }
  MimoFitResult result;
  // Named, not bound: the candidates' tasks capture them.
  const std::pair<Selection, Selection> split = heldout_split(spectra, result.heldout);
  const Selection& train = split.first;
  const Selection& test = split.second;
  const auto report = [&](double f, const std::string& what) {
    if (options.progress) options.progress(f, what);
  };
  // The candidates are independent: one per core. An order the bins cannot carry ends the list.
  std::vector<std::optional<double>> heldout(orders.size());
  const double scan_share =
      static_cast<double>(orders.size()) / static_cast<double>(orders.size() + 1);
  details::SharedProgress scanned(
      orders.size(), [&](double f, const std::string& what) { report(scan_share * f, what); });
  details::run_parallel(orders.size(), [&](std::size_t q) {
    try {
      const MimoLinearModel m = fit_on(spectra, orders[q], train);
      heldout[q] = overall(rms_on(m, spectra, test));
    } catch (const std::invalid_argument&) {
      // more order than the bins carry
    }
    scanned(q, 1.0, "order " + std::to_string(orders[q]));
  });
  for (std::size_t q = 0; q < orders.size() && heldout[q]; ++q) {
    result.scores.push_back({orders[q], *heldout[q]});
  }
  if (result.scores.empty()) {
    throw std::invalid_argument("MIMO fit: no candidate order fits " +
                                std::to_string(spectra.bins.size()) + " excited bins");
  }
  double best = result.scores.front().heldout_rms;
  for (const auto& sc : result.scores) best = std::min(best, sc.heldout_rms);
  // Errors at the rounding floor are equal whatever their ratio.
  double y_power = 0.0;
  for (const auto r : test.realizations) y_power += spectra.y[r].cwiseAbs2().sum();
  const double floor = 1e-9 * std::sqrt(y_power) / static_cast<double>(spectra.period);
  for (const auto& sc : result.scores) {
    if (sc.heldout_rms <= (1.0 + kOrderTolerance) * best + floor) {
      result.order = sc.order;
      break;
    }
  }
  report(static_cast<double>(orders.size()) / static_cast<double>(orders.size() + 1),
         "order " + std::to_string(result.order) + " on all of it");
  result.model = fit_on(spectra, result.order, select(spectra, {}));
  result.fit_rms = rms_on(result.model, spectra, select(spectra, {}));
  report(1.0, "done");
  return result;
}

}  // namespace hystbench::compensation
