// The runs since start (service/details/run_history.hpp): summaries newest first with the figure
// a list shows, each result whole, the faults among them, all bounded.
#include "service/details/run_history.hpp"

#include <gtest/gtest.h>

#include "hystbench/common/command_error.hpp"

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
  hdd::RunHistory h(3, 2);
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
    EXPECT_NE(std::string(e.what()).find("3 kept"), std::string::npos);
  }
}
