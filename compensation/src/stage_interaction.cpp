#include "hystbench/compensation/stage_interaction.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hystbench::compensation {

namespace {

// The index of `f` among r's lines, or -1 (equal within a millionth of it).
long line_of(const MeasuredResponse& r, double f) {
  for (std::size_t k = 0; k < r.size(); ++k) {
    if (std::abs(r.frequency_hz[k] - f) <= 1e-6 * f) return static_cast<long>(k);
  }
  return -1;
}

}  // namespace

StageInteraction stage_interaction(const std::vector<std::vector<MeasuredResponse>>& g,
                                   const std::vector<std::vector<std::complex<double>>>& loops) {
  const std::size_t n = g.size();
  if (n < 2) throw std::invalid_argument("stage_interaction: a stage has two axes or more");
  for (const auto& row : g) {
    if (row.size() != n) throw std::invalid_argument("stage_interaction: g must be square");
  }
  if (loops.size() != n) {
    throw std::invalid_argument("stage_interaction: " + std::to_string(loops.size()) +
                                " loops for " + std::to_string(n) + " axes");
  }
  StageInteraction out;
  const MeasuredResponse& first = g[0][0];
  using Matrix = Eigen::MatrixXcd;
  const auto size = static_cast<Eigen::Index>(n);
  for (std::size_t k = 0; k < first.size(); ++k) {
    const double f = first.frequency_hz[k];
    Matrix et = Matrix::Zero(size, size);
    bool shared = true;
    for (std::size_t j = 0; j < n && shared; ++j) {
      const long kj = line_of(g[j][j], f);
      shared = kj >= 0 && static_cast<std::size_t>(kj) < loops[j].size();
      if (!shared) break;
      const std::complex<double> gjj = g[j][j].response[static_cast<std::size_t>(kj)];
      const std::complex<double> l = loops[j][static_cast<std::size_t>(kj)];
      const std::complex<double> t = l / (1.0 + l);
      for (std::size_t i = 0; i < n && shared; ++i) {
        if (i == j) continue;
        const long kij = line_of(g[i][j], f);
        shared = kij >= 0 && std::abs(gjj) > 0.0;
        if (!shared) break;
        et(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
            g[i][j].response[static_cast<std::size_t>(kij)] / gjj * t;
      }
    }
    if (!shared) continue;
    const Eigen::ComplexEigenSolver<Matrix> eig(et, false);
    const double rho = eig.eigenvalues().cwiseAbs().maxCoeff();
    out.frequency_hz.push_back(f);
    out.spectral_radius.push_back(rho);
    if (rho > out.peak) {
      out.peak = rho;
      out.peak_hz = f;
    }
  }
  if (out.frequency_hz.empty()) {
    throw std::invalid_argument("stage_interaction: no line every response shares");
  }
  return out;
}

}  // namespace hystbench::compensation
