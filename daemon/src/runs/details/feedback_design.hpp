#pragma once
// The feedback of a run that has one (`inverse+pid`, `pid`) and of `tune`: designed on the
// stage's measured frequency responses (the active model's, else the bench's last `frf`) as the
// loop sees them through the feedforward (compensation's feedback_plant.hpp, loop_design.hpp),
// or the gains given by hand ([pid], the request) checked on them the same way and refused,
// naming their margins, unless forced. A rate-dependent model whose rate lowers the output while
// the stage moves puts a right-half-plane zero on the drive at g / K_r (K_r that part's output
// change per unit rate), which the responses, measured around resting operating points, do not
// show: the loop must stay stable with it on every response. The loop's output corrects the
// feedforward's target: hand gains [V/µm ...] are taken at the drive's mean slope (the linear map's
// gain). A design is kept for the model, the compensator and the gains it was made for (another
// sweep run reuses it). Errors are CommandError: no_frequency_response, stale_frequency_response,
// unsafe_gains, bad_params. Not real-time safe.
#include <cstdint>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hystbench/compensation/compensator.hpp"
#include "hystbench/compensation/iterative_learning.hpp"
#include "hystbench/compensation/loop_design.hpp"
#include "hystbench/daemon/loop/oscillation_detector.hpp"

namespace hystbench::daemon::details {

struct RunContext;

/// PID gains a request names [V/µm, V/(µm s), V s/µm]; each absent one is the configured gain,
/// and with none given anywhere the loop is designed. `force` runs hand gains that break the
/// loop's targets on the measured responses (refused otherwise).
struct FeedbackGainsRequest {
  std::optional<double> kp, ki, kd;
  bool force = false;
  /// The correction through the linear map whatever the model: a stage's learning run, whose
  /// loops through each axis's plane inverse jump where their targets cross its cells at ticks
  /// that differ from trial to trial, and ring the mode the axes share.
  bool through_linear_map = false;
  bool any() const { return kp || ki || kd; }
};

struct FeedbackPlan {
  compensation::FeedbackLaw law;
  /// Where its correction enters: through the model's inverse, or (`pid`, no model, a rate law
  /// whose inverse is solved at the drive's own rate) through the linear map.
  compensation::FeedbackPath path = compensation::FeedbackPath::kInverse;
  compensation::LoopEvaluation evaluation;
  /// The responses the loop sees (measured, through the feedforward), for plots.
  std::vector<compensation::MeasuredResponse> plants;
  nlohmann::json summary;  ///< the result's and status' `feedback`
};

/// The last plans and what they were made for (a sweep alternates compensators). Any thread.
struct FeedbackPlanCache {
  static constexpr std::size_t kPlans = 8;
  std::mutex mutex;
  std::vector<std::pair<std::string, FeedbackPlan>> plans;  ///< newest last
};

/// The feedback of `kind` (a feedback kind) on the bench of `ctx`.
FeedbackPlan plan_feedback(const RunContext& ctx, compensation::CompensatorKind kind,
                           const FeedbackGainsRequest& gains);

/// `law` with its loop gain times `factor`: the PID's kp, ki and kd scaled, its boost and
/// shaping as they are (how lowered_plan() lowers a loop, and how its check together is tried).
compensation::FeedbackLaw with_loop_gain(compensation::FeedbackLaw law, double factor);

/// `plan` (plan_feedback()'s for the same inputs) with its loop's gain times `factor` in
/// (0, 1]: its PID's gains scaled, its margins checked again on its responses; its summary's
/// `lowered` gives the factor and `why` (whose "meaning" its `limit` quotes; `limited_by`
/// "coupling"). Kept in ctx's cache in place of `plan`, so that
/// plan_feedback() returns it for the same inputs.
FeedbackPlan lowered_plan(const RunContext& ctx, compensation::CompensatorKind kind,
                          const FeedbackGainsRequest& gains, const FeedbackPlan& plan,
                          double factor, const nlohmann::json& why);

/// The loop on each response the plan saw, for plots: frequency, |L|, arg L [deg], |S|, |T|,
/// and its margins' marks.
nlohmann::json loop_curves(const FeedbackPlan& plan, double dt_s);

/// |S| of the plan's loop at frequency_hz [Hz], the largest over the responses whose lines
/// reach it (linear between lines); NaN where none does.
double sensitivity_at(const FeedbackPlan& plan, double frequency_hz, double dt_s);

/// The plan's law with resonators at the harmonics of a periodic reference whose fundamental is
/// fundamental_hz [Hz] where its loop alone leaves more than half of them
/// (harmonic_resonator_design.hpp), for a designed loop (gains by hand run as given); `feedback`
/// (the run's summary) gets `harmonics`: those kept and why the others were left out.
compensation::FeedbackLaw with_reference_harmonics(const RunContext& ctx, const FeedbackPlan& plan,
                                                   double fundamental_hz, nlohmann::json& feedback);

/// The oscillation supervisor of a run with `feedback` (its summary): the error watched around
/// the loop's weakest frequency (the largest peak of |S| over the measured responses), against
/// the reference's span [µm].
OscillationOptions oscillation_options(const nlohmann::json& feedback, double span_um,
                                       double rate_hz);

/// The lowest mode the stage's measured responses show [Hz]; 0 without responses or modes.
double first_mode_hz(const RunContext& ctx);

/// How long the stage rings after a start from rest: five time constants 1 / (zeta w) of the
/// slowest mode its measured responses show [s]; 0 without responses or modes.
double ringing_time_s(const RunContext& ctx);

/// What a learning run's drive change meets, over the model's local slope (the learner's): the
/// stage's responses through the active model (else the linear map), times the sensitivity of
/// `feedback`'s loop where one runs beside it, averaged over the responses. nullopt where the
/// bench holds no measured response (or one of another loop rate).
std::optional<compensation::MeasuredLearningPlant> learning_plant(const RunContext& ctx,
                                                                  const FeedbackPlan* feedback);

}  // namespace hystbench::daemon::details
