#pragma once
// The active model in the state the actuator's history leaves it: the model stepped through
// the output of every tick the loop kept (OutputHistory). Replayed from the history's oldest
// tick when the model changes, stepped on over the ticks since otherwise; ticks the history
// lost meanwhile are taken as its oldest kept output, held (ActuatorModel::hold). What a run's
// predictor and inverse start from (RunContext::model_state). Not real-time safe: a replay
// steps up to the history's capacity (2^21 ticks by default); callers serialise (the bench's
// mutex).
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/daemon/loop/output_history.hpp"

namespace hystbench::daemon::details {

class ModelStateTracker {
 public:
  /// `history` must outlive the tracker; dt_s is the loop's period [s].
  ModelStateTracker(const OutputHistory& history, double dt_s) : history_(history), dt_(dt_s) {}

  struct State {
    std::shared_ptr<const compensation::ActuatorModel> model;  ///< null: nothing played yet
    std::uint64_t tick = 0;  ///< the history's tick the state is at (its next)
    double history_s = 0.0;  ///< the output history it was stepped through [s]
  };
  /// `active` (its file's model, `generation` the bench's count of model changes) as the
  /// history leaves it now, configured at the loop's period.
  State state(const compensation::ActuatorModel& active, std::uint64_t generation);

 private:
  const OutputHistory& history_;
  double dt_;
  std::optional<compensation::ActuatorModel> model_;  // stepped through ticks [.., tick_)
  std::uint64_t generation_ = 0;
  std::uint64_t tick_ = 0;
  std::uint64_t replayed_from_ = 0;  // the tick model_ was relaxed at
  std::vector<double> outputs_;      // the ticks copied last
};

}  // namespace hystbench::daemon::details
