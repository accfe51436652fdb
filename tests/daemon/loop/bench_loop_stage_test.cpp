// BenchLoop on a stage of several axes (the loopback's two-axis stage), driven by step(): one
// tick writes and reads every axis, each axis's program gets its own drive, record and figures,
// the log holds a set of columns per axis, and what the run does not drive holds its safe output.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/daemon/loop/sample_log_writer.hpp"
#include "hystbench/drivers/driver.hpp"
#include "hystbench/sim/simulated_stage.hpp"

namespace hd = hystbench::daemon;
namespace hs = hystbench::sim;
using nlohmann::json;

namespace {

constexpr double kRate = 10000.0;
constexpr std::uint64_t kSamples = 4000;

std::int64_t fake_now = 0;
std::int64_t fake_clock() noexcept { return fake_now += 1000; }

std::unique_ptr<hystbench::drivers::Driver> stage_driver() {
  auto d = hystbench::drivers::make_driver("loopback");
  const auto configured = d->configure({{"stage", json::object()}}, kRate);
  EXPECT_TRUE(configured.ok) << configured.message;
  EXPECT_TRUE(d->activate().ok);
  return d;
}

/// Axis a's open-loop drive at tick k [V]: smooth from 0 V, a different frequency per axis.
double drive(std::size_t a, std::uint64_t k) {
  const double f = a == 0 ? 7.0 : 3.0, amplitude = a == 0 ? 60.0 : 50.0;
  return amplitude * (1.0 - std::cos(2.0 * M_PI * f * static_cast<double>(k) / kRate));
}

std::unique_ptr<hd::RunProgram> excite_axis(std::size_t a) {
  auto p = std::make_unique<hd::RunProgram>();
  p->kind = hd::RunKind::kExcite;
  p->total_samples = kSamples;
  for (std::uint64_t k = 0; k < kSamples; ++k) p->excitation.push_back(drive(a, k));
  p->records.capacity = kSamples;
  p->records.u.resize(kSamples);
  p->records.y.resize(kSamples);
  p->records.yr.resize(kSamples);
  return p;
}

/// A run of `axes` axes, each with its own drive.
std::unique_ptr<hd::RunProgram> excite_stage(std::size_t axes) {
  auto p = excite_axis(0);
  for (std::size_t a = 1; a < axes; ++a) p->stage_axes.push_back(excite_axis(a));
  return p;
}

hd::BenchLoopOptions options() {
  hd::BenchLoopOptions o;
  o.rate_hz = kRate;
  o.clock_ns = &fake_clock;
  return o;
}

std::unique_ptr<hd::RunProgram> play(hd::BenchLoop& loop, std::unique_ptr<hd::RunProgram> p) {
  const std::uint64_t total = p->total_samples;
  EXPECT_EQ(loop.submit(std::move(p)), nullptr);
  for (std::uint64_t k = 0; k < total; ++k) loop.step();
  return loop.take_finished();
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  for (std::string cell; std::getline(ss, cell, ',');) out.push_back(cell);
  return out;
}

}  // namespace

TEST(BenchLoopStage, EveryAxisIsDrivenAndReadInOneTickAsTheSimulatedStageIs) {
  auto driver = stage_driver();
  hd::BenchLoop loop(*driver, options());
  ASSERT_EQ(loop.axes(), 2u);
  loop.step();  // an idle tick at the safe output
  auto done = play(loop, excite_stage(2));
  ASSERT_NE(done, nullptr);
  ASSERT_EQ(done->end, hd::RunEnd::kCompleted) << done->end_reason;
  ASSERT_EQ(done->stage_axes.size(), 1u);

  hs::SimulatedStage truth(hs::SimulatedStageConfig::xy(), 1.0 / kRate);
  const double safe[2] = {0.0, 0.0};
  truth.reset(safe);
  double y[2];
  truth.step(safe, y);  // the idle tick
  for (std::uint64_t k = 0; k < kSamples; ++k) {
    const double u[2] = {drive(0, k), drive(1, k)};
    truth.step(u, y);
    for (std::size_t a = 0; a < 2; ++a) {
      const hd::RunProgram& axis = done->axis(a);
      ASSERT_EQ(axis.records.u[k], u[a]) << "axis " << a << " tick " << k;
      ASSERT_EQ(axis.records.y[k], y[a]) << "axis " << a << " tick " << k;
    }
  }
  EXPECT_EQ(done->axis(1).done.load(), kSamples);
  EXPECT_EQ(done->axis(1).end, hd::RunEnd::kCompleted);
  EXPECT_EQ(loop.last_output(1), drive(1, kSamples - 1));
  EXPECT_EQ(loop.last_measurement(1), y[1]);
}

TEST(BenchLoopStage, AnAxisTheRunDoesNotDriveHoldsItsSafeOutput) {
  auto driver = stage_driver();
  hd::BenchLoop loop(*driver, options());
  loop.step();
  auto done = play(loop, excite_stage(1));
  ASSERT_NE(done, nullptr);
  ASSERT_EQ(done->end, hd::RunEnd::kCompleted) << done->end_reason;
  EXPECT_EQ(loop.last_output(1), driver->safe_output_v());
  // x moved, and its motion reached the held y through the coupling.
  const hs::SimulatedStage at_rest(hs::SimulatedStageConfig::xy(), 1.0 / kRate);
  EXPECT_GT(std::abs(loop.last_measurement(1) - at_rest.axis(1).true_position()), 0.5);
}

TEST(BenchLoopStage, ARunOfMoreAxesThanTheDriverServesIsRefused) {
  auto driver = stage_driver();
  hd::BenchLoop loop(*driver, options());
  loop.step();
  auto program = excite_stage(3);
  EXPECT_NE(loop.submit(std::move(program)), nullptr);
  EXPECT_EQ(loop.state(), hd::BenchLoop::State::kIdle);
}

TEST(BenchLoopStage, TheLogHoldsASetOfColumnsPerAxisInOneRowPerTick) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("hystbench_stage_log_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  auto driver = stage_driver();
  hd::BenchLoop loop(*driver, options());
  loop.step();
  auto p = excite_stage(2);
  hd::SampleLogOptions lo;
  lo.log_dir = dir;
  lo.run_id = "stage";
  lo.axes = {"x", "y"};
  lo.update_latest_link = false;
  p->log = std::make_unique<hd::SampleLogWriter>(lo);
  auto done = play(loop, std::move(p));
  ASSERT_NE(done, nullptr);
  const auto counts = done->log->close();
  EXPECT_EQ(counts.written, kSamples);
  EXPECT_EQ(counts.dropped, 0u);
  EXPECT_EQ(done->counters.log_drops, 0u);

  std::ifstream in(dir / "stage.csv");
  std::string line;
  while (std::getline(in, line) && line.rfind('#', 0) == 0) {
  }
  const auto header = split(line);
  const std::vector<std::string> expected = {
      "index", "t",         "t_scheduled_ns", "t_wake_ns", "exec_ns", "yr_x",   "u_ff_x", "u_fb_x",
      "u_x",   "y_x",       "y_model_x",      "flags_x",   "yr_y",    "u_ff_y", "u_fb_y", "u_y",
      "y_y",   "y_model_y", "flags_y"};
  ASSERT_EQ(header, expected);
  EXPECT_EQ(hd::sample_log_columns(lo.axes), expected);
  std::uint64_t rows = 0;
  while (std::getline(in, line)) {
    const auto cells = split(line);
    ASSERT_EQ(cells.size(), expected.size()) << line;
    const std::uint64_t k = std::stoull(cells[0]);
    ASSERT_EQ(k, rows);
    EXPECT_EQ(std::stod(cells[8]), done->axis(0).records.u[k]);
    EXPECT_EQ(std::stod(cells[15]), done->axis(1).records.u[k]);
    EXPECT_EQ(std::stod(cells[16]), done->axis(1).records.y[k]);
    ++rows;
  }
  EXPECT_EQ(rows, kSamples);
  std::filesystem::remove_all(dir);
}

TEST(BenchLoopStage, ALogOfStageColumnsRefusesBadAxisNames) {
  hd::SampleLogOptions lo;
  lo.log_dir = std::filesystem::temp_directory_path();
  lo.run_id = "refused";
  for (const auto& [axes, cause] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"x"}, "2 to 6 axes"},
           {{"x", "X"}, "[a-z0-9_]"},
           {{"x", "x"}, "given twice"},
           {{"a", "b", "c", "d", "e", "f", "g"}, "2 to 6 axes"}}) {
    lo.axes = axes;
    try {
      hd::SampleLogWriter w(lo);
      ADD_FAILURE() << "accepted " << axes.size() << " axes";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(cause), std::string::npos) << e.what();
    }
  }
}

// A fault of one axis names it: here y's sensor tops out at 5 µm while its drive keeps
// rising, so its reading repeats bit for bit and the run faults on y, by its name.
TEST(BenchLoopStage, AnAxisFaultNamesTheAxis) {
  auto driver = hystbench::drivers::make_driver("loopback");
  const json stage = {
      {"axes", {{{"name", "x"}}, {{"name", "y"}, {"actuator", {{"adc", {{"range_max", 5.0}}}}}}}}};
  ASSERT_TRUE(driver->configure({{"stage", stage}}, kRate).ok);
  ASSERT_TRUE(driver->activate().ok);
  hd::BenchLoopOptions o = options();
  o.stuck_sensor.ticks = 200;
  o.stuck_sensor.output_span_v = 3.0;
  o.axis_names = {"x", "y"};
  hd::BenchLoop loop(*driver, o);
  loop.step();  // an idle tick: the loop takes runs once it runs
  auto done = play(loop, excite_stage(2));
  ASSERT_NE(done, nullptr);
  EXPECT_EQ(done->end, hd::RunEnd::kFault);
  EXPECT_EQ(std::string(done->end_reason),
            "on axis y: sensor stuck: the same reading while the output moved "
            "(loop.stuck_sensor_ms)");
  // Without names, the axis's index.
  auto unnamed_driver = hystbench::drivers::make_driver("loopback");
  ASSERT_TRUE(unnamed_driver->configure({{"stage", stage}}, kRate).ok);
  ASSERT_TRUE(unnamed_driver->activate().ok);
  o.axis_names.clear();
  hd::BenchLoop unnamed(*unnamed_driver, o);
  unnamed.step();
  auto again = play(unnamed, excite_stage(2));
  ASSERT_NE(again, nullptr);
  EXPECT_EQ(std::string(again->end_reason).rfind("on axis 1: sensor stuck", 0), 0u)
      << again->end_reason;
}
