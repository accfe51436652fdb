#include "hystbench/sim/modal_dynamics.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace hs = hystbench::sim;
namespace hc = hystbench::compensation;

TEST(ModalDynamics, OneModeOfUnitGainIsTheSecondOrderDynamics) {
  const std::vector<hs::Mode> one = {{2500.0, 0.07, 1.0}};
  hs::ModalDynamics modal(one, 1e-4);
  hc::SecondOrderDynamics plain({2500.0, 0.07}, 1e-4);
  modal.reset(3.0);
  plain.reset(3.0);
  for (int k = 0; k < 500; ++k) {
    const double x = (k / 50) % 2 ? 10.0 : -4.0;
    ASSERT_EQ(modal.step(x), plain.step(x)) << k;
  }
}

TEST(ModalDynamics, ModesAddWithTheirGainsToUnitDcGain) {
  const std::vector<hs::Mode> two = {{3000.0, 0.06, 0.88}, {8000.0, 0.03, 0.12}};
  hs::ModalDynamics modal(two, 1e-5);
  modal.reset(0.0);
  double y = 0.0;
  for (int k = 0; k < 100000; ++k) y = modal.step(5.0);  // 1 s: settled
  EXPECT_NEAR(y, 5.0, 1e-9);
  hs::ModalDynamics none;
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(none.step(2.5), 2.5);
}

TEST(ModalDynamics, RejectsABadMode) {
  const std::vector<hs::Mode> bad = {{0.0, 0.05, 1.0}};
  EXPECT_THROW(hs::ModalDynamics(bad, 1e-4), std::invalid_argument);
}
