#include "details/constrained_lsq.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace hystbench::compensation::details {

namespace {

// A column is taken run by run where it holds its value over runs this many rows long on
// average; the block is, where at least this share of its columns is, and it has this many
// columns (below, the rank update costs little, and the fits keep its rounding).
constexpr Eigen::Index kMinRunRows = 8;
constexpr double kMinPiecewiseShare = 0.5;
constexpr Eigen::Index kMinPiecewiseColumns = 64;

}  // namespace

NormalEquations::NormalEquations(Eigen::Index unknowns, Eigen::Index block_rows)
    : block_(block_rows, unknowns),
      targets_(block_rows),
      gram_(Eigen::MatrixXd::Zero(unknowns, unknowns)),
      rhs_(Eigen::VectorXd::Zero(unknowns)) {
  if (unknowns < kMinPiecewiseColumns) return;  // add_piecewise_block() declines: no scratch
  prefix_.resize(block_rows + 1, unknowns);
  column_products_.resize(unknowns);
  varying_block_.resize(block_rows, unknowns);
  varying_gram_.resize(unknowns, unknowns);
  runs_.resize(static_cast<std::size_t>(unknowns));
  varying_.reserve(static_cast<std::size_t>(unknowns));
}

bool NormalEquations::add_piecewise_block() {
  const Eigen::Index k = pending_, n = block_.cols();
  if (k < 2 * kMinRunRows || n < kMinPiecewiseColumns) return false;
  const auto rows = block_.topRows(k);
  std::fill(runs_.begin(), runs_.end(), 1);
  for (Eigen::Index t = 1; t < k; ++t) {
    const double* now = rows.row(t).data();
    const double* before = rows.row(t - 1).data();
    for (Eigen::Index i = 0; i < n; ++i) runs_[static_cast<std::size_t>(i)] += now[i] != before[i];
  }
  varying_.clear();
  const Eigen::Index max_runs = k / kMinRunRows;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (runs_[static_cast<std::size_t>(i)] > max_runs) varying_.push_back(i);
  }
  const auto piecewise = n - static_cast<Eigen::Index>(varying_.size());
  if (static_cast<double>(piecewise) < kMinPiecewiseShare * static_cast<double>(n)) return false;

  // Row t of the prefix sums: the block's rows before t summed.
  prefix_.row(0).setZero();
  for (Eigen::Index t = 0; t < k; ++t) prefix_.row(t + 1) = prefix_.row(t) + rows.row(t);
  // A piecewise column i's products with every column, run by run: value times the run's sums.
  // They go to G's lower triangle: column i from row i down, and row i left of it where the
  // column there is a varying one (a piecewise one's own pass writes its column).
  std::size_t next_varying = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (next_varying < varying_.size() && varying_[next_varying] == i) {
      ++next_varying;
      continue;
    }
    column_products_.setZero();
    bool any = false;
    Eigen::Index start = 0;
    for (Eigen::Index t = 1; t <= k; ++t) {
      if (t < k && rows(t, i) == rows(start, i)) continue;
      const double value = rows(start, i);
      if (value != 0.0) {
        column_products_.noalias() += value * (prefix_.row(t) - prefix_.row(start)).transpose();
        any = true;
      }
      start = t;
    }
    if (!any) continue;
    gram_.col(i).tail(n - i) += column_products_.tail(n - i);
    for (std::size_t v = 0; v < next_varying; ++v) {
      gram_(i, varying_[v]) += column_products_[varying_[v]];
    }
  }
  // The varying columns among themselves: the rank update on them gathered.
  const auto m = static_cast<Eigen::Index>(varying_.size());
  if (m == 0) return true;
  for (Eigen::Index c = 0; c < m; ++c) {
    varying_block_.col(c).head(k) = rows.col(varying_[static_cast<std::size_t>(c)]);
  }
  auto gathered = varying_block_.topLeftCorner(k, m);
  auto products = varying_gram_.topLeftCorner(m, m);
  products.setZero();
  products.selfadjointView<Eigen::Lower>().rankUpdate(gathered.transpose());
  for (Eigen::Index q = 0; q < m; ++q) {
    for (Eigen::Index p = q; p < m; ++p) {
      gram_(varying_[static_cast<std::size_t>(p)], varying_[static_cast<std::size_t>(q)]) +=
          products(p, q);
    }
  }
  return true;
}

void NormalEquations::flush() {
  if (pending_ == 0) return;
  const auto rows = block_.topRows(pending_);
  const auto z = targets_.head(pending_);
  if (!add_piecewise_block()) gram_.selfadjointView<Eigen::Lower>().rankUpdate(rows.transpose());
  rhs_.noalias() += rows.transpose() * z;
  zz_ += z.squaredNorm();
  rows_ += pending_;
  pending_ = 0;
}

const Eigen::MatrixXd& NormalEquations::gram() {
  flush();
  gram_.triangularView<Eigen::StrictlyUpper>() = gram_.transpose();
  return gram_;
}

const Eigen::VectorXd& NormalEquations::rhs() {
  flush();
  return rhs_;
}

double NormalEquations::target_square_sum() {
  flush();
  return zz_;
}

namespace {

constexpr double kRidge = 1e-12;  // relative to the unit diagonal after Jacobi scaling
// Block exchanges that may fail to lower the count of wrong states before the one-at-a-time
// steps take over (ActiveSet::exchange_blocks).
constexpr int kBlockTries = 3;

void validate(const Eigen::MatrixXd& G, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
              const Eigen::VectorXd& upper) {
  const Eigen::Index n = b.size();
  if (G.rows() != n || G.cols() != n || lower.size() != n || upper.size() != n) {
    throw std::invalid_argument(
        "bounded least squares: G must be n x n and b, lower, upper of "
        "length n (n = " +
        std::to_string(n) + ")");
  }
  if (!G.allFinite() || !b.allFinite()) {
    throw std::invalid_argument("bounded least squares: G and b must be finite");
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    if (std::isnan(lower[i]) || std::isnan(upper[i]) || lower[i] > upper[i]) {
      throw std::invalid_argument("bounded least squares: bounds of unknown " + std::to_string(i) +
                                  " are NaN or lower > upper");
    }
  }
}

// The solution of H x = r for H symmetric positive definite (the scaled problem's ridge makes it
// so): Cholesky, blocked and several times faster than a pivoted LDL' on the hundreds of
// unknowns of a Preisach plane; the pivoted LDL' where rounding defeats Cholesky.
Eigen::VectorXd solve_positive_definite(const Eigen::MatrixXd& H, const Eigen::VectorXd& r) {
  const Eigen::LLT<Eigen::MatrixXd> llt(H);
  if (llt.info() == Eigen::Success) return llt.solve(r);
  return H.ldlt().solve(r);
}

// The active-set iteration on the scaled problem min 0.5 x'Hx - c'x, lo <= x <= hi.
class ActiveSet {
 public:
  ActiveSet(const Eigen::MatrixXd& H, const Eigen::VectorXd& c, const Eigen::VectorXd& lo,
            const Eigen::VectorXd& hi)
      : H_(H), c_(c), lo_(lo), hi_(hi), n_(c.size()), state_(n_, BoundState::kFree) {}

  BoundedLsqResult run() {
    BoundedLsqResult out;
    x_ = solve_positive_definite(H_, c_);
    if (feasible(x_)) {
      out.x = x_;
      out.state = state_;
      out.converged = true;
      return out;
    }
    for (Eigen::Index i = 0; i < n_; ++i) {
      if (x_[i] <= lo_[i]) set_bound(i, BoundState::kLower);
      if (x_[i] >= hi_[i]) set_bound(i, BoundState::kUpper);
    }
    out.converged = exchange_blocks(out.iterations);
    const int max_iterations = 100 + 20 * static_cast<int>(n_);
    while (!out.converged && out.iterations < max_iterations) {
      if (!step_to_subspace_minimum()) {
        ++out.iterations;
        continue;
      }
      const Eigen::Index release = most_violated_multiplier();
      if (release < 0) {
        out.converged = true;
        break;
      }
      state_[release] = BoundState::kFree;
      ++out.iterations;
    }
    out.x = x_;
    out.state = state_;
    return out;
  }

 private:
  bool feasible(const Eigen::VectorXd& x) const {
    return ((x - lo_).array() >= 0.0).all() && ((hi_ - x).array() >= 0.0).all();
  }

  void set_bound(Eigen::Index i, BoundState s) {
    state_[i] = s;
    x_[i] = s == BoundState::kLower ? lo_[i] : hi_[i];
  }

  // Block principal pivoting (Judice and Pires; Portugal, Judice and Vicente 1994): from the
  // current states, every unknown whose state is wrong changes it at once: a free one outside
  // its box goes to the bound it passed, a bound one whose multiplier has the wrong sign is
  // freed. Most problems settle in a few exchanges, where the steps below free or fix one unknown
  // per factorisation. Where the count of wrong states stops falling for kBlockTries exchanges
  // (an ill-conditioned plane's can cycle), the states that had fewest hand over to those steps,
  // from a feasible point. True when the optimum was reached; `solves` counts the exchanges.
  bool exchange_blocks(int& solves) {
    std::vector<BoundState> best_state = state_;
    Eigen::VectorXd best_x = x_;
    std::size_t best_wrong = static_cast<std::size_t>(n_) + 1;
    int tries = kBlockTries;
    while (true) {
      const Eigen::VectorXd target = subspace_minimum();
      for (std::size_t a = 0; a < free_.size(); ++a)
        x_[free_[a]] = target[static_cast<Eigen::Index>(a)];
      ++solves;
      const Eigen::VectorXd g = H_ * x_ - c_;
      const double tol = multiplier_tolerance();
      wrong_.clear();
      for (Eigen::Index i = 0; i < n_; ++i) {
        if (state_[i] == BoundState::kFree ? x_[i] < lo_[i] || x_[i] > hi_[i]
                                           : multiplier_violation(i, g) > tol) {
          wrong_.push_back(i);
        }
      }
      if (wrong_.empty()) return true;
      if (wrong_.size() < best_wrong) {
        best_wrong = wrong_.size();
        best_state = state_;
        best_x = x_;
        tries = kBlockTries;
      } else if (--tries < 0) {
        break;
      }
      for (const Eigen::Index i : wrong_) {
        if (state_[i] != BoundState::kFree) {
          state_[i] = BoundState::kFree;
        } else {
          set_bound(i, x_[i] < lo_[i] ? BoundState::kLower : BoundState::kUpper);
        }
      }
    }
    state_ = std::move(best_state);
    x_ = std::move(best_x);
    for (Eigen::Index i = 0; i < n_; ++i) {
      if (state_[i] != BoundState::kFree) continue;
      if (x_[i] < lo_[i]) set_bound(i, BoundState::kLower);
      if (x_[i] > hi_[i]) set_bound(i, BoundState::kUpper);
    }
    return false;
  }

  // The minimum over the free unknowns (free_, set here) with the others held on their bounds.
  Eigen::VectorXd subspace_minimum() {
    free_.clear();
    for (Eigen::Index i = 0; i < n_; ++i) {
      if (state_[i] == BoundState::kFree) free_.push_back(i);
    }
    const auto nf = static_cast<Eigen::Index>(free_.size());
    if (nf == 0) return {};
    // The free unknowns' rows of c - H x_bound (x_bound: x with the free unknowns at 0), and
    // H's free block, gathered column by column (H is column-major).
    Eigen::VectorXd bound = x_;
    for (const Eigen::Index i : free_) bound[i] = 0.0;
    const Eigen::VectorXd pull = H_ * bound;
    Eigen::MatrixXd Hff(nf, nf);
    Eigen::VectorXd rhs(nf);
    for (Eigen::Index a = 0; a < nf; ++a) rhs[a] = c_[free_[a]] - pull[free_[a]];
    for (Eigen::Index b = 0; b < nf; ++b) {
      const auto column = H_.col(free_[b]);
      for (Eigen::Index a = 0; a < nf; ++a) Hff(a, b) = column[free_[a]];
    }
    return solve_positive_definite(Hff, rhs);
  }

  // Moves from the feasible x towards the subspace minimum as far as the bounds allow. Returns
  // false when a bound blocked the move (the blocking unknown is then fixed on it).
  bool step_to_subspace_minimum() {
    const Eigen::VectorXd target = subspace_minimum();
    const auto nf = static_cast<Eigen::Index>(free_.size());
    if (nf == 0) return true;
    double alpha = 1.0;
    Eigen::Index blocking = -1;
    BoundState side = BoundState::kFree;
    for (Eigen::Index a = 0; a < nf; ++a) {
      const Eigen::Index i = free_[a];
      const double d = target[a] - x_[i];
      if (target[a] < lo_[i] && d < 0.0) {
        const double t = (lo_[i] - x_[i]) / d;
        if (t < alpha) alpha = t, blocking = i, side = BoundState::kLower;
      } else if (target[a] > hi_[i] && d > 0.0) {
        const double t = (hi_[i] - x_[i]) / d;
        if (t < alpha) alpha = t, blocking = i, side = BoundState::kUpper;
      }
    }
    alpha = std::max(alpha, 0.0);
    for (Eigen::Index a = 0; a < nf; ++a) {
      const Eigen::Index i = free_[a];
      x_[i] = std::clamp(x_[i] + alpha * (target[a] - x_[i]), lo_[i], hi_[i]);
    }
    if (blocking < 0) return true;
    set_bound(blocking, side);
    return false;
  }

  // The bound unknown whose Lagrange multiplier has the wrong sign by the largest margin, or -1.
  Eigen::Index most_violated_multiplier() const {
    const Eigen::VectorXd g = H_ * x_ - c_;
    Eigen::Index best = -1;
    double worst = multiplier_tolerance();
    for (Eigen::Index i = 0; i < n_; ++i) {
      const double violation = multiplier_violation(i, g);
      if (violation > worst) worst = violation, best = i;
    }
    return best;
  }

  // How far bound unknown i's multiplier has the wrong sign at the gradient g = Hx - c (> 0: it
  // wants off its bound); 0 for free and fixed unknowns. Counted above multiplier_tolerance().
  double multiplier_violation(Eigen::Index i, const Eigen::VectorXd& g) const {
    if (lo_[i] == hi_[i]) return 0.0;                   // fixed unknown
    if (state_[i] == BoundState::kLower) return -g[i];  // wants to increase
    if (state_[i] == BoundState::kUpper) return g[i];   // wants to decrease
    return 0.0;
  }
  double multiplier_tolerance() const {
    return 1e-10 * (c_.lpNorm<Eigen::Infinity>() + x_.lpNorm<Eigen::Infinity>());
  }

  const Eigen::MatrixXd& H_;
  const Eigen::VectorXd& c_;
  const Eigen::VectorXd& lo_;
  const Eigen::VectorXd& hi_;
  Eigen::Index n_;
  std::vector<BoundState> state_;
  std::vector<Eigen::Index> free_;
  std::vector<Eigen::Index> wrong_;  // exchange_blocks()'s unknowns in the wrong state
  Eigen::VectorXd x_;
};

}  // namespace

BoundedLsqResult solve_bounded_lsq(const Eigen::MatrixXd& G, const Eigen::VectorXd& b,
                                   const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  validate(G, b, lower, upper);
  const Eigen::Index n = b.size();
  // Jacobi scaling: unit diagonal, so the ridge and the tolerances are relative.
  Eigen::VectorXd s(n);
  for (Eigen::Index i = 0; i < n; ++i) s[i] = G(i, i) > 0.0 ? 1.0 / std::sqrt(G(i, i)) : 1.0;
  Eigen::MatrixXd H = s.asDiagonal() * G * s.asDiagonal();
  H.diagonal().array() += kRidge;
  const Eigen::VectorXd c = s.cwiseProduct(b);
  const Eigen::VectorXd lo = lower.cwiseQuotient(s);
  const Eigen::VectorXd hi = upper.cwiseQuotient(s);

  BoundedLsqResult out = ActiveSet(H, c, lo, hi).run();
  for (Eigen::Index i = 0; i < n; ++i) {
    switch (out.state[i]) {
      case BoundState::kLower:
        out.x[i] = lower[i];
        break;
      case BoundState::kUpper:
        out.x[i] = upper[i];
        break;
      case BoundState::kFree:
        out.x[i] = std::clamp(out.x[i] * s[i], lower[i], upper[i]);
        break;
    }
  }
  return out;
}

std::vector<double> cumulative_to_increments(const double* cumulative, std::size_t n,
                                             double start) {
  std::vector<double> w(n);
  double prev = start;
  for (std::size_t k = 0; k < n; ++k) {
    w[k] = cumulative[k] - prev;
    prev = cumulative[k];
  }
  return w;
}

}  // namespace hystbench::compensation::details
