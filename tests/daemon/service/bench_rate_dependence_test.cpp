// The rate-dependent path on the bench, as a user takes it: the loopback actuator with its rate
// dependence switched on (`[actuator.rate_dependence] enabled = true`, every other key at its
// default: a Preisach truth whose relays switch behind a front, a law no rpi model contains),
// `identify --model mpi` and `--model rpi` with the daemon's defaults, then sine tracking at
// 1-19 Hz. The rate-dependent inverse tracks the fastest sine better than the rate-independent
// one, is at most 40 % worse at any frequency (a law linear in the rate fitted to a front
// whose lag grows with its square root gives up some of the slow sines for the fast ones; which
// law identify keeps varies between runs, and so does the mpi's slow sine; identify keeps a law
// when it tracks a 20 Hz sine better than its rate-free self, or adds one back from the diagnosis
// of its own record when that tracks better on the bench) and stays within 1.5 % of range, also
// over a reference too long to plan whole. The targets (1 % at every frequency, 85 % below the
// rate-independent inverse on average) are missed: most of what both leave is the Preisach
// loop's shape, and no rate law follows a switching front (docs/measurements.md). No compensator
// may be worse than none and feedback never makes tracking worse; every sample carries the model's
// prediction, and a second identify reports the previous model's error where it is known.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/cli/remote/remote_commands.hpp"
#include "hystbench/compensation/drive_planner.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/daemon/config/config.hpp"
#include "hystbench/daemon/config/daemon_settings.hpp"
#include "hystbench/daemon/loop/sample_log_writer.hpp"
#include "support/bench_fixture.hpp"

namespace hc = hystbench::compensation;
namespace hd = hystbench::daemon;
namespace cli = hystbench::cli;
using nlohmann::json;

namespace {

class BenchRateDependenceTest : public hystbench::test::BenchFixture {
 protected:
  BenchRateDependenceTest() : BenchFixture("hystbench_rate_test") {}

  json track(const std::string& compensator, double f, double periods) {
    return run_and_wait("track", {{"reference", "sine"},
                                  {"frequency_hz", f},
                                  {"periods", periods},
                                  {"compensator", compensator}});
  }

  static double rms(const json& r) { return r.at("rms_error_percent").get<double>(); }
};

constexpr const char* kRateDependent = "[actuator.rate_dependence]\nenabled = true\n";

}  // namespace

TEST_F(BenchRateDependenceTest, RateDependentInverseTracksAcrossFrequencyAndPidNeverHurts) {
  start(settings_from_toml(loopback_toml(kRateDependent)));
  const double freqs[] = {1.0, 5.0, 10.0, 19.0};
  std::map<double, double> mpi_rms, rpi_rms, none_rms;

  const json id_mpi = run_and_wait("identify", {{"model", "mpi"}});
  ASSERT_EQ(id_mpi["end"], "completed") << id_mpi.dump(2);
  ASSERT_FALSE(id_mpi.contains("fit_error")) << id_mpi.dump(2);
  const double mpi_heldout = id_mpi["model"]["heldout"]["rmse"].get<double>();
  std::cout << "mpi extension: " << id_mpi["model"]["extension"].dump() << "\n";
  for (const double f : freqs) {
    const json none = track("none", f, f < 2 ? 3 : 6);
    ASSERT_EQ(none["end"], "completed") << none.dump(2);
    none_rms[f] = rms(none);
    const json inv = track("inverse", f, f < 2 ? 3 : 6);
    ASSERT_EQ(inv["end"], "completed") << inv.dump(2);
    mpi_rms[f] = rms(inv);  // worse than none from 10 Hz: the wrong model for this actuator
    const json pid = track("inverse+pid", f, f < 2 ? 3 : 6);
    ASSERT_EQ(pid["end"], "completed") << pid.dump(2);
    // The loop designed on the measured responses, its crossover far above these references:
    // with the wrong model for this actuator it takes most of the feedforward's error out.
    EXPECT_EQ(pid["feedback"]["gains"], "designed") << pid.dump(2);
    EXPECT_TRUE(pid["feedback"]["meets_targets"].get<bool>()) << pid.dump(2);
    EXPECT_LE(rms(pid), 0.5 * mpi_rms[f]) << f << " Hz: " << pid.dump(2);
  }

  const json id_rpi = run_and_wait("identify", {{"model", "rpi"}});
  ASSERT_EQ(id_rpi["end"], "completed") << id_rpi.dump(2);
  ASSERT_EQ(id_rpi["model"]["type"], "rpi") << id_rpi.dump(2);
  std::cout << "rpi extension: " << id_rpi["model"]["extension"].dump() << "\n";
  std::cout << "rpi rate law: " << id_rpi["model"]["rate_law"].dump() << "\n";
  // Nesting on the bench: the MPI is an RPI with zero rate coefficients. The two identify runs
  // are separate records, so allow their noise to differ a little.
  EXPECT_LE(id_rpi["model"]["heldout"]["rmse"].get<double>(), 1.1 * mpi_heldout) << id_rpi.dump(2);
  // identify chose one of its laws for the front (none is the truth's) and kept it up to its
  // record's rates; a thresholds law says how far they widen. The law and its rate-free self
  // were both played on the 20 Hz sine, where a rate law shows (on the slow triangle the two
  // differ by no more than two runs), and the result says how they fared.
  std::ifstream model_file(id_rpi["model"]["path"].get<std::string>());
  const json rpi_model = json::parse(model_file);
  const json& rate = rpi_model.at("rate");
  EXPECT_TRUE(rate["law"] == "signed" || rate["law"] == "magnitude" || rate["law"] == "thresholds")
      << rate;
  const json& judged = id_rpi["model"]["rate_law"];
  ASSERT_TRUE(judged.is_object()) << id_rpi.dump(2);
  EXPECT_DOUBLE_EQ(judged["sine_hz"].get<double>(), 20.0);
  for (const char* who : {"law", "rate_free"}) {
    EXPECT_TRUE(judged["sine_rms_percent"][who].is_number()) << judged;
    EXPECT_TRUE(judged["triangle_rms_percent"][who].is_number()) << judged;
  }
  // The law reaches the model by one of two routes, and `hystbench identify` says which: kept
  // because it tracks the rate sine better than its rate-free self (on this truth by about 20 %),
  // or, where it lost on the triangle, left out and added again by the diagnosis of identify's
  // own record (a thresholds law with creep tracked 20 Hz at 0.92 % against 1.48 % without).
  const json& extension = id_rpi["model"].value("extension", json::object());
  const bool extended_by_rate = adopted_part(extension, "rate_dependence");
  EXPECT_TRUE(judged["kept"].get<bool>() || extended_by_rate) << judged << extension;
  std::ostringstream text;
  cli::print_run_result(id_rpi, text);
  EXPECT_NE(text.str().find(judged["kept"].get<bool>() ? "rate law        kept: 20 Hz sine rms "
                                                       : "extension       rate_dependence"),
            std::string::npos)
      << text.str();
  if (rate["law"] == "thresholds") {
    EXPECT_GT(rate.value("threshold_s", 0.0), 0.0) << rate;
  }
  EXPECT_GE(rate["record_max_rate"].get<double>(), rate["max_rate"].get<double>()) << rate;
  // Which laws lag the drive and are planned over a known reference (compensation::plan_drive).
  const bool plans = hc::can_plan_drive(hc::model_file_from_json(rpi_model).model);
  double reduction_sum = 0.0;
  for (const double f : freqs) {
    // The truth's creep relaxes while the bench idles at its safe output (as long as the host
    // takes to fit: a slower machine idles longer), and no model here holds it: the rpi's first
    // 1 Hz inverse after identify tracked at 0.86-1.07 % by the idle before it, 0.82-0.87 %
    // after an uncompensated run. So each inverse follows the same run as the mpi's did.
    const json none = track("none", f, f < 2 ? 3 : 6);
    ASSERT_EQ(none["end"], "completed") << none.dump(2);
    const json inv = track("inverse", f, f < 2 ? 3 : 6);
    ASSERT_EQ(inv["end"], "completed") << inv.dump(2);
    rpi_rms[f] = rms(inv);
    // The model's own prediction is in the result.
    ASSERT_TRUE(inv.contains("model_rms_error_percent")) << inv.dump(2);
    EXPECT_TRUE(std::isfinite(inv["model_rms_error_percent"].get<double>()));
    // Hysteresis first; the rate law after it (a creep part, where one was added, between).
    const json& inverted = inv["feedforward"]["inverted"];
    EXPECT_EQ(inverted[0], "hysteresis") << inv.dump(2);
    EXPECT_NE(std::find(inverted.begin(), inverted.end(), "rate"), inverted.end()) << inv.dump(2);
    // A law that lags the drive is planned over the known reference, unless the previewed
    // inverse already meets the targets on the model; the result says which, and a plan that
    // plays beats the previewed inverse on the model. The signed law with weights growing with
    // the rate is inverted exactly each tick: nothing is planned and the result says so.
    const std::string how = inv["feedforward"].value("rate", "");
    if (plans) {
      EXPECT_NE(how.find("planned"), std::string::npos) << inv.dump(2);
      const json& plan = inv["feedforward"]["planned"];
      ASSERT_TRUE(plan.is_object()) << inv.dump(2);
      if (plan["samples"].get<double>() > 0.0) {
        EXPECT_LE(plan["model_rms_um"].get<double>(), plan["previewed_model_rms_um"].get<double>())
            << inv.dump(2);
      } else {
        EXPECT_FALSE(plan.value("why_not", "").empty()) << inv.dump(2);
      }
    } else {
      EXPECT_NE(how.find("exact"), std::string::npos) << inv.dump(2);
      EXPECT_FALSE(inv["feedforward"].contains("planned")) << inv.dump(2);
    }
    EXPECT_LE(rpi_rms[f], 1.4 * mpi_rms[f] + 0.02) << f << " Hz: " << inv.dump(2);
    if (f == 19.0) {
      EXPECT_LT(rpi_rms[f], mpi_rms[f]) << f << " Hz: " << inv.dump(2);
    }
    EXPECT_LE(rpi_rms[f], 1.5) << f << " Hz: " << inv.dump(2);
    EXPECT_LE(rpi_rms[f], none_rms[f]) << f << " Hz: " << inv.dump(2);
    const json pid = track("inverse+pid", f, f < 2 ? 3 : 6);
    ASSERT_EQ(pid["end"], "completed") << pid.dump(2);
    EXPECT_LE(rms(pid), 1.05 * rpi_rms[f] + 0.02) << f << " Hz: " << pid.dump(2);
    if (f == 5.0 || f == 19.0) {
      // No compensator is worse than none. `pid` adds its feedback to the linear map's drive
      // (an integral loop alone trailed 1 Hz by 26 % of range); `inverse_multiplicative` plays
      // the plan too (its one-tick loop through a law that lags the drive trailed by 21-44 %).
      // Against none run in this phase (at 19 Hz none differs by 5 % between the two phases).
      for (const char* other : {"pid", "inverse_multiplicative"}) {
        const json r = track(other, f, 6);
        ASSERT_EQ(r["end"], "completed") << r.dump(2);
        EXPECT_LE(rms(r), 1.05 * rms(none) + 0.02) << other << ", " << f << " Hz: " << r.dump(2);
      }
    }
    reduction_sum += 1.0 - rpi_rms[f] / mpi_rms[f];
    std::cout << f << " Hz: none " << none_rms[f] << " %, mpi inverse " << mpi_rms[f]
              << " %, rpi inverse " << rpi_rms[f] << " %, rpi inverse+pid " << rms(pid)
              << " % of range (rms)\n";
  }
  // A periodic reference longer than the planner takes (its work: samples x (plays + 2) within
  // 1e6): its first four periods are planned and the third repeats. The previewed inverse that
  // played such a reference before tracked 10 Hz at 11 % rms (10 s).
  const double plays = static_cast<double>(rpi_model["play"]["thresholds"].size());
  const double longest_s = 1e6 / (plays + 2.0) / 10000.0;
  // Planned in part, or the previewed inverse when it already meets the targets on the model.
  const json lng = run_and_wait("track", {{"reference", "sine"},
                                          {"frequency_hz", 10.0},
                                          {"duration_s", std::ceil(1.2 * longest_s)},
                                          {"compensator", "inverse"}});
  ASSERT_EQ(lng["end"], "completed") << lng.dump(2);
  const json long_plan = lng["feedforward"].value("planned", json::object());
  if (!plans) {
    EXPECT_FALSE(lng["feedforward"].contains("planned")) << lng.dump(2);
  } else if (long_plan.at("samples").get<double>() > 0.0) {
    EXPECT_EQ(long_plan["samples"].get<double>(), 10000.0 * std::ceil(1.2 * longest_s))
        << lng.dump(2);
    EXPECT_LT(long_plan["optimised_samples"].get<double>(), long_plan["samples"].get<double>())
        << lng.dump(2);
  } else {
    EXPECT_FALSE(long_plan.value("why_not", "").empty()) << lng.dump(2);
  }
  EXPECT_LE(rms(lng), 1.5) << lng.dump(2);
  std::cout << "10 Hz for " << std::ceil(1.2 * longest_s) << " s: rpi inverse " << rms(lng)
            << " % of range (rms), " << long_plan.value("optimised_samples", 0.0) << " of "
            << long_plan.value("samples", 0.0) << " samples planned\n";

  const double mean_reduction = reduction_sum / 4.0;
  std::cout << "mean reduction of the rpi inverse against the mpi inverse: "
            << 100.0 * mean_reduction << " %\n";
  // The target is 85 %. On this truth the rate law gains most at 10-19 Hz (19-25 % at 19 Hz)
  // and gives up some of the slow sines for it (-12..-20 % at 1 Hz); the rest is the loop's
  // shape, which no rate law removes. What a rate law must do: gain more the faster the sine.
  EXPECT_GT(1.0 - rpi_rms[19.0] / mpi_rms[19.0], 1.0 - rpi_rms[1.0] / mpi_rms[1.0]);
}

// The default truth at 1 Hz: the inverse's max error is 0.36 % of range through the plane that
// identify's extension keeps, 1.8-1.9 % through the modified PI where the extension is not
// adopted (the plane's own test, BenchTest.IdentifyKeepsThePlane*, holds the targets); far below
// none, and the feedback lowers it. Which of two near-equal candidates identify keeps, and whether
// its extension is adopted, follows the truth's state at identify's start: with another identify
// running beside it the modified PI once tracked at 2.36 % max (0.85 % rms), so the bounds sit
// above that spread and the choice is printed when they fail.
TEST_F(BenchRateDependenceTest, WithoutRateDependenceTodaysFiguresHoldAndEverySampleHasYModel) {
  start(settings_from_toml(loopback_toml()));
  const json id = run_and_wait("identify", json::object());
  ASSERT_EQ(id["end"], "completed") << id.dump(2);
  // The first identify had only the linear map as predictor: y_model is filled all the same.
  ASSERT_TRUE(id.contains("model_rms_error_percent")) << id.dump(2);

  const json inv = run_and_wait(
      "track",
      {{"reference", "triangle"}, {"frequency_hz", 1}, {"periods", 3}, {"compensator", "inverse"}});
  ASSERT_EQ(inv["end"], "completed") << inv.dump(2);
  std::ostringstream choice;
  choice << "chosen by " << id["model"].value("chosen_by", "") << ", extension "
         << id["model"].value("extension", json::object()).value("adopted", false) << "; ";
  for (const auto& c : id.value("candidates", json::array())) {
    choice << c.value("label", "") << ": triangle max "
           << c["verification"].value("max_error_percent", NAN) << " %, rms "
           << c["verification"].value("rms_error_percent", NAN) << " %; ";
  }
  EXPECT_LE(inv["max_error_percent"].get<double>(), 2.6) << choice.str() << inv.dump(2);
  EXPECT_LE(inv["rms_error_percent"].get<double>(), 1.0) << choice.str() << inv.dump(2);
  const json none = run_and_wait(
      "track",
      {{"reference", "triangle"}, {"frequency_hz", 1}, {"periods", 3}, {"compensator", "none"}});
  ASSERT_EQ(none["end"], "completed") << none.dump(2);
  EXPECT_LE(inv["max_error_percent"].get<double>(), none["max_error_percent"].get<double>() / 6.0)
      << inv.dump(2);
  const json pid = run_and_wait("track", {{"reference", "triangle"},
                                          {"frequency_hz", 1},
                                          {"periods", 3},
                                          {"compensator", "inverse+pid"}});
  ASSERT_EQ(pid["end"], "completed") << pid.dump(2);
  EXPECT_LE(pid["rms_error_percent"].get<double>(), inv["rms_error_percent"].get<double>());

  // Every sample of the run log holds the model's output for the drive applied, and the result's
  // model error is the rms of y - y_model over the scored samples.
  const auto table = cli::DataTable::read_csv(inv["log"].get<std::string>());
  const auto& y_model = table.column("y_model");
  const auto& y = table.column("y");
  ASSERT_EQ(y_model.size(), table.rows());
  for (std::size_t k = 0; k < y_model.size(); ++k) ASSERT_TRUE(std::isfinite(y_model[k])) << k;
  const json header = hd::read_sample_log_header(inv["log"].get<std::string>());
  const auto from = header["run"]["metrics_from"].get<std::size_t>();
  double sum = 0.0, sum2 = 0.0;
  for (std::size_t k = from; k < y.size(); ++k) {
    sum += y[k] - y_model[k];
    sum2 += (y[k] - y_model[k]) * (y[k] - y_model[k]);
  }
  const double rms_from_log = std::sqrt(sum2 / static_cast<double>(y.size() - from));
  EXPECT_NEAR(rms_from_log, inv["model_rms_error_um"].get<double>(),
              1e-3 * inv["model_rms_error_um"].get<double>());
  EXPECT_NEAR(sum / static_cast<double>(y.size() - from), inv["model_mean_error_um"].get<double>(),
              1e-3 * inv["model_rms_error_um"].get<double>());
  EXPECT_LT(inv["model_rms_error_percent"].get<double>(), 2.0) << inv.dump(2);

  // A second identify reports the active model against the new record where the drive has swept
  // the range (its major loop on), not over the settle that starts wherever the last run left
  // the actuator (scored from the first sample, an rpi model read 45 % there).
  const json id2 = run_and_wait("identify", json::object());
  ASSERT_EQ(id2["end"], "completed") << id2.dump(2);
  EXPECT_EQ(id2["y_model"], "the model active before this identification") << id2.dump(2);
  EXPECT_LT(id2["model_rms_error_percent"].get<double>(), 1.0) << id2.dump(2);
}

// The Preisach plane's rate law through the user's path, on a 1 kHz loop with the rate
// dependence on and every other key at its default: identify --model preisach fits the plane
// with its relays widening with the rate, verifies it against the plane refitted without the law
// on the rate sine, and keeps it (on this truth it tracks the 20 Hz sine at 1.5 % rms, the plane
// without it at 4.9 %). The model file holds the law, the track result names it inverted, and a
// 19 Hz sine through its inverse tracks within 2 % of range, the second time as the first.
TEST_F(BenchRateDependenceTest, ThePlanesRateLawIsKeptOnTheBenchAndItsInverseTracks) {
  start(settings_from_toml(loopback_toml(kRateDependent, kSimulatedClock, 1000.0)));
  const json id = run_and_wait("identify", {{"model", "preisach"}});
  ASSERT_EQ(id["end"], "completed") << id.dump(2);
  ASSERT_EQ(id["model"]["type"], "preisach") << id.dump(2);
  ASSERT_TRUE(id["model"].contains("rate_law")) << id["model"].dump(2);
  const json& law = id["model"]["rate_law"];
  std::cout << "plane rate law: " << law.dump() << "\n";
  ASSERT_TRUE(law["kept"].get<bool>()) << law.dump();
  EXPECT_LE(law["sine_rms_percent"]["law"].get<double>(),
            0.5 * law["sine_rms_percent"]["rate_free"].get<double>())
      << law.dump();
  const json file = bench_->handle("model.get", json::object())["model"];
  EXPECT_EQ(file["preisach"]["rate"]["law"], "thresholds") << file.dump();
  double first = 0.0;
  for (int pass = 0; pass < 2; ++pass) {
    const json inv = track("inverse", 19.0, 10.0);
    ASSERT_EQ(inv["end"], "completed") << inv.dump(2);
    std::cout << "19 Hz through the plane's inverse: " << rms(inv) << " % rms\n";
    EXPECT_LE(rms(inv), 2.0) << inv.dump(2);
    if (pass == 0) first = rms(inv);
    EXPECT_LE(rms(inv), 1.1 * first) << inv.dump(2);
    const json& inverted = inv["feedforward"]["inverted"];
    EXPECT_NE(std::find(inverted.begin(), inverted.end(), "rate"), inverted.end()) << inv.dump(2);
  }
}
