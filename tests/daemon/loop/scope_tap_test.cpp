// The loop's scope tap (loop/scope_tap.hpp): the loop offers every decimation-th tick, run or
// idle, with the run's reference; a full ring drops and counts, the loop never waits; offering
// allocates nothing.
#include "hystbench/daemon/loop/scope_tap.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "hystbench/sim/simulated_actuator.hpp"
#include "support/allocation_counter.hpp"

namespace hd = hystbench::daemon;
namespace hs = hystbench::sim;

namespace {

constexpr double kRate = 5000.0;

std::unique_ptr<hystbench::drivers::Driver> loopback() {
  auto d = hystbench::drivers::make_driver("loopback");
  EXPECT_TRUE(
      d->configure({{"actuator", hs::to_json(hs::SimulatedActuatorConfig::modified_pi_truth())}},
                   kRate)
          .ok);
  EXPECT_TRUE(d->activate().ok);
  return d;
}

std::vector<hd::ScopeSample> drain_all(hd::ScopeTap& tap) {
  std::vector<hd::ScopeSample> all, batch(256);
  while (const std::size_t n = tap.drain(batch))
    all.insert(all.end(), batch.begin(), batch.begin() + n);
  return all;
}

}  // namespace

TEST(ScopeTap, RefusesDecimationZero) { EXPECT_THROW(hd::ScopeTap(0, 16), std::invalid_argument); }

TEST(ScopeTap, AFullRingDropsAndCountsInsteadOfWaiting) {
  hd::ScopeTap tap(1, 8);
  hd::ScopeSample s;
  for (int i = 0; i < 20; ++i) {
    s.tick = static_cast<std::uint64_t>(i);
    tap.offer(s);
  }
  EXPECT_EQ(tap.dropped(), 12u);
  const auto kept = drain_all(tap);
  ASSERT_EQ(kept.size(), 8u);
  EXPECT_EQ(kept.front().tick, 0u);  // the oldest stay, the newest are dropped
  EXPECT_EQ(kept.back().tick, 7u);
}

TEST(ScopeTap, TheLoopOffersEveryDecimatedTickWithTheRunsReference) {
  auto driver = loopback();
  hd::ScopeTap tap(10, 4096);
  hd::BenchLoopOptions o;
  o.rate_hz = kRate;
  o.scope = &tap;
  hd::BenchLoop loop(*driver, o);
  for (int k = 0; k < 100; ++k) loop.step();  // idle: no reference
  auto idle = drain_all(tap);
  ASSERT_EQ(idle.size(), 10u);
  for (std::size_t i = 0; i < idle.size(); ++i) {
    EXPECT_EQ(idle[i].tick, 10 * i);
    EXPECT_FALSE(idle[i].running);
    EXPECT_TRUE(std::isnan(idle[i].yr[0]));
    EXPECT_EQ(idle[i].axes, 1u);
  }

  hd::VerificationSpec spec;
  spec.frequency_hz = 10.0;
  spec.periods = 2.0;
  spec.precondition_s = 0.05;
  const auto truth =
      hs::make_truth_model(hs::SimulatedActuatorConfig::modified_pi_truth(), 1.0 / kRate);
  auto program =
      hd::make_verification_program(truth, spec, loop.last_output(), o.limits, 1.0 / kRate);
  const std::uint64_t total = program->total_samples;
  ASSERT_EQ(loop.submit(std::move(program)), nullptr);
  for (std::uint64_t k = 0; k < total; ++k) loop.step();
  const auto run = drain_all(tap);
  ASSERT_GE(run.size(), total / 10 - 1);
  double y_lo = INFINITY, y_hi = -INFINITY, worst = 0.0;
  std::size_t with_reference = 0;
  for (const auto& s : run) {
    y_lo = std::min(y_lo, s.y[0]);
    y_hi = std::max(y_hi, s.y[0]);
    if (s.running && std::isfinite(s.yr[0])) {
      ++with_reference;
      worst = std::max(worst, std::abs(s.yr[0] - s.y[0]));
    }
  }
  // The scope sees the actuator move over most of its range and follow the reference it drove
  // (the sample shows the previous tick's exchange: within a tick's travel of it).
  EXPECT_GT(y_hi - y_lo, 20.0);
  EXPECT_GT(with_reference, run.size() / 2);
  EXPECT_LT(worst, 2.0);
  EXPECT_EQ(tap.dropped(), 0u);
}

TEST(ScopeTap, OfferingAllocatesNothing) {
  hd::ScopeTap tap(1, 64);
  hd::ScopeSample s;
  const long n = hystbench::test::allocations_during([&] {
    for (int i = 0; i < 200; ++i) tap.offer(s);  // the ring fills: drops are counted too
  });
  EXPECT_EQ(n, 0);
  EXPECT_EQ(tap.dropped(), 136u);
}
