#include "hystbench/compensation/mimo_linear_model.hpp"

#include <stdexcept>

namespace hystbench::compensation {

namespace {

bool is_real(std::complex<double> p) { return p.imag() == 0.0; }

std::size_t term_count(const std::vector<std::complex<double>>& poles) {
  std::size_t n = 1;
  for (const auto p : poles) n += is_real(p) ? 1 : 2;
  return n;
}

}  // namespace

MimoLinearModel::MimoLinearModel(std::vector<std::complex<double>> poles,
                                 std::vector<Eigen::MatrixXd> terms, Eigen::VectorXd output_offset)
    : poles_(std::move(poles)), terms_(std::move(terms)), offset_(std::move(output_offset)) {
  if (terms_.size() != term_count(poles_)) {
    throw std::invalid_argument("MIMO linear model: " + std::to_string(terms_.size()) +
                                " terms for poles that need " + std::to_string(term_count(poles_)));
  }
  for (const auto& t : terms_) {
    if (t.rows() != terms_[0].rows() || t.cols() != terms_[0].cols() || t.size() == 0) {
      throw std::invalid_argument("MIMO linear model: terms of different or empty shapes");
    }
  }
  if (offset_.size() == 0) offset_ = Eigen::VectorXd::Zero(terms_[0].rows());
  if (offset_.size() != terms_[0].rows()) {
    throw std::invalid_argument("MIMO linear model: one output offset per output");
  }
  for (const auto p : poles_) {
    if (!(std::abs(p) < 1.0) || p.imag() < 0.0) {
      throw std::invalid_argument(
          "MIMO linear model: poles inside the unit circle, pairs once "
          "with Im p > 0");
    }
  }
}

std::size_t MimoLinearModel::order() const noexcept { return term_count(poles_) - 1; }

Eigen::VectorXcd MimoLinearModel::basis(const std::vector<std::complex<double>>& poles,
                                        std::complex<double> z) {
  Eigen::VectorXcd b(static_cast<Eigen::Index>(term_count(poles)));
  Eigen::Index q = 0;
  b(q++) = 1.0;
  const std::complex<double> j(0.0, 1.0);
  for (const auto p : poles) {
    const std::complex<double> a = 1.0 / (z - p);
    if (is_real(p)) {
      b(q++) = a;
    } else {
      const std::complex<double> c = 1.0 / (z - std::conj(p));
      b(q++) = a + c;
      b(q++) = j * (a - c);
    }
  }
  return b;
}

Eigen::MatrixXcd MimoLinearModel::response(std::complex<double> z) const {
  const Eigen::VectorXcd b = basis(poles_, z);
  Eigen::MatrixXcd g = Eigen::MatrixXcd::Zero(terms_[0].rows(), terms_[0].cols());
  for (Eigen::Index q = 0; q < b.size(); ++q) g += b(q) * terms_[static_cast<std::size_t>(q)];
  return g;
}

Eigen::MatrixXd MimoLinearModel::simulate(const Eigen::MatrixXd& u) const {
  if (static_cast<std::size_t>(u.rows()) != inputs()) {
    throw std::invalid_argument("MIMO linear model: " + std::to_string(u.rows()) +
                                " input rows for a model of " + std::to_string(inputs()));
  }
  const Eigen::Index n = u.cols();
  Eigen::MatrixXd y = terms_[0] * u;
  y.colwise() += offset_;
  std::size_t q = 1;
  for (const auto p : poles_) {
    // x(t+1) = p x(t) + u(t); the section's output at t is read from x(t).
    if (is_real(p)) {
      const Eigen::MatrixXd& r = terms_[q++];
      Eigen::VectorXd x = Eigen::VectorXd::Zero(u.rows());
      for (Eigen::Index t = 0; t < n; ++t) {
        y.col(t).noalias() += r * x;
        x *= p.real();
        x += u.col(t);
      }
    } else {
      const Eigen::MatrixXd two_a = 2.0 * terms_[q];
      const Eigen::MatrixXd minus_two_b = -2.0 * terms_[q + 1];
      q += 2;
      Eigen::VectorXd xr = Eigen::VectorXd::Zero(u.rows()), xi = xr, next = xr;
      const double pr = p.real(), pi = p.imag();
      for (Eigen::Index t = 0; t < n; ++t) {
        y.col(t).noalias() += two_a * xr;
        y.col(t).noalias() += minus_two_b * xi;
        next = pr * xr;
        next -= pi * xi;
        next += u.col(t);
        xi *= pr;
        xi += pi * xr;
        xr.swap(next);
      }
    }
  }
  return y;
}

}  // namespace hystbench::compensation
