#include "hystbench/sim/logarithmic_creep.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hs = hystbench::sim;

namespace {
double step_response(const hystbench::compensation::CreepParameters& p, double t) {
  double y = 0.0;
  for (std::size_t k = 0; k < p.gains.size(); ++k) {
    y += p.gains[k] * (1.0 - std::exp(-t / p.time_constants_s[k]));
  }
  return y;
}
}  // namespace

TEST(LogarithmicCreep, TheLagBankFollowsTheLogKernelOverItsSpan) {
  for (const double longest : {10.0, 1e3, 1e5, 1e7}) {
    const double gamma = 0.02;
    const auto p = hs::logarithmic_creep_bank(gamma, longest);
    double worst = 0.0;
    for (double t = 1e-3; t <= longest; t *= 1.05) {
      worst = std::max(worst, std::abs(step_response(p, t) - gamma * std::log10(1.0 + t / 0.1)));
    }
    EXPECT_LT(worst, 0.005 * gamma) << "longest " << longest;
    for (const double g : p.gains) EXPECT_GT(g, 0.0);
    // It levels off beyond longest_s: no more than half a decade more.
    EXPECT_LT(step_response(p, 1e4 * longest) - step_response(p, longest), 0.5 * gamma);
    EXPECT_GT(p.gains.size(), 8u);  // dense: three per decade
  }
}

TEST(LogarithmicCreep, RejectsBadArgumentsNamingThem) {
  EXPECT_THROW(hs::logarithmic_creep_bank(-0.01, 1e5), std::invalid_argument);
  EXPECT_THROW(hs::logarithmic_creep_bank(0.01, 0.5), std::invalid_argument);
  EXPECT_THROW(hs::logarithmic_creep_bank(0.01, 1e5, 0.0), std::invalid_argument);
  for (const double g : hs::logarithmic_creep_bank(0.0, 1e5).gains) EXPECT_EQ(g, 0.0);
}
