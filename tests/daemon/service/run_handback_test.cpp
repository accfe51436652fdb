// The run hand-back's routing without a loop run: a run that ended before it played is delivered
// with why and no samples; a played run no component owns is delivered as it ended; an identify
// that played to its end goes to the identify coordinator with the fit request it was launched
// with, one that was stopped is delivered without a fit. The walks through each owner (identify's
// segments, frf's responses, a stage's) are held by the bench's tests (bench_test.cpp,
// bench_feedback_test.cpp, bench_stage_test.cpp).
#include "service/details/run_handback.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "service/details/feedback_designer.hpp"
#include "service/details/identify_coordinator.hpp"
#include "service/details/learning_runs.hpp"
#include "service/details/model_store.hpp"
#include "support/bench_parts_harness.hpp"

namespace hd = hystbench::daemon;
using nlohmann::json;

namespace {

struct Harness : hystbench::test::BenchPartsHarness {
  std::unique_ptr<hd::details::ModelStore> models;
  std::unique_ptr<hd::details::IdentifyCoordinator> identify;
  std::unique_ptr<hd::details::LearningRuns> learning;
  std::unique_ptr<hd::details::FeedbackDesigner> feedback;
  std::unique_ptr<hd::details::RunHandback> handback;
  std::vector<json> delivered;

  Harness() {
    settings.model_dir = (std::filesystem::temp_directory_path() / "hystbench-handback").string();
    models = std::make_unique<hd::details::ModelStore>(settings.model_dir);
    const hd::details::BenchParts parts = this->parts();
    const auto deliver = [this](json result) { delivered.push_back(std::move(result)); };
    hd::details::IdentifyCoordinator::Hooks identify_hooks;
    identify_hooks.run_context = []() -> hd::details::RunContext {
      throw std::logic_error("no run is built before a candidate fits");
    };
    identify_hooks.adopt = [](auto&&...) { return json(); };
    identify_hooks.deliver = deliver;
    identify = std::make_unique<hd::details::IdentifyCoordinator>(parts, identify_hooks);
    learning = std::make_unique<hd::details::LearningRuns>(
        parts, [](const std::string&) { return std::string(); });
    feedback = std::make_unique<hd::details::FeedbackDesigner>(
        parts, *models,
        hd::details::RunHooks{[]() -> hd::details::RunContext {
                                throw std::logic_error("the hand-back builds no run");
                              },
                              deliver});
    handback = std::make_unique<hd::details::RunHandback>(
        parts, hd::details::RunHandback::Owners{*identify, *learning, *feedback, nullptr, deliver});
  }
};

// A run as the loop hands it back: `kind`, ended `end`, with `n` samples of a still actuator.
std::unique_ptr<hd::RunProgram> ended(hd::RunKind kind, hd::RunEnd end, std::size_t n,
                                      const std::string& id) {
  auto run = std::make_unique<hd::RunProgram>();
  run->kind = kind;
  run->run_id = id;
  run->end = end;
  run->total_samples = n;
  run->records.u.assign(n, 0.0);
  run->records.y.assign(n, 0.0);
  run->records.capacity = n;
  run->records.count = n;
  return run;
}

}  // namespace

TEST(RunHandback, ARunThatEndsBeforeItPlaysIsDeliveredWithWhyAndNoSamples) {
  Harness h;
  h.handback->unplayed(ended(hd::RunKind::kTrack, hd::RunEnd::kCompleted, 0, "r-track-1"),
                       hd::RunEnd::kAborted, "stopped while its drive was planned");
  ASSERT_EQ(h.delivered.size(), 1U);
  const json& r = h.delivered.front();
  EXPECT_EQ(r["run_id"], "r-track-1");
  EXPECT_EQ(r["end"], "aborted");
  EXPECT_EQ(r["reason"], "stopped while its drive was planned");
  EXPECT_EQ(r["samples"], 0);
}

TEST(RunHandback, APlayedRunNoComponentOwnsIsDeliveredAsItEnded) {
  Harness h;
  h.handback->played(ended(hd::RunKind::kExcite, hd::RunEnd::kCompleted, 300, "r-excite-1"));
  ASSERT_EQ(h.delivered.size(), 1U);
  EXPECT_EQ(h.delivered.front()["run_id"], "r-excite-1");
  EXPECT_EQ(h.delivered.front()["end"], "completed");
  EXPECT_FALSE(h.delivered.front().contains("fit_error"));
}

TEST(RunHandback, AnIdentifyGoesToItsFitWithTheRequestItWasLaunchedWith) {
  Harness h;
  // The fit request names a family no fit knows: the coordinator's fit says so, which shows
  // that the request it got is the one launched with the run.
  json fit_request = {{"model", "no_such_family"}, {"extend", false}};
  {
    std::lock_guard lock(h.mutex);
    h.handback->expect_fit(fit_request);
  }
  std::vector<double> u(500), y(500);
  for (std::size_t k = 0; k < u.size(); ++k) u[k] = y[k] = static_cast<double>(k % 100);
  auto run = ended(hd::RunKind::kIdentify, hd::RunEnd::kCompleted, u.size(), "r-identify-1");
  run->records.u = u;
  run->records.y = y;
  h.handback->played(std::move(run));
  ASSERT_EQ(h.delivered.size(), 1U);
  const json& r = h.delivered.front();
  ASSERT_TRUE(r.contains("fit_error")) << r.dump(2);
  EXPECT_NE(r["fit_error"].get<std::string>().find("no_such_family"), std::string::npos)
      << r["fit_error"];

  // Stopped before its excitation ended: its result as it ended, no fit tried.
  h.handback->played(ended(hd::RunKind::kIdentify, hd::RunEnd::kStopped, 500, "r-identify-2"));
  ASSERT_EQ(h.delivered.size(), 2U);
  EXPECT_EQ(h.delivered.back()["end"], "stopped");
  EXPECT_FALSE(h.delivered.back().contains("fit_error")) << h.delivered.back().dump(2);
}
