#pragma once
// Bound-constrained linear least squares for the identification (not real-time).
//   minimise ||A x - z||^2  subject to  lower <= x <= upper   (bounds may be +-infinity)
// A is never stored: rows are accumulated into the normal equations G = A'A, b = A'z, and the
// quadratic programme  min 0.5 x'Gx - b'x  is solved by a primal active-set method (the
// bounded-variable least-squares idea of Stark & Parker, on the normal equations).
// Cumulative-weight constraints W_k = sum_{i<=k} w_i >= eps become plain bounds once the
// unknowns are the cumulative weights themselves (see cumulative_to_increments()).
#include <Eigen/Dense>
#include <vector>

namespace hystbench::compensation::details {

/// Accumulates G = A'A, b = A'z and z'z row by row without storing A. Rows are buffered in
/// blocks and added with a symmetric rank-k update (cache friendly, no allocation per row).
class NormalEquations {
 public:
  explicit NormalEquations(Eigen::Index unknowns, Eigen::Index block_rows = 128);

  /// The next row to fill, unknowns() values; commit it with push().
  double* row() noexcept { return block_.row(pending_).data(); }
  /// Commits the row filled through row() with its target z.
  void push(double target) {
    targets_[pending_] = target;
    if (++pending_ == block_.rows()) flush();
  }

  /// G (full symmetric), b and z'z of every row pushed so far.
  const Eigen::MatrixXd& gram();
  const Eigen::VectorXd& rhs();
  double target_square_sum();
  Eigen::Index rows() const noexcept { return rows_ + pending_; }
  Eigen::Index unknowns() const noexcept { return gram_.rows(); }

 private:
  void flush();

  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> block_;
  Eigen::VectorXd targets_;
  Eigen::MatrixXd gram_;  // lower triangle up to date after flush(); full on gram()
  Eigen::VectorXd rhs_;
  double zz_ = 0.0;
  Eigen::Index pending_ = 0;
  Eigen::Index rows_ = 0;
};

enum class BoundState : signed char { kLower = -1, kFree = 0, kUpper = 1 };

struct BoundedLsqResult {
  Eigen::VectorXd x;
  std::vector<BoundState> state;  ///< which bound each unknown ends on
  int iterations = 0;             ///< active-set changes
  bool converged = false;         ///< KKT conditions met within tolerance
};

/// Minimises 0.5 x'Gx - b'x subject to lower <= x <= upper (entries may be +-inf; lower == upper
/// fixes an unknown). G symmetric positive semidefinite; a relative ridge of 1e-12 after Jacobi
/// scaling keeps rank-deficient problems well posed. When the unconstrained minimiser is
/// feasible it is returned as is. Unknowns on a bound are set exactly to that bound.
/// Throws std::invalid_argument on mismatched sizes, NaN or lower > upper.
BoundedLsqResult solve_bounded_lsq(const Eigen::MatrixXd& G, const Eigen::VectorXd& b,
                                   const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

/// Increments w_k = W_k - W_{k-1} (W_{-1} = start) of cumulative values W.
std::vector<double> cumulative_to_increments(const double* cumulative, std::size_t n,
                                             double start = 0.0);

}  // namespace hystbench::compensation::details
