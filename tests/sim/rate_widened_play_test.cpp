#include "hystbench/sim/rate_widened_play.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace hs = hystbench::sim;

TEST(RateWidenedPlay, LagsARampByItsWideningTimesTheRate) {
  for (const double rate : {500.0, 4000.0}) {
    const double dt = 1e-5, widening = 1e-3;
    hs::RateWidenedPlay play(widening, 2e-4, dt);
    play.reset(0.0);
    double u = 0.0, v = 0.0;
    for (int k = 0; k < 20000; ++k) v = play.step(u += rate * dt);
    EXPECT_NEAR(u - v, widening * rate, 1e-6 * rate) << rate << " V/s";
  }
}

TEST(RateWidenedPlay, ReachesTheInputWhereItReversesAndHoldsOnTheWayBack) {
  const double dt = 1e-5;
  hs::RateWidenedPlay play(1e-3, 0.0, dt);
  play.reset(0.0);
  double u = 0.0, v = 0.0;
  for (int k = 0; k < 1000; ++k) v = play.step(u += 1000.0 * dt);  // up to 10 V at 1 kV/s
  EXPECT_NEAR(v, u - 1.0, 1e-9);
  v = play.step(u);  // held: the rate falls to zero and the relays catch up with the input
  EXPECT_DOUBLE_EQ(v, u);
  const double top = u;
  for (int k = 0; k < 100; ++k) v = play.step(u -= 1000.0 * dt);  // back down by 1 V
  EXPECT_DOUBLE_EQ(v, top);                                       // inside the widened band: held
}

TEST(RateWidenedPlay, RefusesBadArgumentsNamingThem) {
  EXPECT_THROW(hs::RateWidenedPlay(-1e-3, 0.0, 1e-4), std::invalid_argument);
  EXPECT_THROW(hs::RateWidenedPlay(1e-3, -1.0, 1e-4), std::invalid_argument);
  EXPECT_THROW(hs::RateWidenedPlay(1e-3, 0.0, 0.0), std::invalid_argument);
}
