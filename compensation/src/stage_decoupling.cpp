#include "hystbench/compensation/stage_decoupling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace hystbench::compensation {

namespace {

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }

/// y = M x over the first min(size) values of each; M's entries beyond are taken as 0.
void multiply(const Eigen::MatrixXd& m, std::span<const double> x, std::span<double> y) noexcept {
  const auto n = static_cast<std::size_t>(m.rows());
  for (std::size_t i = 0; i < n && i < y.size(); ++i) {
    double sum = 0.0;
    for (std::size_t j = 0; j < n && j < x.size(); ++j) {
      sum += m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) * x[j];
    }
    y[i] = sum;
  }
}

}  // namespace

CouplingEstimate estimate_coupling_gains(std::span<const OneAxisMotion> records) {
  if (records.empty()) fail("coupling: no record");
  const Eigen::Index n = records.front().outputs.rows();
  double largest_spread = 0.0;
  for (std::size_t r = 0; r < records.size(); ++r) {
    const OneAxisMotion& rec = records[r];
    const std::string which = "coupling: record " + std::to_string(r);
    if (rec.outputs.rows() != n) {
      fail(which + " has " + std::to_string(rec.outputs.rows()) + " axes, record 0 has " +
           std::to_string(n));
    }
    if (rec.moved >= static_cast<std::size_t>(n)) {
      fail(which + " moved axis " + std::to_string(rec.moved) + " of " + std::to_string(n));
    }
    if (rec.outputs.cols() < 2) fail(which + " has fewer than 2 samples");
    if (!rec.outputs.allFinite()) fail(which + " holds a value that is not a finite number");
    const Eigen::VectorXd x = rec.outputs.row(static_cast<Eigen::Index>(rec.moved)).transpose();
    const double spread = std::sqrt((x.array() - x.mean()).square().mean());
    largest_spread = std::max(largest_spread, spread);
  }
  CouplingEstimate out;
  out.gains = Eigen::MatrixXd::Zero(n, n);
  out.residual_share = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    // Pooled sums over the records that moved axis j, each centred on its own means.
    double sxx = 0.0;
    Eigen::VectorXd sxy = Eigen::VectorXd::Zero(n), syy = Eigen::VectorXd::Zero(n);
    bool moved = false;
    for (const OneAxisMotion& rec : records) {
      if (static_cast<Eigen::Index>(rec.moved) != j) continue;
      moved = true;
      const Eigen::MatrixXd centred = rec.outputs.colwise() - rec.outputs.rowwise().mean();
      const Eigen::VectorXd x = centred.row(j).transpose();
      sxx += x.squaredNorm();
      sxy += centred * x;
      syy += centred.rowwise().squaredNorm();
    }
    if (!moved) fail("coupling: no record moved axis " + std::to_string(j) + " alone");
    if (!(sxx > 0.0) || std::sqrt(sxx) < 1e-9 * largest_spread) {
      fail("coupling: axis " + std::to_string(j) + " barely moved in its record");
    }
    for (Eigen::Index i = 0; i < n; ++i) {
      if (i == j) continue;
      const double k = sxy(i) / sxx;
      out.gains(i, j) = k;
      // What the line leaves: syy - k sxy (the normal equations), per the motion's own power.
      out.residual_share(i, j) = std::sqrt(std::max(0.0, syy(i) - k * sxy(i)) / sxx);
    }
  }
  return out;
}

StageDecoupler::StageDecoupler(const Eigen::MatrixXd& gains) : gains_(gains) {
  if (gains.rows() < 1 || gains.rows() != gains.cols()) {
    fail("decoupler: the gains must be a square matrix, got " + std::to_string(gains.rows()) +
         " x " + std::to_string(gains.cols()));
  }
  if (!gains.allFinite()) fail("decoupler: a gain is not a finite number");
  for (Eigen::Index i = 0; i < gains.rows(); ++i) {
    if (gains(i, i) != 0.0) {
      fail("decoupler: gains(" + std::to_string(i) + ", " + std::to_string(i) +
           ") must be 0 (an axis's own gain is its model's)");
    }
  }
  const Eigen::MatrixXd coupled = Eigen::MatrixXd::Identity(gains.rows(), gains.cols()) + gains;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(coupled);
  const Eigen::VectorXd& s = svd.singularValues();
  if (!(s(s.size() - 1) > 0.0) || s(0) / s(s.size() - 1) > 1e3) {
    fail("decoupler: I + gains is singular or ill-conditioned (condition number " +
         std::to_string(s(0) / s(s.size() - 1)) + " > 1000)");
  }
  coupled_ = coupled;
  inverse_ = coupled.inverse();
}

void StageDecoupler::apply(std::span<const double> stage, std::span<double> own) const noexcept {
  multiply(inverse_, stage, own);
}

void StageDecoupler::couple(std::span<const double> own, std::span<double> stage) const noexcept {
  multiply(coupled_, own, stage);
}

double gain_db(double gain) noexcept {
  return gain != 0.0 ? 20.0 * std::log10(std::abs(gain)) : -std::numeric_limits<double>::infinity();
}

StageFit fit_stage(std::span<const OneAxisMotion> records, const StageFitOptions& options) {
  if (options.stride == 0) fail("stage fit: stride must be >= 1");
  StageFit fit;
  fit.coupling = estimate_coupling_gains(records);
  const StageDecoupler decoupler(fit.coupling.gains);
  const auto n = static_cast<std::size_t>(fit.coupling.gains.rows());
  fit.coupling_db =
      Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n),
                                -std::numeric_limits<double>::infinity());
  for (Eigen::Index i = 0; i < fit.coupling.gains.rows(); ++i) {
    for (Eigen::Index j = 0; j < fit.coupling.gains.cols(); ++j) {
      if (i != j) fit.coupling_db(i, j) = gain_db(fit.coupling.gains(i, j));
    }
  }
  // Every record checked before the first (slow) fit.
  for (const OneAxisMotion& rec : records) {
    const std::string which = "stage fit: axis " + std::to_string(rec.moved) + ": ";
    if (rec.drive.size() != static_cast<std::size_t>(rec.outputs.cols())) {
      fail(which + "its drive has " + std::to_string(rec.drive.size()) + " samples, its outputs " +
           std::to_string(rec.outputs.cols()));
    }
    if (!(rec.dt > 0.0)) fail(which + "dt must be > 0");
  }
  for (std::size_t axis = 0; axis < n; ++axis) {
    const auto it = std::find_if(records.begin(), records.end(),
                                 [&](const OneAxisMotion& r) { return r.moved == axis; });
    const OneAxisMotion& rec = *it;  // estimate_coupling_gains() found one for every axis
    const std::string which = "stage fit: axis " + std::to_string(axis) + ": ";
    std::vector<double> t, u, own;
    std::vector<double> y(n), s(n);
    for (std::size_t k = 0; k < rec.drive.size(); k += options.stride) {
      for (std::size_t i = 0; i < n; ++i) {
        y[i] = rec.outputs(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k));
      }
      decoupler.apply(y, s);
      t.push_back(static_cast<double>(k) * rec.dt);
      u.push_back(rec.drive[k]);
      own.push_back(s[axis]);
    }
    try {
      fit.axes.push_back(fit_model(t, u, own, options.axis));
    } catch (const std::invalid_argument& e) {
      fail(which + e.what());
    }
  }
  return fit;
}

}  // namespace hystbench::compensation
