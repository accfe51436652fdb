#include "runs/details/stage_loops_together.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "hystbench/common/command_error.hpp"
#include "hystbench/compensation/loop_analysis.hpp"
#include "hystbench/compensation/number_text.hpp"
#include "hystbench/compensation/stage_interaction.hpp"

namespace hystbench::daemon::details {

using common::CommandError;
using nlohmann::json;
namespace hc = hystbench::compensation;

namespace {

// The check of the axes' loops together (compensation/stage_interaction.hpp): the worst over
// the responses every axis measured alike, each loop's gain times `factor`; nullopt without a
// loop on every axis, or without cross responses.
struct Interaction {
  hc::StageInteraction worst;
  std::string on;  ///< the response it was worst on
};

std::optional<Interaction> worst_interaction(
    const StageModel* stage, const std::vector<std::shared_ptr<const FeedbackPlan>>& plans,
    double factor, double dt) {
  const std::size_t n = plans.size();
  if (stage == nullptr || stage->cross.size() != n || n < 2) return std::nullopt;
  std::size_t responses = std::numeric_limits<std::size_t>::max();
  for (std::size_t i = 0; i < n; ++i) {
    if (!plans[i] || !stage->models[i].responses) return std::nullopt;
    responses = std::min(
        {responses, stage->models[i].responses->responses.size(), plans[i]->plants.size()});
    for (std::size_t j = 0; j < n; ++j) {
      if (i != j) responses = std::min(responses, stage->cross[i][j].responses.size());
    }
  }
  if (responses == 0 || responses == std::numeric_limits<std::size_t>::max()) return std::nullopt;
  std::vector<hc::FeedbackController> controllers;
  controllers.reserve(n);
  for (const auto& plan : plans) controllers.emplace_back(with_loop_gain(plan->law, factor), dt);
  std::optional<Interaction> out;
  for (std::size_t k = 0; k < responses; ++k) {
    std::vector<std::vector<hc::MeasuredResponse>> g(n, std::vector<hc::MeasuredResponse>(n));
    std::vector<std::vector<std::complex<double>>> loops;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < n; ++j) {
        g[i][j] =
            i == j ? stage->models[i].responses->responses[k] : stage->cross[i][j].responses[k];
      }
      loops.push_back(hc::loop_response(plans[i]->plants[k], controllers[i], dt));
    }
    try {
      hc::StageInteraction s = hc::stage_interaction(g, loops);
      if (!out || s.peak > out->worst.peak) {
        out = Interaction{std::move(s), stage->models[0].responses->responses[k].label};
      }
    } catch (const std::invalid_argument&) {
      // The axes' responses do not share lines at this operating point: not comparable.
    }
  }
  return out;
}

// The largest the check may reach for the loops to run as designed: below 1 they are stable
// together; 0.7 leaves what the cross responses' estimates and each loop's own gain
// uncertainty (the design's +/-30 %: 1 / 1.3) may take.
constexpr double kInteractionLimit = 0.7;

}  // namespace

json design_loops_together(hc::CompensatorKind kind, const FeedbackGainsRequest& gains,
                           std::vector<RunContext>& contexts, const StageModel* stage, double dt) {
  if (!hc::uses_feedback(kind) || stage == nullptr || contexts.size() < 2 ||
      stage->cross.size() != contexts.size()) {
    return nullptr;
  }
  std::vector<std::shared_ptr<const FeedbackPlan>> plans;
  for (RunContext& c : contexts) {
    c.feedback_plans = std::make_shared<FeedbackPlanCache>();
    plans.push_back(std::make_shared<const FeedbackPlan>(plan_feedback(c, kind, gains)));
  }
  const std::optional<Interaction> alone = worst_interaction(stage, plans, 1.0, dt);
  if (!alone) return nullptr;
  json out = {{"peak_alone", alone->worst.peak},
              {"peak_alone_hz", alone->worst.peak_hz},
              {"limit", kInteractionLimit}};
  if (alone->worst.peak <= kInteractionLimit) {
    out["lowered_by"] = 1.0;
    return out;
  }
  if (plans.front()->summary.value("gains", "") != "designed") {
    out["lowered_by"] = 1.0;
    out["as_given"] = "gains given by hand run as given: the check above says what they risk";
    return out;
  }
  double low = 0.0, high = 1.0;
  for (int i = 0; i < 20; ++i) {
    const double mid = 0.5 * (low + high);
    const std::optional<Interaction> at = worst_interaction(stage, plans, mid, dt);
    (at && at->worst.peak <= kInteractionLimit ? low : high) = mid;
  }
  if (low < 0.02) {
    throw CommandError("no_design",
                       "the axes' loops checked together through the coupling stay "
                       "above " +
                           std::to_string(kInteractionLimit) +
                           " down to a fiftieth of their gain: the coupling is too "
                           "strong for a loop per axis");
  }
  const std::string meaning =
      "the axes' loops designed alone reach " + hc::significant(alone->worst.peak, 3) +
      " together through the coupling (at " + hc::significant(alone->worst.peak_hz, 4) +
      " Hz); every loop is lowered by one factor until they stay under " +
      hc::significant(kInteractionLimit, 4);
  const json why = {
      {"peak_alone", alone->worst.peak}, {"limit", kInteractionLimit}, {"meaning", meaning}};
  for (std::size_t a = 0; a < contexts.size(); ++a) {
    lowered_plan(contexts[a], kind, gains, *plans[a], low, why);
  }
  out["lowered_by"] = low;
  return out;
}

json feedback_interaction(const StageModel* stage,
                          const std::vector<std::shared_ptr<const FeedbackPlan>>& plans,
                          double dt) {
  const std::optional<Interaction> worst = worst_interaction(stage, plans, 1.0, dt);
  if (!worst) return nullptr;
  return {{"peak", worst->worst.peak},
          {"peak_hz", worst->worst.peak_hz},
          {"on", worst->on},
          {"dominant", worst->worst.dominant()},
          {"meaning",
           "the largest spectral radius of E T over the measured lines (E: each cross response "
           "over the driven axis's own, T: each axis's complementary sensitivity); below 1 the "
           "axes' loops, each stable alone, are stable together"}};
}

}  // namespace hystbench::daemon::details
