// `hystbench sweep` against a real daemon on the loopback: one row per compensator and
// frequency, and with --learn N a column of learned errors (a `track --learn N` run at each
// frequency from the daemon's default compensator), its trials in the JSON rows.
#include "hystbench/cli/remote/sweep_command.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/daemon_process.hpp"
#include "support/temp_dir_test.hpp"

namespace cli = hystbench::cli;
using nlohmann::json;

namespace {

class SweepCommandTest : public hystbench::test::TempDirTest {
 protected:
  SweepCommandTest() : TempDirTest("hbsweep") {}
};

const json* row(const json& rows, double f, const std::string& column) {
  for (const json& r : rows) {
    if (r["frequency_hz"] == f && r["compensator"] == column) return &r;
  }
  return nullptr;
}

}  // namespace

TEST_F(SweepCommandTest, LearnAddsAColumnOfLearnedErrors) {
  hystbench::testing::Daemon daemon(dir_);
  ASSERT_TRUE(daemon.running()) << "hystbenchd did not start";
  cli::SweepCommand cmd;
  cmd.socket_path = daemon.socket();
  cmd.frequencies_hz = {20.0, 50.0};
  cmd.compensators = {"none"};
  cmd.learn_trials = 4;
  cmd.json_output = true;
  std::ostringstream out, err;
  ASSERT_EQ(cli::run_sweep(cmd, out, err), 0) << err.str();
  const json sweep = json::parse(out.str());
  EXPECT_EQ(sweep["learn_trials"], 4);
  for (const double f : cmd.frequencies_hz) {
    const json* none = row(sweep["rows"], f, "none");
    const json* learned = row(sweep["rows"], f, "learned");
    ASSERT_NE(none, nullptr) << sweep.dump(2);
    ASSERT_NE(learned, nullptr) << sweep.dump(2);
    EXPECT_EQ((*learned)["end"], "completed") << learned->dump(2);
    EXPECT_EQ((*learned)["learn_trials"], 4);
    const json& trials = (*learned)["learning"]["trials_rms_percent"];
    // The compensator's, its repeat (the bench's floor), then four learned.
    ASSERT_EQ(trials.size(), 6u) << learned->dump(2);
    EXPECT_DOUBLE_EQ((*learned)["rms_error_percent"].get<double>(), trials.back().get<double>());
    // Without a model the learning starts from `none` and corrects most of its error.
    EXPECT_LT((*learned)["rms_error_percent"].get<double>(),
              0.5 * (*none)["rms_error_percent"].get<double>())
        << sweep.dump(2);
    EXPECT_FALSE((*learned)["learning"]["drive"].get<std::string>().empty()) << learned->dump(2);
  }
  // The table has the column too.
  cmd.json_output = false;
  cmd.frequencies_hz = {20.0};
  std::ostringstream table;
  ASSERT_EQ(cli::run_sweep(cmd, table, err), 0) << err.str();
  EXPECT_NE(table.str().find("learned (4)"), std::string::npos) << table.str();
}
