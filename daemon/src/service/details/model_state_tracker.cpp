#include "service/details/model_state_tracker.hpp"

namespace hystbench::daemon::details {

ModelStateTracker::State ModelStateTracker::state(const compensation::ActuatorModel& active,
                                                  std::uint64_t generation) {
  const bool same = model_.has_value() && generation_ == generation;
  const std::uint64_t first = history_.copy_since(same ? tick_ : 0, outputs_);
  if (!same) {
    if (outputs_.empty()) return {};
    model_ = active;
    model_->configure(dt_);
    model_->reset(outputs_.front());
    generation_ = generation;
    replayed_from_ = first;
  } else if (first > tick_) {
    // The history lost the ticks between: held at the oldest output it kept.
    model_->hold(outputs_.empty() ? model_->last_input() : outputs_.front(), first - tick_);
  }
  for (const double u : outputs_) (void)model_->step(u);
  tick_ = first + outputs_.size();
  return {std::make_shared<const compensation::ActuatorModel>(*model_), tick_,
          static_cast<double>(tick_ - replayed_from_) * dt_};
}

}  // namespace hystbench::daemon::details
