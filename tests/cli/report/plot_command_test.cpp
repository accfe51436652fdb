// `hystbench plot`: a run log drawn as three non-empty PNGs, the error named for a log that is
// not one, and a log without reference or model still drawn.
#include "hystbench/cli/report/plot_command.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

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

  // A run log as the daemon writes it: a JSON header comment, NaN where a column has no value
  // (yr during the precondition sweep), 50 000 samples (thinned for the plot).
  std::string write_log(bool with_reference) {
    const fs::path path = dir_ / "run.csv";
    std::ofstream f(path);
    f << "# {\"run_id\":\"test\"}\nindex,t,yr,u,y,y_model,flags\n";
    for (int k = 0; k < 50000; ++k) {
      const double t = k * 1e-4;
      const double u = 75.0 + 70.0 * std::sin(2.0 * std::numbers::pi * t);
      const double y = 0.3 * u + 2.0 * std::cos(2.0 * std::numbers::pi * t);
      f << k << ',' << t << ',';
      if (with_reference && k >= 10000) {
        f << y + 0.01 * std::sin(40.0 * t);
      } else {
        f << "NaN";
      }
      f << ',' << u << ',' << y << ',' << y - 0.02 << ",0\n";
    }
    return path.string();
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
}

TEST_F(PlotCommandTest, ALogWithoutReferenceIsDrawnWithItsModelError) {
  const std::string log = write_log(false);
  const auto pngs = cli::plot_run_log(log, dir_ / "p");
  ASSERT_EQ(pngs.size(), 3u);
  for (const auto& p : pngs) EXPECT_GT(fs::file_size(p), 2000u) << p;
  EXPECT_EQ(cli::default_plot_dir(log), dir_ / "run-plots");
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
