// The bound-constrained least-squares solver behind the identification: optimality (KKT),
// agreement with the unconstrained solution when no bound is active, and exact bounds.
#include "../../compensation/src/details/constrained_lsq.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace hd = hystbench::compensation::details;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Problem {
  Eigen::MatrixXd A;
  Eigen::VectorXd z;
  Eigen::MatrixXd G;
  Eigen::VectorXd b;
};

Problem random_problem(std::mt19937_64& rng, int rows, int cols, double noise) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Problem p;
  p.A.resize(rows, cols);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) p.A(i, j) = normal(rng);
  }
  Eigen::VectorXd x(cols);
  for (int j = 0; j < cols; ++j) x[j] = normal(rng);
  p.z = p.A * x;
  for (int i = 0; i < rows; ++i) p.z[i] += noise * normal(rng);
  p.G = p.A.transpose() * p.A;
  p.b = p.A.transpose() * p.z;
  return p;
}

double objective(const Problem& p, const Eigen::VectorXd& x) {
  return 0.5 * x.dot(p.G * x) - p.b.dot(x);
}

// KKT conditions of min 0.5 x'Gx - b'x, lo <= x <= hi: gradient zero on free unknowns,
// pointing out of the feasible box on active ones.
void expect_kkt(const Problem& p, const Eigen::VectorXd& x, const Eigen::VectorXd& lo,
                const Eigen::VectorXd& hi) {
  const Eigen::VectorXd g = p.G * x - p.b;
  const double tol = 1e-8 * (p.b.lpNorm<Eigen::Infinity>() + 1.0);
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    ASSERT_GE(x[i], lo[i]) << "unknown " << i << " below its lower bound";
    ASSERT_LE(x[i], hi[i]) << "unknown " << i << " above its upper bound";
    if (x[i] == lo[i] && x[i] == hi[i]) continue;
    if (x[i] == lo[i]) {
      EXPECT_GE(g[i], -tol) << "unknown " << i << " on its lower bound wants to increase";
    } else if (x[i] == hi[i]) {
      EXPECT_LE(g[i], tol) << "unknown " << i << " on its upper bound wants to decrease";
    } else {
      EXPECT_NEAR(g[i], 0.0, tol) << "free unknown " << i << " is not stationary";
    }
  }
}

}  // namespace

TEST(NormalEquations, MatchesDenseProductsAcrossBlocks) {
  std::mt19937_64 rng(1);
  const Problem p = random_problem(rng, 301, 5, 0.1);  // not a multiple of the block size
  hd::NormalEquations ne(5, 64);
  for (int i = 0; i < 301; ++i) {
    Eigen::Map<Eigen::VectorXd>(ne.row(), 5) = p.A.row(i).transpose();
    ne.push(p.z[i]);
  }
  EXPECT_EQ(ne.rows(), 301);
  EXPECT_LT((ne.gram() - p.G).norm(), 1e-10 * p.G.norm());
  EXPECT_LT((ne.rhs() - p.b).norm(), 1e-10 * p.b.norm());
  EXPECT_NEAR(ne.target_square_sum(), p.z.squaredNorm(), 1e-10 * p.z.squaredNorm());
  EXPECT_TRUE(ne.gram().isApprox(ne.gram().transpose()));
}

// Rows like a Preisach plane's: most columns hold their value over runs of rows (some stay 0),
// a few vary every row, interleaved; more than one block and a partial one.
TEST(NormalEquations, MatchesDenseProductsWhereMostColumnsArePiecewiseConstant) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::uniform_int_distribution<int> run(5, 60);
  const int n = 80, rows = 1000;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, n);
  for (int i = 0; i < n; ++i) {
    if (i % 7 == 3) {
      for (int t = 0; t < rows; ++t) A(t, i) = value(rng);  // varies every row
    } else if (i % 5 != 1) {                                // every fifth column stays 0
      for (int t = 0; t < rows;) {
        const int length = run(rng);
        const double v = value(rng);
        for (int r = t; r < std::min(rows, t + length); ++r) A(r, i) = v;
        t += length;
      }
    }
  }
  Eigen::VectorXd z(rows);
  for (int t = 0; t < rows; ++t) z[t] = value(rng);
  const Eigen::MatrixXd G = A.transpose() * A;
  hd::NormalEquations ne(n, 128);
  for (int t = 0; t < rows; ++t) {
    Eigen::Map<Eigen::VectorXd>(ne.row(), n) = A.row(t).transpose();
    ne.push(z[t]);
  }
  EXPECT_LT((ne.gram() - G).cwiseAbs().maxCoeff(), 1e-12 * G.cwiseAbs().maxCoeff());
  EXPECT_LT((ne.rhs() - A.transpose() * z).norm(), 1e-12 * (A.transpose() * z).norm());
  EXPECT_EQ(ne.gram(), ne.gram().transpose());
}

TEST(BoundedLsq, EqualsUnconstrainedSolutionWhenNoBoundIsActive) {
  std::mt19937_64 rng(2);
  const Problem p = random_problem(rng, 200, 8, 0.3);
  const Eigen::VectorXd expected = p.A.colPivHouseholderQr().solve(p.z);
  const Eigen::VectorXd lo = expected.array() - 1.0;
  const Eigen::VectorXd hi = expected.array() + 1.0;
  for (const auto& [l, h] :
       {std::pair{lo, hi}, std::pair{Eigen::VectorXd::Constant(8, -kInf).eval(),
                                     Eigen::VectorXd::Constant(8, kInf).eval()}}) {
    const hd::BoundedLsqResult r = hd::solve_bounded_lsq(p.G, p.b, l, h);
    EXPECT_TRUE(r.converged);
    EXPECT_EQ(r.iterations, 0);
    EXPECT_LT((r.x - expected).norm(), 1e-9 * expected.norm());
    for (const auto s : r.state) EXPECT_EQ(s, hd::BoundState::kFree);
  }
}

TEST(BoundedLsq, MeetsKktAndBoundsWhenConstraintsBind) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    const Problem p = random_problem(rng, 60, 10, 1.0);
    const Eigen::VectorXd unconstrained = p.A.colPivHouseholderQr().solve(p.z);
    // Bounds that cut through the unconstrained solution on about half of the unknowns.
    Eigen::VectorXd lo = unconstrained.array() + 0.3;
    Eigen::VectorXd hi = Eigen::VectorXd::Constant(10, kInf);
    for (int j = 0; j < 10; j += 3) lo[j] = -kInf, hi[j] = unconstrained[j] - 0.2;
    for (int j = 1; j < 10; j += 4) lo[j] = -kInf;  // some unknowns free
    const hd::BoundedLsqResult r = hd::solve_bounded_lsq(p.G, p.b, lo, hi);
    ASSERT_TRUE(r.converged) << "trial " << trial;
    expect_kkt(p, r.x, lo, hi);
    EXPECT_LT(objective(p, unconstrained), objective(p, r.x));  // the bounds do cost something
  }
}

TEST(BoundedLsq, FindsTheGlobalMinimumOfSmallProblems) {
  // Brute force over every active set (3^n) of a 4-unknown problem.
  std::mt19937_64 rng(4);
  for (int trial = 0; trial < 30; ++trial) {
    const Problem p = random_problem(rng, 12, 4, 1.0);
    const Eigen::VectorXd lo = Eigen::VectorXd::Constant(4, -0.3);
    const Eigen::VectorXd hi = Eigen::VectorXd::Constant(4, 0.4);
    double best = kInf;
    for (int code = 0; code < 81; ++code) {
      Eigen::VectorXd x = Eigen::VectorXd::Zero(4);
      std::vector<int> free;
      for (int j = 0, c = code; j < 4; ++j, c /= 3) {
        if (c % 3 == 0) x[j] = lo[j];
        if (c % 3 == 1) x[j] = hi[j];
        if (c % 3 == 2) free.push_back(j);
      }
      if (!free.empty()) {
        const auto nf = static_cast<Eigen::Index>(free.size());
        Eigen::MatrixXd Gff(nf, nf);
        Eigen::VectorXd rhs(nf);
        for (Eigen::Index a = 0; a < nf; ++a) {
          rhs[a] = p.b[free[a]] - p.G.row(free[a]).dot(x);
          for (Eigen::Index c = 0; c < nf; ++c) Gff(a, c) = p.G(free[a], free[c]);
        }
        const Eigen::VectorXd xf = Gff.ldlt().solve(rhs);
        for (Eigen::Index a = 0; a < nf; ++a) x[free[a]] = xf[a];
      }
      if ((x.array() >= lo.array() - 1e-12).all() && (x.array() <= hi.array() + 1e-12).all()) {
        best = std::min(best, objective(p, x));
      }
    }
    const hd::BoundedLsqResult r = hd::solve_bounded_lsq(p.G, p.b, lo, hi);
    ASSERT_TRUE(r.converged);
    EXPECT_NEAR(objective(p, r.x), best, 1e-9 * (1.0 + std::abs(best))) << "trial " << trial;
  }
}

TEST(BoundedLsq, HoldsFixedUnknownsAndSurvivesRankDeficiency) {
  std::mt19937_64 rng(5);
  Problem p = random_problem(rng, 40, 4, 0.1);
  p.A.col(3) = p.A.col(2);  // duplicate column: G singular
  p.G = p.A.transpose() * p.A;
  p.b = p.A.transpose() * p.z;
  Eigen::VectorXd lo = Eigen::VectorXd::Constant(4, 0.05);
  Eigen::VectorXd hi = Eigen::VectorXd::Constant(4, kInf);
  lo[0] = hi[0] = 0.7;  // fixed
  const hd::BoundedLsqResult r = hd::solve_bounded_lsq(p.G, p.b, lo, hi);
  ASSERT_TRUE(r.x.allFinite());
  EXPECT_EQ(r.x[0], 0.7);
  EXPECT_GE(r.x.minCoeff(), 0.05);
  expect_kkt(p, r.x, lo, hi);
}

TEST(BoundedLsq, RejectsInconsistentInput) {
  const Eigen::MatrixXd G = Eigen::MatrixXd::Identity(2, 2);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(2);
  const Eigen::VectorXd lo = Eigen::VectorXd::Zero(2);
  const Eigen::VectorXd hi = Eigen::VectorXd::Ones(2);
  EXPECT_THROW(hd::solve_bounded_lsq(G, Eigen::VectorXd::Ones(3), lo, hi), std::invalid_argument);
  EXPECT_THROW(hd::solve_bounded_lsq(G, b, hi, lo.array() - 1.0), std::invalid_argument);
  Eigen::VectorXd bad = b;
  bad[1] = std::nan("");
  EXPECT_THROW(hd::solve_bounded_lsq(G, bad, lo, hi), std::invalid_argument);
}

TEST(CumulativeToIncrements, InvertsARunningSum) {
  const double W[] = {1.0, 1.5, 1.25, 2.0};
  const std::vector<double> w = hd::cumulative_to_increments(W, 4);
  EXPECT_EQ(w, (std::vector<double>{1.0, 0.5, -0.25, 0.75}));
  const std::vector<double> v = hd::cumulative_to_increments(W, 2, 1.0);
  EXPECT_EQ(v, (std::vector<double>{0.0, 0.5}));
}

// Columns like a Preisach plane's relays (nested steps of the input, nearly collinear) with
// nonnegative weights, two thirds of which end on zero, and an upper bound on a few: the states
// are exchanged in blocks, so the solve takes a few factorisations, not one per bound that
// binds, and it ends at the optimum.
TEST(BoundedLsq, SettlesTheBoundsOfNearlyCollinearRelayColumnsInFewFactorisations) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    const int rows = 600, n = 90;
    Problem p;
    p.A.resize(rows, n);
    for (int t = 0; t < rows; ++t) {
      const double u = std::sin(0.031 * t) * (1.0 + 0.3 * std::sin(0.0047 * t));
      for (int j = 0; j < n; ++j) p.A(t, j) = u > -1.3 + 2.6 * j / n ? 1.0 : 0.0;
    }
    p.z.resize(rows);
    for (int t = 0; t < rows; ++t) p.z[t] = p.A.row(t).sum() / n + 0.2 * normal(rng);
    p.G = p.A.transpose() * p.A;
    p.b = p.A.transpose() * p.z;
    const Eigen::VectorXd lo = Eigen::VectorXd::Zero(n);
    Eigen::VectorXd hi = Eigen::VectorXd::Constant(n, kInf);
    for (int j = 0; j < n; j += 11) hi[j] = 0.002;
    const hd::BoundedLsqResult r = hd::solve_bounded_lsq(p.G, p.b, lo, hi);
    ASSERT_TRUE(r.converged) << "trial " << trial;
    expect_kkt(p, r.x, lo, hi);
    const auto bound = std::count(r.state.begin(), r.state.end(), hd::BoundState::kLower);
    EXPECT_GT(bound, n / 2) << "trial " << trial;
    EXPECT_LT(r.iterations, bound / 5) << "trial " << trial << ": " << bound << " on zero";
  }
}
