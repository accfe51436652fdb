// fit and diagnose of records at several amplitudes through the offline commands the CLI calls
// with its defaults: a stage whose first mode stiffens with its amplitude (a cubic spring, outside
// every model family here), one that stays linear, the refusals, and the CubeSpec mirror's three
// train sets where ../shared/data holds them (the benchmark's table).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/offline/offline_command_test.hpp"
#include "hystbench/cli/offline/convert_command.hpp"
#include "hystbench/cli/offline/diagnose_command.hpp"
#include "hystbench/cli/offline/offline_commands.hpp"
#include "support/periodic_records.hpp"

namespace cli = hystbench::cli;
namespace ht = hystbench::test;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const fs::path kCubeSpec = fs::path(HYSTBENCH_SHARED_DATA_DIR) / "piezo-fsm-cubespec";
constexpr double kDt = 2e-4;
constexpr std::size_t kPeriod = 1024, kPeriods = 2, kBins = 300;  // excited up to 1.46 kHz

class AmplitudeCommandsTest : public hystbench::test::OfflineCommandTest {
 protected:
  AmplitudeCommandsTest() : OfflineCommandTest("hystbench-amplitude") {}

  // Three realizations of two periods of the cubic-spring stage (beta: its stiffening; 0 a
  // linear stage) per amplitude (per bin of its multisines), one amplitude after the other,
  // with `realization` and `period` columns, y in m as a sensor gives it.
  std::string write_record(const std::string& name, const std::vector<double>& amplitudes,
                           double beta, unsigned seed) {
    std::string file = path(name);
    std::ofstream out(file);
    out << "t,realization,period,u1_V,u2_V,y1_m,y2_m\n";
    out.precision(17);
    std::size_t realization = 0;
    for (const double amplitude : amplitudes) {
      for (const auto& u :
           ht::random_multisines(2, 3, kPeriod, kPeriods, kBins, amplitude, seed++)) {
        const Eigen::MatrixXd y = ht::cubic_spring_stage(u, kDt, beta) * 1e-6;
        for (Eigen::Index t = 0; t < u.cols(); ++t) {
          out << static_cast<double>(t) * kDt << "," << realization << ","
              << t / static_cast<Eigen::Index>(kPeriod) << "," << u(0, t) << "," << u(1, t) << ","
              << y(0, t) << "," << y(1, t) << "\n";
        }
        ++realization;
      }
    }
    return file;
  }

  template <typename Command>
  void two_by_two(Command& c) const {
    c.columns.u = "u1_V,u2_V";
    c.columns.y = "y1_m,y2_m";
    c.columns.y_scale = 1e6;
    c.json_output = true;
  }

  json diagnose(const std::vector<std::string>& records) {
    cli::DiagnoseCommand diag;
    diag.data_paths = records;
    two_by_two(diag);
    json d;
    EXPECT_EQ(run([&](auto& o, auto& e) { return cli::run_diagnose(diag, o, e); }, &d), 0) << err_;
    return d;
  }

  // fit of the records (the first, then the others) into `model`; checks it is one model of
  // three amplitudes and returns the result.
  json fit_three(const std::vector<std::string>& records, const std::string& model) {
    cli::FitCommand fit;
    fit.data_path = records.front();
    fit.more_data_paths.assign(records.begin() + 1, records.end());
    fit.output_path = model;
    two_by_two(fit);
    json f;
    EXPECT_EQ(run([&](auto& o, auto& e) { return cli::run_fit(fit, o, e); }, &f), 0) << err_;
    EXPECT_EQ(f["type"], "mimo_amplitude_scheduled");
    EXPECT_EQ(f["amplitudes"].size(), 3u);
    return f;
  }

  json simulate(const std::string& model, const std::string& record) {
    cli::SimulateCommand sim;
    sim.model_path = model;
    sim.data_path = record;
    sim.output_path = path("simulated.csv");
    sim.columns.y_scale = 1e6;
    sim.json_output = true;
    sim.skip_s = kPeriod * kDt;  // from rest: the first period is the transient
    json r;
    EXPECT_EQ(run([&](auto& o, auto& e) { return cli::run_simulate(sim, o, e); }, &r), 0) << err_;
    return r;
  }
};

// The stage's cubic spring: its first mode (150 Hz at rest) stiffens by several percent from the
// lowest amplitude to the highest.
constexpr double kBeta = 4.0;

}  // namespace

TEST_F(AmplitudeCommandsTest, AStiffeningModeIsNamedAndOneModelHoldsEveryAmplitude) {
  const std::vector<std::string> records{write_record("a2.csv", {0.004}, kBeta, 2),
                                         write_record("a1.csv", {0.002}, kBeta, 1),
                                         write_record("a3.csv", {0.006}, kBeta, 3)};
  const json d = diagnose(records);
  ASSERT_EQ(d["cause"], "amplitude_dependence") << d.dump(1);
  const json& a = d["amplitude_dependence"];
  EXPECT_GT(a["gain"].get<double>(), 1.2);
  ASSERT_EQ(a["left_out"].size(), 3u);
  EXPECT_EQ(a["left_out"][0]["data"], records[1]);  // by amplitude, lowest first
  // The spring's mode rises with the amplitude; the 600 Hz one stays.
  json spring, linear;
  for (const auto& m : a["modes"]) {
    const double f0 = m["frequency_hz"][0].get<double>();
    if (std::abs(f0 - 150.0) < 5.0) spring = m;
    if (std::abs(f0 - 600.0) < 5.0) linear = m;
  }
  ASSERT_TRUE(spring.is_object() && linear.is_object()) << a["modes"];
  EXPECT_GT(spring["shift_percent"].get<double>(), 2.0) << spring;
  EXPECT_LT(std::abs(linear["shift_percent"].get<double>()), 0.2) << linear;
  // The entry it reaches most changes most, where the spring's mode is.
  EXPECT_EQ(a["entries"][0]["input"], "u1_V");
  EXPECT_EQ(a["entries"][0]["output"], "y1_m");
  EXPECT_NEAR(a["entries"][0]["at_hz"].get<double>(), 150.0, 10.0);

  // fit of the three records gives one model; on a fourth record between two amplitudes it
  // beats the model fitted at either neighbour alone.
  const json f = fit_three(records, path("scheduled.json"));
  for (const auto& l : f["amplitudes"]) {
    EXPECT_GT(l["left_out_rms"].get<double>(), l["schedule_rms"].get<double>()) << l;
  }
  const std::string between = write_record("between.csv", {0.005}, kBeta, 7);
  const double scheduled = simulate(path("scheduled.json"), between)["rmse"].get<double>();
  // The simulation says what amplitude the schedule saw: settled at the record's own.
  std::ifstream simulated(path("simulated.csv"));
  std::string line, header;
  while (std::getline(simulated, line) && line.starts_with("#")) {
  }
  header = line;
  EXPECT_TRUE(header.ends_with(",amplitude_V") || header.find(",amplitude_V,") != std::string::npos)
      << header;
  const double settled = f["amplitudes"][1]["amplitude"].get<double>() * 1.25;  // 0.005 / 0.004
  std::string last;
  while (std::getline(simulated, line)) last = line;
  const std::size_t column = static_cast<std::size_t>(
      std::count(header.begin(),
                 header.begin() + static_cast<std::ptrdiff_t>(header.find("amplitude_V")), ','));
  std::stringstream cells(last);
  std::string cell;
  for (std::size_t k = 0; k <= column; ++k) std::getline(cells, cell, ',');
  EXPECT_NEAR(std::stod(cell), settled, 0.05 * settled) << last;
  for (const std::size_t k : {0u, 2u}) {
    cli::FitCommand one;
    one.data_path = records[k];
    one.output_path = path("one.json");
    two_by_two(one);
    ASSERT_EQ(run([&](auto& o, auto& e) { return cli::run_fit(one, o, e); }), 0) << err_;
    const double alone = simulate(path("one.json"), between)["rmse"].get<double>();
    EXPECT_LT(scheduled, 0.8 * alone) << records[k];
  }
}

TEST_F(AmplitudeCommandsTest, OneFileOfRealizationsAtSeveralAmplitudesIsSplitByThem) {
  // The three amplitudes as realizations 0-8 of one file, the middle one first.
  const std::string record = write_record("every.csv", {0.004, 0.002, 0.006}, kBeta, 1);
  const json f = fit_three({record}, path("scheduled.json"));
  ASSERT_EQ(f["amplitudes"].size(), 3u);
  EXPECT_EQ(f["amplitudes"][0]["data"], record + " (realizations 3, 4, 5)");
  EXPECT_EQ(f["amplitudes"][1]["data"], record + " (realizations 0, 1, 2)");
  EXPECT_NEAR(
      f["amplitudes"][2]["amplitude"].get<double>() / f["amplitudes"][0]["amplitude"].get<double>(),
      3.0, 0.1);
}

TEST_F(AmplitudeCommandsTest, ALinearStageIsNotNamed) {
  const json d =
      diagnose({write_record("a1.csv", {0.002}, 0.0, 1), write_record("a2.csv", {0.004}, 0.0, 2),
                write_record("a3.csv", {0.006}, 0.0, 3)});
  EXPECT_EQ(d["cause"], "none") << d.dump(1);
  EXPECT_LT(d["amplitude_dependence"]["gain"].get<double>(), 1.2);
}

TEST_F(AmplitudeCommandsTest, RefusalsNameTheCause) {
  const std::string a = write_record("a.csv", {0.002}, kBeta, 1);
  const std::string b = write_record("b.csv", {0.002}, kBeta, 5);  // the same amplitude
  cli::FitCommand fit;
  fit.data_path = a;
  fit.more_data_paths = {b};
  fit.output_path = path("m.json");
  two_by_two(fit);
  EXPECT_EQ(run([&](auto& o, auto& e) { return cli::run_fit(fit, o, e); }), 1);
  EXPECT_NE(err_.find("one amplitude"), std::string::npos) << err_;
  EXPECT_FALSE(fs::exists(path("m.json")));
  // A model of one input takes one record.
  cli::FitCommand siso;
  siso.data_path = a;
  siso.more_data_paths = {b};
  siso.output_path = path("m.json");
  EXPECT_EQ(run([&](auto& o, auto& e) { return cli::run_fit(siso, o, e); }), 1);
  EXPECT_NE(err_.find("one record"), std::string::npos) << err_;
}

// The benchmark: one model trained on the 100, 200 and 300 mV train sets, simulated on each test
// set from rest with its first 1000 samples not scored, against the published NL-LFR's figures.
TEST_F(AmplitudeCommandsTest, TheCubeSpecMirrorIsHeldAtEveryAmplitudeByOneModel) {
  const std::vector<std::string> sets{"100mV_train", "200mV_train", "300mV_train",
                                      "100mV_test",  "200mV_test",  "300mV_test"};
  for (const auto& set : sets) {
    for (const char* side : {"u_", "y_"}) {
      if (!fs::exists(kCubeSpec / (side + set + ".npy"))) {
        GTEST_SKIP() << "shared data set piezo-fsm-cubespec (" << side << set << ".npy) is not in "
                     << kCubeSpec;
      }
    }
  }
  for (const auto& set : sets) {
    cli::ConvertCommand convert;
    convert.u_path = (kCubeSpec / ("u_" + set + ".npy")).string();
    convert.y_path = (kCubeSpec / ("y_" + set + ".npy")).string();
    convert.output_path = path(set + ".csv");
    convert.rate_hz = 6400.0;
    ASSERT_EQ(run([&](auto& o, auto& e) { return cli::run_convert(convert, o, e); }), 0) << err_;
  }
  cli::FitCommand fit;
  fit.data_path = path("100mV_train.csv");
  fit.more_data_paths = {path("200mV_train.csv"), path("300mV_train.csv")};
  fit.output_path = path("mirror.json");
  fit.columns.u = "u1_V,u2_V,u3_V";
  fit.columns.y = "y1_m,y2_m,y3_m";
  fit.columns.y_scale = 1e6;
  fit.json_output = true;
  json f;
  ASSERT_EQ(run([&](auto& o, auto& e) { return cli::run_fit(fit, o, e); }, &f), 0) << err_;
  const std::map<std::string, double> published{
      {"100mV_test", 0.0866}, {"200mV_test", 0.1309}, {"300mV_test", 0.1686}};
  for (const auto& [set, nl_lfr] : published) {
    cli::SimulateCommand sim;
    sim.model_path = path("mirror.json");
    sim.data_path = path(set + ".csv");
    sim.output_path = path("simulated.csv");
    sim.columns.y_scale = 1e6;
    sim.json_output = true;
    sim.skip_s = 1000.0 / 6400.0;
    json r;
    ASSERT_EQ(run([&](auto& o, auto& e) { return cli::run_simulate(sim, o, e); }, &r), 0) << err_;
    EXPECT_LT(r["rmse"].get<double>(), nl_lfr) << set;
  }
}
