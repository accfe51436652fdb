#pragma once
// A discrete-time linear dynamic block with m inputs and p outputs in pole-residue form: every
// entry shares the poles (a structure's modes),
//   G(z) = D + sum over real poles   R_q / (z - p_q)
//            + sum over pairs (p, p*)  [A_q (1/(z-p) + 1/(z-p*)) + B_q j (1/(z-p) - 1/(z-p*))],
// with real p x m matrices D, R_q, A_q, B_q, plus a constant output offset. Simulated as parallel
// first-order sections (well conditioned at any order), from rest. Units: the input's and the
// output's as given; z = exp(j 2 pi f dt). Pure maths; simulate() allocates its result.
#include <Eigen/Dense>
#include <complex>
#include <cstddef>
#include <vector>

namespace hystbench::compensation {

class MimoLinearModel {
 public:
  MimoLinearModel() = default;
  /// poles: stable (|p| < 1); complex ones given once each (Im p > 0), their conjugate implied.
  /// terms: the real p x m matrices, in the order basis() lists them: D, then per pole its one
  /// (real) or two (pair) matrices. Throws std::invalid_argument on a mismatch or unstable pole.
  MimoLinearModel(std::vector<std::complex<double>> poles, std::vector<Eigen::MatrixXd> terms,
                  Eigen::VectorXd output_offset);

  std::size_t inputs() const noexcept { return terms_.empty() ? 0 : terms_[0].cols(); }
  std::size_t outputs() const noexcept { return terms_.empty() ? 0 : terms_[0].rows(); }
  /// The order: the number of poles, a pair counting two.
  std::size_t order() const noexcept;
  const std::vector<std::complex<double>>& poles() const noexcept { return poles_; }
  const std::vector<Eigen::MatrixXd>& terms() const noexcept { return terms_; }
  const Eigen::VectorXd& output_offset() const noexcept { return offset_; }

  /// The real basis functions of the terms at z, in their order (1 first).
  static Eigen::VectorXcd basis(const std::vector<std::complex<double>>& poles,
                                std::complex<double> z);
  /// G(z): p x m.
  Eigen::MatrixXcd response(std::complex<double> z) const;
  /// Output (p x N) for input u (m x N) from rest, offset included.
  Eigen::MatrixXd simulate(const Eigen::MatrixXd& u) const;

 private:
  std::vector<std::complex<double>> poles_;
  std::vector<Eigen::MatrixXd> terms_;
  Eigen::VectorXd offset_;
};

}  // namespace hystbench::compensation
