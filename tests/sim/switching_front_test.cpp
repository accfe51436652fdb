#include "hystbench/sim/switching_front.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hs = hystbench::sim;

TEST(SwitchingFront, LagsARampByTheSquareRootOfItsRate) {
  for (const double rate : {250.0, 1000.0, 9000.0}) {
    const double dt = 1e-5;
    hs::SwitchingFront front(2.5, 2.0, dt);
    front.reset(0.0);
    double u = 0.0;
    for (int k = 0; k < 100000; ++k) front.step(u += rate * dt);
    // The input is held over each sample: half a sample's rise more or less.
    EXPECT_NEAR(u - front.front(), 2.5 * std::sqrt(rate / 1000.0), 0.01 * 2.5 + rate * dt)
        << rate << " V/s";
  }
}

TEST(SwitchingFront, TheSolutionOverAHeldSampleIsExact) {
  // One long sample equals many short ones for the same held input.
  for (const double n : {1.0, 2.0, 3.0}) {
    hs::SwitchingFront coarse(2.0, n, 1e-3), fine(2.0, n, 1e-6);
    coarse.reset(0.0);
    fine.reset(0.0);
    coarse.step(10.0);
    for (int k = 0; k < 1000; ++k) fine.step(10.0);
    EXPECT_NEAR(coarse.front(), fine.front(), 1e-9) << "n = " << n;
    EXPECT_GT(coarse.front(), 0.0);
    EXPECT_LT(coarse.front(), 10.0);
    coarse.step(-5.0);  // and back down through the input
    EXPECT_LT(coarse.front(), 10.0);
    EXPECT_GT(coarse.front(), -5.0);
  }
}

TEST(SwitchingFront, WithExponentOneItIsAFirstOrderLag) {
  const double dt = 1e-5, rate = 2000.0;
  hs::SwitchingFront front(3.0, 1.0, dt);
  front.reset(0.0);
  double u = 0.0;
  for (int k = 0; k < 100000; ++k) front.step(u += rate * dt);
  // Lag r tau, tau = lag / (1 kV/s): twice the rate, twice the lag.
  EXPECT_NEAR(u - front.front(), 3.0 * rate / 1000.0, 0.01 + rate * dt);
}

TEST(SwitchingFront, RejectsBadArgumentsNamingThem) {
  EXPECT_THROW(hs::SwitchingFront(0.0, 2.0, 1e-4), std::invalid_argument);
  EXPECT_THROW(hs::SwitchingFront(1.0, 0.5, 1e-4), std::invalid_argument);
  EXPECT_THROW(hs::SwitchingFront(1.0, 2.0, 0.0), std::invalid_argument);
}
