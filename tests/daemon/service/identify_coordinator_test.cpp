// The identify coordinator's edges that need no loop run: a record no family fits still ends
// identify with a result (fit_error named, the run's own keys kept, no model adopted), and the
// coordinator claims no run as its segment before or after. The whole walk (fit, verification,
// extension, responses) is held by the bench's tests (bench_test.cpp, bench_feedforward_test.cpp).
#include "service/details/identify_coordinator.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/bench_parts_harness.hpp"

namespace hd = hystbench::daemon;
using nlohmann::json;

namespace {

struct Harness : hystbench::test::BenchPartsHarness {
  std::vector<json> delivered;
  int adopted = 0;
  std::unique_ptr<hd::details::IdentifyCoordinator> coordinator;

  Harness() {
    hd::details::IdentifyCoordinator::Hooks hooks;
    hooks.run_context = []() -> hd::details::RunContext {
      throw std::logic_error("no run is built before a candidate fits");
    };
    hooks.adopt = [this](auto&&...) {
      ++adopted;
      return json();
    };
    hooks.deliver = [this](json result) { delivered.push_back(std::move(result)); };
    coordinator = std::make_unique<hd::details::IdentifyCoordinator>(parts(), std::move(hooks));
  }
};

// identify's excitation as the loop hands it back: `n` samples of u and y.
std::unique_ptr<hd::RunProgram> played_identify(const std::vector<double>& u,
                                                const std::vector<double>& y) {
  auto run = std::make_unique<hd::RunProgram>();
  run->kind = hd::RunKind::kIdentify;
  run->run_id = "20261205T000000Z-identify-1";
  run->records.u = u;
  run->records.y = y;
  run->records.capacity = u.size();
  run->records.count = u.size();
  return run;
}

hd::details::RunResult completed(const hd::RunProgram& run) {
  hd::details::RunResult r;
  r.kind = hd::RunKind::kIdentify;
  r.recorded = run.records.count;
  r.report = {{"run_id", run.run_id}, {"kind", "identify"}, {"end", "completed"}};
  return r;
}

}  // namespace

TEST(IdentifyCoordinator, ARecordNoFamilyFitsEndsIdentifyWithItsResultAndTheFitError) {
  Harness h;
  // The actuator never moved: no hysteresis to fit.
  const std::vector<double> still(500, 0.0);
  const auto run = played_identify(still, still);
  EXPECT_FALSE(h.coordinator->owns(*run));
  // The fit request identify's builder makes from the daemon's defaults.
  const json fit_request = {{"model", h.settings.identify.model},
                            {"operators", h.settings.identify.operators},
                            {"dead_zones", h.settings.identify.dead_zones},
                            {"extend", true},
                            {"family_fixed", false},
                            {"skip_samples", 0},
                            {"precondition_s", 0.0},
                            {"settle_s", 0.0}};
  h.coordinator->excitation_played(*run, completed(*run), fit_request);
  ASSERT_EQ(h.delivered.size(), 1U);
  const json& result = h.delivered.front();
  ASSERT_TRUE(result.contains("fit_error"));
  // The cause named: the input never moved.
  EXPECT_NE(result["fit_error"].get<std::string>().find("constant"), std::string::npos)
      << result["fit_error"];
  EXPECT_EQ(result["run_id"], run->run_id);
  EXPECT_EQ(result["end"], "completed");
  EXPECT_EQ(h.adopted, 0);
  // No session is left behind: a later run of the same id is not taken for a segment.
  EXPECT_FALSE(h.coordinator->owns(*run));
}
