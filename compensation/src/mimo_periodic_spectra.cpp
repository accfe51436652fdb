// Periodic records read as spectra: the transient period dropped, the others averaged and read
// at the excited bins, the noise from the differences between periods.
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <unsupported/Eigen/FFT>

#include "details/periodic_dft.hpp"
#include "hystbench/compensation/mimo_identification.hpp"

namespace hystbench::compensation {

namespace details {

Eigen::MatrixXcd averaged_dft(const Eigen::MatrixXd& x, std::size_t n, std::size_t np,
                              std::size_t from, const std::vector<std::size_t>& bins) {
  Eigen::FFT<double> fft;
  std::vector<double> buf(n);
  std::vector<std::complex<double>> f;
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

}  // namespace details

namespace {

using cd = std::complex<double>;

// A bin is excited where the inputs' power is at least this fraction of the strongest bin's.
constexpr double kExcitedFraction = 1e-3;

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
    out.u[r] = details::averaged_dft(v[r], n, np, spectra.transient_periods, spectra.bins);
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