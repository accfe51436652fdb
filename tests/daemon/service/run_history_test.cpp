// The runs kept (service/details/run_history.hpp): summaries newest first with the figure
// a list shows, each result whole, the faults among them, all bounded.
#include "service/details/run_history.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "hystbench/common/command_error.hpp"
#include "support/temp_dir_test.hpp"

namespace hdd = hystbench::daemon::details;
using nlohmann::json;

TEST(RunHistory, ListsNewestFirstWithTheFigureEachKindOfRunStates) {
  hdd::RunHistory h;
  h.add({{"run_id", "a"},
         {"kind", "track"},
         {"end", "completed"},
         {"rms_error_percent", 0.5},
         {"log", "/logs/a.csv"}});
  h.add({{"run_id", "b"},
         {"kind", "identify"},
         {"end", "completed"},
         {"model_rms_error_percent", 5.0},  // the straight line's before any model
         {"verification", {{"rms_error_percent", 0.2}}}});
  h.add({{"run_id", "c"},
         {"kind", "track"},
         {"end", "completed"},
         {"axes", {{"x", {{"rms_error_percent", 0.1}}}, {"y", {{"rms_error_percent", 0.3}}}}}});
  h.add(
      {{"run_id", "d"}, {"kind", "excite"}, {"end", "stopped"}, {"reason", "stopped by request"}});
  h.add({{"run_id", "e"},
         {"kind", "identify"},
         {"end", "completed"},
         {"stage_model",
          {{"axes",
            {{"x", {{"heldout_rms_error_percent", 0.25}}},
             {"y", {{"heldout_rms_error_percent", 0.08}}}}}}}});
  EXPECT_EQ(h.runs()["runs"][0]["rms_error_percent"], 0.25);  // a stage's fits: the worst
  const json all = h.runs()["runs"];
  const json runs(all.begin() + 1, all.end());
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(runs[0]["run_id"], "d");
  EXPECT_TRUE(runs[0]["rms_error_percent"].is_null());  // nothing tracked
  EXPECT_TRUE(runs[0]["log"].is_null());
  EXPECT_EQ(runs[0]["reason"], "stopped by request");
  EXPECT_EQ(runs[1]["rms_error_percent"], 0.3);  // a stage: its worst axis
  EXPECT_EQ(runs[2]["rms_error_percent"], 0.2);  // identify: its verification
  EXPECT_EQ(runs[3]["rms_error_percent"], 0.5);
  EXPECT_EQ(runs[3]["log"], "/logs/a.csv");
  EXPECT_EQ(runs[3]["finished"].get<std::string>().size(), 20u);  // 2026-01-01T00:00:00Z
  EXPECT_EQ(h.run("b")["verification"]["rms_error_percent"], 0.2);
  EXPECT_TRUE(h.faults().empty());
}

TEST(RunHistory, KeepsTheLastRunsAndFaultsAndNamesAnUnknownRun) {
  hdd::RunHistory h({}, 3, 2);
  for (int i = 0; i < 5; ++i) {
    // Appended, not "r" + ...: GCC 12 warns falsely (-Wrestrict) on the latter.
    const std::string n = std::to_string(i);
    h.add({{"run_id", std::string("r").append(n)},
           {"kind", "track"},
           {"end", "fault"},
           {"reason", std::string("sensor stuck ").append(n)}});
  }
  const json runs = h.runs()["runs"];
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_EQ(runs[0]["run_id"], "r4");
  EXPECT_EQ(runs[2]["run_id"], "r2");
  const json faults = h.faults();
  ASSERT_EQ(faults.size(), 2u);
  EXPECT_EQ(faults[0]["run_id"], "r4");
  EXPECT_EQ(faults[0]["reason"], "sensor stuck 4");
  EXPECT_EQ(faults[0]["kind"], "track");
  try {
    h.run("r0");
    ADD_FAILURE() << "a run that left the history was found";
  } catch (const hystbench::common::CommandError& e) {
    EXPECT_EQ(e.code(), "unknown_run");
    EXPECT_NE(std::string(e.what()).find("3 are"), std::string::npos);
  }
}

class RunHistoryFolder : public hystbench::test::TempDirTest {
 protected:
  RunHistoryFolder() : TempDirTest("run_history") {}
};

TEST_F(RunHistoryFolder, TheListOutlivesARestartAndSkipsWhatIsNotAResult) {
  {
    hdd::RunHistory h(dir_, 2, 5);
    h.add({{"run_id", "20260101T000000Z-track-1"},
           {"kind", "track"},
           {"end", "completed"},
           {"rms_error_percent", 0.5}});
    h.add({{"run_id", "20260101T000001Z-track-2"},
           {"kind", "track"},
           {"end", "fault"},
           {"reason", "sensor stuck"}});
    h.add({{"run_id", "20260101T000002Z-excite-3"}, {"kind", "excite"}, {"end", "completed"}});
  }
  std::ofstream(dir_ / "20260101T000003Z-track-4.result.json") << "{ not json";
  const hdd::RunHistory again(dir_, 2, 5);  // the daemon started again
  const json runs = again.runs()["runs"];
  ASSERT_EQ(runs.size(), 2u);  // the newest two of the three kept, the broken file skipped
  EXPECT_EQ(runs[0]["run_id"], "20260101T000002Z-excite-3");
  EXPECT_EQ(runs[1]["run_id"], "20260101T000001Z-track-2");
  EXPECT_EQ(again.run("20260101T000001Z-track-2")["reason"], "sensor stuck");
  ASSERT_EQ(again.faults().size(), 1u);
  EXPECT_EQ(again.faults()[0]["reason"], "sensor stuck");
  EXPECT_EQ(runs[1]["finished"].get<std::string>().size(), 20u);
}

TEST(RunHistory, IdentifysOwnModelErrorIsNotItsFigureButAnExcitesIsWhereAModelPredicted) {
  hdd::RunHistory h;
  h.add(
      {{"run_id", "i"}, {"kind", "identify"}, {"end", "fault"}, {"model_rms_error_percent", 5.0}});
  h.add({{"run_id", "line"},
         {"kind", "excite"},
         {"end", "completed"},
         {"y_model_from", "limits"},
         {"model_rms_error_percent", 4.2}});
  h.add({{"run_id", "e"},
         {"kind", "excite"},
         {"end", "completed"},
         {"y_model_from", "model"},
         {"model_rms_error_percent", 0.7}});
  const json runs = h.runs()["runs"];
  EXPECT_EQ(runs[0]["rms_error_percent"], 0.7);         // the model's error on the excitation
  EXPECT_TRUE(runs[1]["rms_error_percent"].is_null());  // the straight line's: measures nothing
  EXPECT_TRUE(runs[2]["rms_error_percent"].is_null());  // a model before it, or none: not its own
}
