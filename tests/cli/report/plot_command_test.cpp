// `hystbench plot`: a run log drawn as three non-empty PNGs, the error named for a log that is
// not one, and a log without reference or model still drawn.
#include "hystbench/cli/report/plot_command.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace cli = hystbench::cli;
namespace fs = std::filesystem;

namespace {

class PlotCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) {
      GTEST_SKIP() << "gnuplot is not installed (scripts/deps.sh installs it)";
    }
    dir_ = fs::temp_directory_path() /
           ("hystbench_plot_test_" +
            std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A run log as the daemon writes it: a JSON header comment with the flag bits, the open-loop
  // rows (the precondition sweep; all of them without a reference) flagged with yr = y_model,
  // 50 000 samples (thinned for the plot).
  std::string write_log(bool with_reference) {
    const fs::path path = dir_ / "run.csv";
    std::ofstream f(path);
    f << "# {\"run_id\":\"test\"}\n# {\"flags\":{\"stale\":64,\"open_loop\":128}}\n"
      << "index,t,yr,u,y,y_model,flags\n";
    for (int k = 0; k < 50000; ++k) {
      const double t = k * 1e-4;
      const double u = 75.0 + 70.0 * std::sin(2.0 * std::numbers::pi * t);
      const double y = 0.3 * u + 2.0 * std::cos(2.0 * std::numbers::pi * t);
      const bool followed = with_reference && k >= 10000;
      f << k << ',' << t << ',' << (followed ? y + 0.01 * std::sin(40.0 * t) : y - 0.02) << ',' << u
        << ',' << y << ',' << y - 0.02 << ',' << (followed ? 0 : 128) << '\n';
    }
    return path.string();
  }

  // plot.dat's rows: t u y yr y_model error_min error_max.
  std::vector<std::array<double, 7>> plotted(const fs::path& dat) {
    std::vector<std::array<double, 7>> rows;
    std::ifstream in(dat);
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream cells(line);
      std::array<double, 7> r{};
      for (double& v : r) {
        std::string cell;
        cells >> cell;
        v = cell == "NaN" ? std::numeric_limits<double>::quiet_NaN() : std::stod(cell);
      }
      rows.push_back(r);
    }
    return rows;
  }

  fs::path dir_;
};

}  // namespace

TEST_F(PlotCommandTest, WritesTheThreePicturesOfARunLog) {
  const std::string log = write_log(true);
  std::ostringstream out, err;
  ASSERT_EQ(cli::run_plot({log, (dir_ / "plots").string(), false}, out, err), 0) << err.str();
  for (const char* name : {"time.png", "error.png", "loop.png"}) {
    const fs::path png = dir_ / "plots" / name;
    ASSERT_TRUE(fs::exists(png)) << name;
    EXPECT_GT(fs::file_size(png), 2000u) << name;
    EXPECT_NE(out.str().find(png.string()), std::string::npos) << out.str();
  }
  // Thinned to at most 20 000 points, each bin's error extremes kept.
  std::ifstream dat(dir_ / "plots" / "plot.dat");
  std::size_t lines = 0;
  for (std::string line; std::getline(dat, line);) ++lines;
  EXPECT_LE(lines, 20001u);
  EXPECT_GT(lines, 10000u);
  // The open-loop rows draw no reference and no tracking error; after them, the reference's
  // error (0.01 um at most here, where the model's is 0.02).
  for (const auto& r : plotted(dir_ / "plots" / "plot.dat")) {
    if (r[0] < 1.0 - 1e-3) {
      ASSERT_TRUE(std::isnan(r[3])) << r[0];
      ASSERT_TRUE(std::isnan(r[5])) << r[0];
    } else if (r[0] > 1.0 + 1e-3) {
      ASSERT_FALSE(std::isnan(r[3])) << r[0];
      ASSERT_LE(std::abs(r[6]), 0.0100001) << r[0];
    }
  }
}

TEST_F(PlotCommandTest, ALogWithoutReferenceIsDrawnWithItsModelError) {
  const std::string log = write_log(false);
  const auto pngs = cli::plot_run_log(log, dir_ / "p");
  ASSERT_EQ(pngs.size(), 3u);
  for (const auto& p : pngs) EXPECT_GT(fs::file_size(p), 2000u) << p;
  EXPECT_EQ(cli::default_plot_dir(log), dir_ / "run-plots");
  // No row follows a reference: none is drawn, and the error is the model's (the log's six
  // digits round it).
  for (const auto& r : plotted(dir_ / "p" / "plot.dat")) {
    ASSERT_TRUE(std::isnan(r[3])) << r[0];
    ASSERT_NEAR(r[5], 0.02, 1e-4) << r[0];
  }
}

TEST_F(PlotCommandTest, AFileThatIsNotARunLogIsRefusedByName) {
  const fs::path path = dir_ / "other.csv";
  std::ofstream(path) << "t,x\n0,1\n1,2\n";
  std::ostringstream out, err;
  EXPECT_EQ(cli::run_plot({path.string(), (dir_ / "q").string(), false}, out, err), 1);
  EXPECT_NE(err.str().find("no 'u' column"), std::string::npos) << err.str();
  EXPECT_FALSE(fs::exists(dir_ / "q" / "time.png"));
}

// learning.png: each trial's rms and max, and the last trial's error from the log's last period
// (its data file holds exactly that period, y - yr).
TEST_F(PlotCommandTest, ALearningRunDrawsItsTrialsAndItsLastTrial) {
  const std::string log = write_log(true);
  nlohmann::json learning = {{"period_samples", 1000}, {"trials", nlohmann::json::array()}};
  for (int k = 0; k < 4; ++k) {
    learning["trials"].push_back({{"trial", k},
                                  {"rms_error_percent", std::pow(0.3, k)},
                                  {"max_error_percent", 3.0 * std::pow(0.3, k)}});
  }
  const fs::path png = cli::plot_learning(learning, log, dir_);
  EXPECT_EQ(png, dir_ / "learning.png");
  ASSERT_TRUE(fs::exists(png));
  EXPECT_GT(fs::file_size(png), 10000u);  // two panels drawn, not an empty canvas
  std::ifstream dat(dir_ / "learning.dat");
  std::string line;
  int trials = 0, last = 0, block = 0;
  while (std::getline(dat, line)) {
    if (line.empty()) {
      block = 1;
    } else if (line[0] != '#') {
      ++(block == 0 ? trials : last);
    }
  }
  EXPECT_EQ(trials, 4);
  EXPECT_EQ(last, 1000);
  // A learning without a trial, or a log shorter than one, is named.
  nlohmann::json none = learning;
  none["trials"] = nlohmann::json::array();
  EXPECT_THROW(cli::plot_learning(none, log, dir_), std::runtime_error);
  nlohmann::json long_period = learning;
  long_period["period_samples"] = 100000;
  EXPECT_THROW(cli::plot_learning(long_period, log, dir_), std::runtime_error);
}
