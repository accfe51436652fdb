// The check before a model is written: sound models of every family pass with their inverse
// tracking them closely; a model whose inverse does not exist over its input range fails and
// the result names the part and the cause.
#include "hystbench/compensation/model_check.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/preisach_model.hpp"
#include "support/random_models.hpp"

namespace hc = hystbench::compensation;
using hystbench::testing::random_mpi_actuator;

namespace {

hc::ActuatorModel pi_actuator(std::vector<double> weights, double span) {
  hc::PiParameters p;
  p.thresholds = hc::uniform_thresholds(weights.size(), span);
  p.weights = std::move(weights);
  hc::ActuatorModel m(std::make_unique<hc::PiModel>(p));
  m.input_min = 0.0;
  m.input_max = span;
  return m;
}

}  // namespace

TEST(ModelCheck, SoundModelsWithEveryPartPassAndTheirInverseTracksThem) {
  std::mt19937_64 rng(7);
  for (const double dt : {1e-4, 1e-3}) {
    for (int trial = 0; trial < 4; ++trial) {
      hc::ActuatorModel m = random_mpi_actuator(rng, 8, 3, 100.0, dt);
      m.set_creep(hc::CreepParameters{{0.05, 0.5, 5.0}, {0.01, 0.02, 0.03}});
      m.set_dynamics(hc::DynamicsParameters{190.0, 0.06});
      m.set_delay(2 * dt);
      const hc::ModelCheck c = hc::check_model(m, dt);
      EXPECT_TRUE(c.passed) << c.reason;
      EXPECT_TRUE(c.part.empty());
      EXPECT_LT(c.inverse_rms_percent, 0.05) << "dt " << dt << ", trial " << trial;
      EXPECT_LT(c.inverse_max_percent, 0.5) << "dt " << dt << ", trial " << trial;
      EXPECT_NE(hc::describe(c).find("passed"), std::string::npos);
    }
  }
}

TEST(ModelCheck, APreisachPlanePasses) {
  hc::PreisachParameters p;
  p.u_min = 0.0;
  p.u_max = 100.0;
  p.cells = 20;
  p.densities.assign(p.cells * (p.cells + 1) / 2, 0.0);
  for (std::size_t a = 0; a < p.cells; ++a) {
    for (std::size_t b = 0; b <= a; ++b) {
      p.densities[hc::PreisachModel::cell_index(a, b)] =
          1e-3 * (1.0 + 0.1 * static_cast<double>(b));
    }
  }
  p.slope = 0.2;
  hc::ActuatorModel m(std::make_unique<hc::PreisachModel>(p));
  m.input_min = 0.0;
  m.input_max = 100.0;
  const hc::ModelCheck c = hc::check_model(m, 1e-4);
  EXPECT_TRUE(c.passed) << c.reason;
  EXPECT_LT(c.inverse_rms_percent, 0.05);
}

TEST(ModelCheck, AWeightThatTurnsTheLoadingCurveDownFailsOnTheHysteresis) {
  const hc::ModelCheck c = hc::check_model(pi_actuator({1.0, -1.5, 0.2}, 100.0), 1e-3);
  EXPECT_FALSE(c.passed);
  EXPECT_EQ(c.part, "hysteresis");
  EXPECT_NE(c.reason.find("not positive"), std::string::npos) << c.reason;
  EXPECT_NE(hc::describe(c).find("failed: "), std::string::npos);
}

TEST(ModelCheck, ACreepThatTurnsTheStaticMapDownFailsOnTheInverse) {
  // Invertible plays, but a fast creep of gain -2 makes the output fall as the input rises.
  hc::ActuatorModel m = pi_actuator({1.0}, 100.0);
  m.set_creep(hc::CreepParameters{{0.01}, {-2.0}});
  const hc::ModelCheck c = hc::check_model(m, 1e-3);
  EXPECT_FALSE(c.passed);
  EXPECT_EQ(c.part, "inverse") << c.reason;
  EXPECT_GT(c.inverse_rms_percent, hc::ModelCheck::kMaxRmsPercent);
  EXPECT_NE(c.reason.find("% rms"), std::string::npos) << c.reason;
}

TEST(ModelCheck, AnEmptyInputRangeFailsAndABadSamplePeriodThrows) {
  hc::ActuatorModel m = pi_actuator({1.0, 0.5}, 100.0);
  m.input_max = m.input_min;
  const hc::ModelCheck c = hc::check_model(m, 1e-3);
  EXPECT_FALSE(c.passed);
  EXPECT_EQ(c.part, "input_range");
  EXPECT_THROW((void)hc::check_model(pi_actuator({1.0}, 10.0), 0.0), std::invalid_argument);
  EXPECT_FALSE(hc::check_model(hc::ActuatorModel{}, 1e-3).passed);
}
