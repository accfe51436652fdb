// A finished program's report without a loop or a log: what run.finished carries.
#include "runs/details/run_result.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hd = hystbench::daemon;
namespace hdd = hystbench::daemon::details;
using nlohmann::json;

TEST(RunResult, ReportsTheOutcomeCountersSummaryAndTheModelsError) {
  hd::RunProgram p;
  p.run_id = "20260101T000000Z-excite-1";
  p.kind = hd::RunKind::kExcite;
  p.total_samples = 10;
  p.done = 4;
  p.end = hd::RunEnd::kStopped;
  p.end_reason = "stopped by request";
  p.counters.clamps = 2;
  p.summary = {{"compensator", "none"}};
  p.records.y = {0.0, 5.0, 10.0, 2.0};
  p.records.count = 4;
  // rms 1 um over 4 samples, the largest (1.5 um) at sample 2
  for (const auto& [k, e] : {std::pair{0, 1.0}, {1, -0.5}, {2, -1.5}, {3, std::sqrt(0.5)}}) {
    p.model_error.add(e, k);
  }
  const hdd::RunResult r = hdd::collect_result(p, 3.25);
  EXPECT_FALSE(r.wants_fit());
  EXPECT_TRUE(r.log_path.empty());
  const json& j = r.report;
  EXPECT_EQ(j["run_id"], p.run_id);
  EXPECT_EQ(j["kind"], "excite");
  EXPECT_EQ(j["end"], "stopped");
  EXPECT_EQ(j["reason"], "stopped by request");
  EXPECT_EQ(j["samples"], 4);
  EXPECT_EQ(j["planned_samples"], 10);
  EXPECT_EQ(j["clamps"], 2);
  EXPECT_EQ(j["output_v_after"], 3.25);
  EXPECT_EQ(j["compensator"], "none");
  EXPECT_FALSE(j.contains("rms_error_um"));  // tracking figures only for track
  // Over the 0..10 um the run covered.
  EXPECT_DOUBLE_EQ(j["model_rms_error_um"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(j["model_rms_error_percent"].get<double>(), 10.0);
  EXPECT_DOUBLE_EQ(j["model_max_error_percent"].get<double>(), 15.0);
  EXPECT_EQ(j["model_max_error_index"], 2);
  // The mean apart: (1 - 0.5 - 1.5 + sqrt(0.5)) / 4.
  EXPECT_DOUBLE_EQ(j["model_mean_error_um"].get<double>(), (std::sqrt(0.5) - 1.0) / 4.0);
}

TEST(RunResult, OnlyACompletedIdentifyWithARecordWantsAFit) {
  hd::RunProgram p;
  p.kind = hd::RunKind::kIdentify;
  p.records.count = 101;
  EXPECT_TRUE(hdd::collect_result(p, 0.0).wants_fit());
  p.end = hd::RunEnd::kAborted;
  EXPECT_FALSE(hdd::collect_result(p, 0.0).wants_fit());
  p.end = hd::RunEnd::kCompleted;
  p.records.count = 100;
  EXPECT_FALSE(hdd::collect_result(p, 0.0).wants_fit());
}
