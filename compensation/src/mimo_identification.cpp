#include "hystbench/compensation/mimo_identification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <unsupported/Eigen/FFT>

#include "details/parallel_tasks.hpp"
#include "hystbench/compensation/play_operator.hpp"

namespace hystbench::compensation {

namespace {

using cd = std::complex<double>;

// A bin is excited where the inputs' power is at least this fraction of the strongest bin's.
constexpr double kExcitedFraction = 1e-3;
// Sanathanan-Koerner: at most this many re-weightings, stopped when the denominator's
// coefficients move less than this (relative).
constexpr int kSkIterations = 30;
constexpr double kSkTolerance = 1e-6;
// A root this close to the real axis (relative to its modulus) is a real pole.
constexpr double kRealPole = 1e-9;
// Poles are kept at most this far out (a reflected or marginal root).
constexpr double kMaxPoleRadius = 0.9999;
// A lower order within this fraction of the best held-out error is preferred.
constexpr double kOrderTolerance = 0.02;

// Which realizations and bins a fit or a score uses.
struct Selection {
  std::vector<std::size_t> realizations;
  int bin_parity = -1;  // -1: every bin; 0 / 1: the even / odd bin indices only

  bool uses_bin(std::size_t k) const {
    return bin_parity < 0 || static_cast<int>(k % 2) == bin_parity;
  }
};

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

// The cross-spectra a fit needs at bin k, summed over the selected realizations:
// uu(j, j') = sum conj(U_j) U_j', yu(i, j) = sum conj(Y_i) U_j, yy(i) = sum |Y_i|^2.
struct CrossSpectra {
  std::vector<Eigen::MatrixXcd> uu, yu;
  std::vector<Eigen::VectorXd> yy;
  std::vector<std::size_t> k;  // the bin indices used
};

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
  LagSums t{std::vector<Eigen::MatrixXcd>(lags, Eigen::MatrixXcd::Zero(m, m)),
            std::vector<Eigen::MatrixXcd>(lags, Eigen::MatrixXcd::Zero(p, m)),
            std::vector<Eigen::VectorXd>(lags, Eigen::VectorXd::Zero(p)), n};
  for (std::size_t q = 0; q < c.k.size(); ++q) {
    const cd z = s.z(c.k[q]);
    cd zd = std::pow(z, -static_cast<double>(n));
    for (Eigen::Index d = 0; d < lags; ++d) {
      const cd f = w[q] * zd;
      t.uu[d] += f * c.uu[q];
      t.yu[d] += f * c.yu[q];
      t.yy[d] += w[q] * zd.real() * c.yy[q];
      zd *= z;
    }
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
  for (std::size_t q = 0; q < c.k.size(); ++q) {
    const cd z = s.z(c.k[q]);
    Eigen::VectorXcd zl(N + 1);
    zl(0) = 1.0;
    for (Eigen::Index l = 1; l <= N; ++l) zl(l) = zl(l - 1) / z;
    const cd den = 1.0 + (a.cast<cd>().array() * zl.tail(N).array()).sum();
    for (Eigen::Index i = 0; i < p; ++i) {
      Eigen::VectorXcd g(m);  // row i of G at z
      for (Eigen::Index j = 0; j < m; ++j) {
        g(j) = (b[static_cast<std::size_t>(i)].segment(j * (N + 1), N + 1).cast<cd>().array() *
                zl.array())
                   .sum() /
               den;
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

// The terms (D, then each pole's) of least output error with the poles fixed, and the offset.
MimoLinearModel residues(const PeriodicSpectra& s, const CrossSpectra& c,
                         const std::vector<cd>& poles) {
  const auto m = static_cast<Eigen::Index>(s.inputs()), p = static_cast<Eigen::Index>(s.outputs());
  const Eigen::Index nq = MimoLinearModel::basis(poles, cd(1.0, 0.0)).size();
  const Eigen::Index n = m * nq;  // unknowns per output: (j, q)
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, p);
  for (std::size_t q = 0; q < c.k.size(); ++q) {
    const Eigen::VectorXcd psi = MimoLinearModel::basis(poles, s.z(c.k[q]));
    const Eigen::MatrixXcd pp = psi.conjugate() * psi.transpose();  // conj(psi_q) psi_q'
    for (Eigen::Index j = 0; j < m; ++j) {
      for (Eigen::Index j2 = 0; j2 < m; ++j2) {
        a.block(j * nq, j2 * nq, nq, nq) += (pp * c.uu[q](j, j2)).real();
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

// The mean over periods [from, np) of the DFT of x (channels x (np n)) at `bins`.
Eigen::MatrixXcd averaged_dft(const Eigen::MatrixXd& x, std::size_t n, std::size_t np,
                              std::size_t from, const std::vector<std::size_t>& bins) {
  Eigen::FFT<double> fft;
  std::vector<double> buf(n);
  std::vector<cd> f;
  Eigen::MatrixXcd out = Eigen::MatrixXcd::Zero(x.rows(), static_cast<Eigen::Index>(bins.size()));
  for (Eigen::Index ch = 0; ch < x.rows(); ++ch) {
    for (std::size_t q = from; q < np; ++q) {
      for (std::size_t t = 0; t < n; ++t) buf[t] = x(ch, static_cast<Eigen::Index>(q * n + t));
      fft.fwd(f, buf);
      for (std::size_t k = 0; k < bins.size(); ++k) {
        out(ch, static_cast<Eigen::Index>(k)) += f[bins[k]] / static_cast<double>(np - from);
      }
    }
  }
  return out;
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

// Throws unless the record has a period of >= 4 samples, >= 1 period, dt > 0 and every
// realization channels x (periods x period) like the first.
void validate_periodic_record(const PeriodicRecord& record) {
  const std::size_t n = record.period, np = record.periods;
  if (n < 4 || np < 1 || !(record.dt > 0.0) || record.u.empty() ||
      record.u.size() != record.y.size()) {
    throw std::invalid_argument(
        "periodic record: needs a period of >= 4 samples, >= 1 period, dt > 0 and as many "
        "output realizations as input ones");
  }
  const Eigen::Index m = record.u[0].rows(), p = record.y[0].rows();
  for (std::size_t r = 0; r < record.u.size(); ++r) {
    if (record.u[r].rows() != m || record.y[r].rows() != p ||
        record.u[r].cols() != static_cast<Eigen::Index>(n * np) ||
        record.y[r].cols() != static_cast<Eigen::Index>(n * np) || m == 0 || p == 0) {
      throw std::invalid_argument("periodic record: realization " + std::to_string(r) +
                                  " is not channels x (periods x period) like the first");
    }
  }
}

// DFT of each period of each channel of each realization x[r] (channels x (np n)):
// [r][period] is channels x (n / 2 + 1).
std::vector<std::vector<Eigen::MatrixXcd>> period_dfts(const std::vector<Eigen::MatrixXd>& x,
                                                       std::size_t n, std::size_t np) {
  const std::size_t nr = x.size(), half = n / 2;
  Eigen::FFT<double> fft;
  std::vector<std::vector<Eigen::MatrixXcd>> out(nr);
  std::vector<double> buf(n);
  std::vector<cd> f;
  for (std::size_t r = 0; r < nr; ++r) {
    for (std::size_t q = 0; q < np; ++q) {
      Eigen::MatrixXcd per(x[r].rows(), static_cast<Eigen::Index>(half + 1));
      for (Eigen::Index ch = 0; ch < x[r].rows(); ++ch) {
        for (std::size_t t = 0; t < n; ++t) buf[t] = x[r](ch, static_cast<Eigen::Index>(q * n + t));
        fft.fwd(f, buf);
        for (std::size_t k = 0; k <= half; ++k) per(ch, static_cast<Eigen::Index>(k)) = f[k];
      }
      out[r].push_back(std::move(per));
    }
  }
  return out;
}

// The mean of the per-period spectra over the periods [from, np).
Eigen::MatrixXcd mean_over_periods(const std::vector<Eigen::MatrixXcd>& per, std::size_t from,
                                   std::size_t np) {
  Eigen::MatrixXcd avg = Eigen::MatrixXcd::Zero(per[0].rows(), per[0].cols());
  for (std::size_t q = from; q < np; ++q) avg += per[q];
  return Eigen::MatrixXcd(avg / static_cast<double>(np - from));
}

// The bins 1 .. n / 2 where the inputs' power (summed over the realizations' mean spectra ua) is
// at least kExcitedFraction of the strongest; DC and Nyquist never count.
std::vector<std::size_t> excited_bins(const std::vector<Eigen::MatrixXcd>& ua, std::size_t n) {
  const std::size_t half = n / 2;
  Eigen::VectorXd power = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(half + 1));
  for (const Eigen::MatrixXcd& u : ua) power += u.cwiseAbs2().colwise().sum().transpose();
  power(0) = 0.0;  // DC is the offset, not an excitation
  if (n % 2 == 0) power(static_cast<Eigen::Index>(half)) = 0.0;  // Nyquist: no phase
  const double strongest = power.maxCoeff();
  if (!(strongest > 0.0)) throw std::invalid_argument("periodic record: no excited frequency");
  std::vector<std::size_t> bins;
  for (std::size_t k = 1; k <= half; ++k) {
    if (power(static_cast<Eigen::Index>(k)) >= kExcitedFraction * strongest) bins.push_back(k);
  }
  return bins;
}

// Noise at s.bins: the scatter of one realization's output periods [from, np) about their mean,
// divided by their count (the mean's), added to s.noise_var for the nr realizations' average.
void add_period_scatter(PeriodicSpectra& s, const std::vector<Eigen::MatrixXcd>& ys,
                        std::size_t from, std::size_t np, std::size_t nr) {
  const auto kb = static_cast<Eigen::Index>(s.bins.size());
  const Eigen::MatrixXcd avg = mean_over_periods(ys, from, np);
  const double count = static_cast<double>(np - from);
  for (std::size_t q = from; q < np; ++q) {
    for (Eigen::Index k = 0; k < kb; ++k) {
      const auto b = static_cast<Eigen::Index>(s.bins[static_cast<std::size_t>(k)]);
      s.noise_var.col(k) += (ys[q].col(b) - avg.col(b)).cwiseAbs2() / ((count - 1.0) * count * nr);
    }
  }
}

}  // namespace

PeriodicSpectra with_inputs(const PeriodicSpectra& spectra, const std::vector<Eigen::MatrixXd>& v) {
  if (v.size() != spectra.u.size()) {
    throw std::invalid_argument("periodic spectra: one input matrix per realization");
  }
  PeriodicSpectra out = spectra;
  const std::size_t n = spectra.period;
  const std::size_t np = spectra.transient_periods + spectra.periods_used;
  out.u_mean = Eigen::VectorXd::Zero(v[0].rows());
  for (std::size_t r = 0; r < v.size(); ++r) {
    if (v[r].cols() != static_cast<Eigen::Index>(n * np) || v[r].rows() != v[0].rows()) {
      throw std::invalid_argument("periodic spectra: inputs of another length than the record's");
    }
    out.u[r] = averaged_dft(v[r], n, np, spectra.transient_periods, spectra.bins);
    out.u_mean +=
        v[r].rightCols(static_cast<Eigen::Index>(n * spectra.periods_used)).rowwise().mean() /
        static_cast<double>(v.size());
  }
  return out;
}

cd PeriodicSpectra::z(std::size_t k) const {
  return std::polar(
      1.0, 2.0 * std::numbers::pi * static_cast<double>(bins[k]) / static_cast<double>(period));
}

PeriodicSpectra periodic_spectra(const PeriodicRecord& record) {
  validate_periodic_record(record);
  const std::size_t n = record.period, np = record.periods;
  const Eigen::Index m = record.u[0].rows(), p = record.y[0].rows();
  PeriodicSpectra s;
  s.period = n;
  s.dt = record.dt;
  s.transient_periods = np >= 2 ? 1 : 0;
  s.periods_used = np - s.transient_periods;
  const std::size_t nr = record.u.size();
  const auto us = period_dfts(record.u, n, np), ys = period_dfts(record.y, n, np);
  // The steady state: the mean over the periods used.
  std::vector<Eigen::MatrixXcd> ua(nr), ya(nr);
  for (std::size_t r = 0; r < nr; ++r) {
    ua[r] = mean_over_periods(us[r], s.transient_periods, np);
    ya[r] = mean_over_periods(ys[r], s.transient_periods, np);
  }
  s.bins = excited_bins(ua, n);
  const auto kb = static_cast<Eigen::Index>(s.bins.size());
  s.noise_var = Eigen::MatrixXd::Zero(p, kb);
  s.u_mean = Eigen::VectorXd::Zero(m);
  s.y_mean = Eigen::VectorXd::Zero(p);
  const std::size_t from = s.periods_used >= 2 ? s.transient_periods : 0;
  for (std::size_t r = 0; r < nr; ++r) {
    Eigen::MatrixXcd u(m, kb), y(p, kb);
    for (Eigen::Index k = 0; k < kb; ++k) {
      u.col(k) = ua[r].col(static_cast<Eigen::Index>(s.bins[static_cast<std::size_t>(k)]));
      y.col(k) = ya[r].col(static_cast<Eigen::Index>(s.bins[static_cast<std::size_t>(k)]));
    }
    s.u.push_back(std::move(u));
    s.y.push_back(std::move(y));
    s.u_mean += ua[r].col(0).real() / static_cast<double>(n * nr);
    s.y_mean += ya[r].col(0).real() / static_cast<double>(n * nr);
    if (np - from >= 2) add_period_scatter(s, ys[r], from, np, nr);
  }
  return s;
}

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

namespace hystbench::compensation {

namespace {

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
      spec[r][j] = averaged_dft(basis[r][j], n, np, s.transient_periods, s.bins);
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

PeriodicSpectra subset(const PeriodicSpectra& spectra, const std::vector<std::size_t>& inputs,
                       const std::vector<std::size_t>& outputs) {
  for (const auto j : inputs) {
    if (j >= spectra.inputs())
      throw std::invalid_argument("spectra: no input " + std::to_string(j));
  }
  for (const auto i : outputs) {
    if (i >= spectra.outputs())
      throw std::invalid_argument("spectra: no output " + std::to_string(i));
  }
  const auto rows = [](const Eigen::MatrixXcd& m, const std::vector<std::size_t>& idx) {
    Eigen::MatrixXcd out(static_cast<Eigen::Index>(idx.size()), m.cols());
    for (std::size_t q = 0; q < idx.size(); ++q)
      out.row(static_cast<Eigen::Index>(q)) = m.row(static_cast<Eigen::Index>(idx[q]));
    return out;
  };
  PeriodicSpectra out = spectra;
  for (std::size_t r = 0; r < spectra.u.size(); ++r) {
    out.u[r] = rows(spectra.u[r], inputs);
    out.y[r] = rows(spectra.y[r], outputs);
  }
  out.noise_var =
      Eigen::MatrixXd(static_cast<Eigen::Index>(outputs.size()), spectra.noise_var.cols());
  out.u_mean.resize(static_cast<Eigen::Index>(inputs.size()));
  out.y_mean.resize(static_cast<Eigen::Index>(outputs.size()));
  for (std::size_t q = 0; q < outputs.size(); ++q) {
    out.noise_var.row(static_cast<Eigen::Index>(q)) =
        spectra.noise_var.row(static_cast<Eigen::Index>(outputs[q]));
    out.y_mean(static_cast<Eigen::Index>(q)) =
        spectra.y_mean(static_cast<Eigen::Index>(outputs[q]));
  }
  for (std::size_t q = 0; q < inputs.size(); ++q)
    out.u_mean(static_cast<Eigen::Index>(q)) = spectra.u_mean(static_cast<Eigen::Index>(inputs[q]));
  return out;
}

}  // namespace hystbench::compensation
