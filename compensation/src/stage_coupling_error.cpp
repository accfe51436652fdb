#include "hystbench/compensation/stage_coupling_error.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace hystbench::compensation {

CouplingErrorLeft coupling_error_left(const Eigen::MatrixXd& errors,
                                      const Eigen::MatrixXd& outputs) {
  if (errors.rows() != outputs.rows() || errors.cols() != outputs.cols()) {
    throw std::invalid_argument("coupling error: errors are " + std::to_string(errors.rows()) +
                                " x " + std::to_string(errors.cols()) + ", outputs " +
                                std::to_string(outputs.rows()) + " x " +
                                std::to_string(outputs.cols()));
  }
  const Eigen::Index n = errors.rows(), samples = errors.cols();
  if (n < 2) throw std::invalid_argument("coupling error: a stage has two axes at least");
  if (samples < 10) throw std::invalid_argument("coupling error: fewer than 10 samples");
  if (!errors.allFinite() || !outputs.allFinite()) {
    throw std::invalid_argument("coupling error: a value is not finite");
  }
  const Eigen::MatrixXd centred_y = outputs.colwise() - outputs.rowwise().mean();
  const Eigen::MatrixXd centred_e = errors.colwise() - errors.rowwise().mean();
  CouplingErrorLeft out;
  out.gains = Eigen::MatrixXd::Zero(n, n);
  out.rms_um = Eigen::VectorXd::Zero(n);
  out.error_rms_um =
      (errors.array().square().rowwise().sum() / static_cast<double>(samples)).sqrt().matrix();
  const double scale = std::max(1e-300, centred_y.cwiseAbs().maxCoeff());
  for (Eigen::Index i = 0; i < n; ++i) {
    // The other axes that moved: their centred outputs, samples x others.
    Eigen::MatrixXd x(samples, n - 1);
    std::vector<Eigen::Index> moved;
    for (Eigen::Index j = 0; j < n; ++j) {
      if (j == i) continue;
      const double sd = std::sqrt(centred_y.row(j).squaredNorm() / static_cast<double>(samples));
      if (sd <= 1e-12 * scale) continue;
      x.col(static_cast<Eigen::Index>(moved.size())) = centred_y.row(j).transpose();
      moved.push_back(j);
    }
    if (moved.empty()) continue;
    const auto m = static_cast<Eigen::Index>(moved.size());
    const Eigen::MatrixXd a = x.leftCols(m);
    const Eigen::VectorXd g = a.colPivHouseholderQr().solve(centred_e.row(i).transpose());
    for (Eigen::Index c = 0; c < m; ++c) out.gains(i, moved[static_cast<std::size_t>(c)]) = g(c);
    out.rms_um(i) = std::sqrt((a * g).squaredNorm() / static_cast<double>(samples));
  }
  return out;
}

}  // namespace hystbench::compensation
