// The active model in the state the loop's output history leaves it
// (service/details/model_state_tracker.hpp): the same as the model stepped through every output
// kept, whether stepped on run by run or replayed after a model change, and the ticks the history
// lost taken as held.
#include "service/details/model_state_tracker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "hystbench/compensation/pi_model.hpp"

namespace hc = hystbench::compensation;
namespace hd = hystbench::daemon;
namespace hdd = hystbench::daemon::details;

namespace {

constexpr double kDt = 1e-3;

// A PI model with creep whose slowest lag outlasts every history here.
hc::ActuatorModel model_with_creep(double gain) {
  hc::ActuatorModel m(
      std::make_unique<hc::PiModel>(hc::PiParameters{{0.0, 1.0, 2.5}, {gain, 0.2, 0.1}, 0.0}));
  m.set_creep(hc::CreepParameters{{0.05, 2.0, 300.0}, {0.01, 0.02, 0.05}});
  return m;
}

// `m` relaxed at u[0] and stepped through u.
hc::ActuatorModel stepped_through(hc::ActuatorModel m, const std::vector<double>& u) {
  m.configure(kDt);
  m.reset(u.front());
  for (const double x : u) (void)m.step(x);
  return m;
}

// A history, its tracker and every output pushed, in order.
struct Played {
  explicit Played(std::size_t capacity) : history(capacity), tracker(history, kDt) {}
  void sine(std::size_t n, double phase) {
    for (std::size_t k = 0; k < n; ++k) {
      hold(5.0 + 4.0 * std::sin(0.013 * static_cast<double>(all.size()) + phase), 1);
    }
  }
  void hold(double u, std::size_t n) {
    for (std::size_t k = 0; k < n; ++k) {
      history.push(u);
      all.push_back(u);
    }
  }
  hd::OutputHistory history;
  hdd::ModelStateTracker tracker;
  std::vector<double> all;
};

// The two models answer the same inputs alike, within `tolerance`.
void expect_alike(hc::ActuatorModel a, hc::ActuatorModel b, double tolerance = 0.0) {
  for (const double u : {3.0, 7.5, 1.0}) EXPECT_NEAR(a.step(u), b.step(u), tolerance) << u;
}

}  // namespace

TEST(ModelStateTracker, NothingPlayedIsNoState) {
  Played p(100);
  EXPECT_EQ(p.tracker.state(model_with_creep(0.6), 1).model, nullptr);
}

TEST(ModelStateTracker, StepsTheModelOnRunByRunAsThroughTheWholeHistory) {
  Played p(100000);
  p.sine(3000, 0.0);
  const hc::ActuatorModel active = model_with_creep(0.6);
  const auto first = p.tracker.state(active, 1);
  ASSERT_NE(first.model, nullptr);
  EXPECT_EQ(first.tick, 3000u);
  EXPECT_DOUBLE_EQ(first.history_s, 3.0);
  p.sine(2000, 1.0);
  const auto second = p.tracker.state(active, 1);
  EXPECT_EQ(second.tick, 5000u);
  const hc::ActuatorModel whole = stepped_through(active, p.all);
  // The state carries what relaxing at the last output forgets: the creep of the history.
  hc::ActuatorModel relaxed = active;
  relaxed.configure(kDt);
  relaxed.reset(p.all.back());
  EXPECT_GT(std::abs(relaxed.peek_static(p.all.back()) - whole.peek_static(p.all.back())), 1e-3);
  expect_alike(*second.model, whole);
}

TEST(ModelStateTracker, ANewModelIsReplayedFromTheOldestOutputKept) {
  Played p(100000);
  p.sine(4000, 0.0);
  (void)p.tracker.state(model_with_creep(0.6), 1);
  p.sine(1000, 2.0);
  const hc::ActuatorModel next = model_with_creep(0.9);
  expect_alike(*p.tracker.state(next, 2).model, stepped_through(next, p.all));
}

TEST(ModelStateTracker, TicksTheHistoryLostAreTakenAsItsOldestOutputHeld) {
  // A ring of 500 ticks; 20 000 of one held output pass between two states.
  Played p(500);
  p.sine(400, 0.0);
  const hc::ActuatorModel active = model_with_creep(0.6);
  (void)p.tracker.state(active, 1);
  p.hold(2.0, 20000);
  const hc::ActuatorModel whole = stepped_through(active, p.all);
  // Replayed from the ring alone (relaxed at its oldest tick) it would have lost the start's
  // slow creep; held, it has it.
  const hc::ActuatorModel ring_only = stepped_through(active, std::vector<double>(499, 2.0));
  EXPECT_GT(std::abs(ring_only.peek_static(2.0) - whole.peek_static(2.0)), 1e-3);
  expect_alike(*p.tracker.state(active, 1).model, whole, 1e-9);
}
