// A stage's identify fit (runs/details/stage_identify.cpp) on records made here: each axis's
// readings are put at the outputs they answer, and a driver's exchange latency becomes each
// axis's model delay, as a one-axis identify does.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "hystbench/sim/identification_excitation.hpp"
#include "runs/details/stage_runs.hpp"

namespace hc = hystbench::compensation;
namespace hd = hystbench::daemon;
using nlohmann::json;

namespace {

constexpr double kRateHz = 2000.0;  // the fit rate too: no block averaging

/// Two axes identified one at a time: in turn a, axis a plays a shortened identification
/// excitation through a classical PI (its own weights) while the other holds 0 V; the held
/// axis moves by `coupling` of the moved one's displacement. Each reading arrives `latency`
/// ticks late and says so (response_ticks), as a thread-mode Modbus exchange's.
struct StageRecord {
  std::unique_ptr<hd::RunProgram> run = std::make_unique<hd::RunProgram>();
  json fit;
};

StageRecord stage_record(std::uint32_t latency, double coupling) {
  hystbench::sim::IdentificationExcitationOptions o;
  o.rate_frequencies_hz = {0.5, 5.0};
  o.rate_cycles = {1, 4};
  o.minor_loops = 2;
  o.hold_s = 0.2;
  const auto x = hystbench::sim::identification_excitation(0.0, 100.0, 1.0 / kRateHz, o);
  const std::size_t turn = x.samples.size();
  StageRecord r;
  r.run->stage_axes.push_back(std::make_unique<hd::RunProgram>());
  std::vector<std::vector<double>> y(2, std::vector<double>(2 * turn));
  for (std::size_t a = 0; a < 2; ++a) {
    hc::PiParameters p;
    p.thresholds = hc::uniform_thresholds(8, 50.0);
    for (std::size_t i = 0; i < p.thresholds.size(); ++i) {
      p.weights.push_back(i == 0 ? 0.25 + 0.05 * a : 0.03);
    }
    hc::PiModel plant(p);
    plant.reset(0.0);
    hd::RunRecords& rec = r.run->axis(a).records;
    rec.u.assign(2 * turn, 0.0);
    rec.response.assign(2 * turn, latency);
    for (std::size_t k = 0; k < turn; ++k) rec.u[a * turn + k] = x.samples[k];
    std::vector<double> own(2 * turn);
    for (std::size_t k = 0; k < 2 * turn; ++k) own[k] = plant.step(rec.u[k]);
    for (std::size_t k = 0; k < 2 * turn; ++k) {
      const std::size_t from = k >= latency ? k - latency : 0;
      y[a][k] += own[from];
      y[1 - a][k] += coupling * own[from];
    }
  }
  for (std::size_t a = 0; a < 2; ++a) {
    hd::RunRecords& rec = r.run->axis(a).records;
    rec.y = y[a];
    rec.yr.assign(2 * turn, 0.0);
    rec.capacity = rec.count = 2 * turn;
  }
  r.fit = {{"model", "pi"},        {"operators", 8},         {"axes", {"x", "y"}},
           {"turn_samples", turn}, {"record_samples", turn}, {"skip_samples", 0},
           {"u_min", 0.0},         {"u_max", 100.0}};
  return r;
}

hd::BenchSettings settings() {
  hd::BenchSettings s;
  s.loop.rate_hz = kRateHz;
  s.identify.fit_rate_hz = kRateHz;
  return s;
}

}  // namespace

TEST(StageIdentify, AnExchangeLatencyBecomesEachAxisModelDelay) {
  const StageRecord late = stage_record(2, 0.1);
  const hd::details::StageModel m =
      hd::details::fit_stage_identify(*late.run, late.fit, settings());
  ASSERT_EQ(m.models.size(), 2u);
  for (std::size_t a = 0; a < 2; ++a) {
    SCOPED_TRACE(a);
    EXPECT_DOUBLE_EQ(m.models[a].model.delay_s(), 2.0 / kRateHz);
    const json& figures = m.report["axes"][a == 0 ? "x" : "y"];
    EXPECT_EQ(figures["delay_samples"], 2);
    // Aligned, the record is the plant's own: the PI family fits it to a nanometre.
    EXPECT_LT(figures["heldout_rms_error_um"].get<double>(), 1e-3) << figures.dump();
  }
  EXPECT_NEAR(m.coupling.gains(1, 0), 0.1, 1e-3);
  EXPECT_NEAR(m.coupling.gains(0, 1), 0.1, 1e-3);

  // Readings that answer their own tick: no delay.
  const StageRecord prompt = stage_record(0, 0.1);
  const hd::details::StageModel p =
      hd::details::fit_stage_identify(*prompt.run, prompt.fit, settings());
  EXPECT_EQ(p.models[0].model.delay_s(), 0.0);
  EXPECT_EQ(p.report["axes"]["x"]["delay_samples"], 0);
}
