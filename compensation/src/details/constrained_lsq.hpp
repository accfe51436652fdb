#pragma once
// Bound-constrained linear least squares for the identification (not real-time).
//   minimise ||A x - z||^2  subject to  lower <= x <= upper   (bounds may be +-infinity)
// A is never stored: rows are accumulated into the normal equations G = A'A, b = A'z, and the
// quadratic programme  min 0.5 x'Gx - b'x  is solved on the normal equations by block principal
// pivoting (Judice & Pires: every wrong bound state exchanged at once), finished where that
// stalls by a primal active-set method (the bounded-variable least squares of Stark & Parker).
// Cumulative-weight constraints W_k = sum_{i<=k} w_i >= eps become plain bounds once the
// unknowns are the cumulative weights themselves (see cumulative_to_increments()).
#include <Eigen/Dense>
#include <vector>

namespace hystbench::compensation::details {

/// Accumulates G = A'A, b = A'z and z'z row by row without storing A. Rows are buffered in
/// blocks and added with a symmetric rank-k update (cache friendly, no allocation per row).
/// Where most of a wide block's columns hold their value over long runs of rows (a Preisach plane's
/// cells: only those the input's front crosses change), those columns' products are taken run
/// by run from the block's prefix sums instead, and the rank update covers the rest alone.
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
  using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  void flush();
  /// Adds the pending block's products where enough of its columns are piecewise constant;
  /// false (nothing added) where the plain rank update is as cheap.
  bool add_piecewise_block();

  RowMajorMatrix block_;
  Eigen::VectorXd targets_;
  Eigen::MatrixXd gram_;  // lower triangle up to date after flush(); full on gram()
  Eigen::VectorXd rhs_;
  double zz_ = 0.0;
  Eigen::Index pending_ = 0;
  Eigen::Index rows_ = 0;
  // add_piecewise_block()'s scratch, sized once where the blocks are wide enough for it.
  RowMajorMatrix prefix_;              // block rows + 1 prefix sums of the block's rows
  Eigen::VectorXd column_products_;    // one piecewise column's products with every column
  Eigen::MatrixXd varying_block_;      // the block's varying columns, gathered
  Eigen::MatrixXd varying_gram_;       // their products among themselves
  std::vector<Eigen::Index> runs_;     // per column, its runs of equal values in the block
  std::vector<Eigen::Index> varying_;  // the columns the rank update takes
};

enum class BoundState : signed char { kLower = -1, kFree = 0, kUpper = 1 };

struct BoundedLsqResult {
  Eigen::VectorXd x;
  std::vector<BoundState> state;  ///< which bound each unknown ends on
  int iterations = 0;             ///< factorisations after the first (block exchanges, then steps)
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
