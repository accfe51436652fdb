#include "hystbench/compensation/compensator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "details/validate.hpp"

namespace hystbench::compensation {

namespace {
constexpr std::array<std::pair<CompensatorKind, std::string_view>, 5> kNames{{
    {CompensatorKind::kNone, "none"},
    {CompensatorKind::kInverse, "inverse"},
    {CompensatorKind::kInverseMultiplicative, "inverse_multiplicative"},
    {CompensatorKind::kInversePid, "inverse+pid"},
    {CompensatorKind::kPid, "pid"},
}};
}  // namespace

std::string_view to_string(CompensatorKind kind) noexcept {
  for (const auto& [k, n] : kNames) {
    if (k == kind) return n;
  }
  return "unknown";
}

std::optional<CompensatorKind> compensator_kind_from_string(std::string_view name) noexcept {
  for (const auto& [k, n] : kNames) {
    if (n == name) return k;
  }
  return std::nullopt;
}

bool needs_model(CompensatorKind kind) noexcept {
  return kind == CompensatorKind::kInverse || kind == CompensatorKind::kInverseMultiplicative ||
         kind == CompensatorKind::kInversePid;
}

bool uses_feedback(CompensatorKind kind) noexcept {
  return kind == CompensatorKind::kInversePid || kind == CompensatorKind::kPid;
}

Compensator::Compensator(CompensatorKind kind, std::unique_ptr<InverseModel> inverse,
                         std::optional<FeedbackController> feedback, LinearMap linear,
                         FeedbackPath path)
    : kind_(kind),
      inverse_(std::move(inverse)),
      feedback_(std::move(feedback)),
      linear_(linear),
      path_(inverse_ ? path : FeedbackPath::kLinearMap) {
  details::require(!needs_model(kind_) || inverse_ != nullptr,
                   std::string("compensator '") + std::string(to_string(kind_)) +
                       "' needs a model (identify or load one first)");
  details::require(
      !uses_feedback(kind_) || feedback_.has_value(),
      std::string("compensator '") + std::string(to_string(kind_)) + "' needs a feedback law");
  details::require(std::isfinite(linear_.gain) && linear_.gain > 0.0,
                   "linear map gain must be > 0");
  if (!uses_feedback(kind_)) feedback_.reset();
  if (feedback_ && inverse_ && path_ == FeedbackPath::kInverse) feedforward_ = inverse_->clone();
  shifted_.assign(std::max<std::size_t>(1, preview_samples()), 0.0);
}

Compensator::Compensator(const Compensator& other)
    : kind_(other.kind_),
      inverse_(other.inverse_ ? other.inverse_->clone() : nullptr),
      feedforward_(other.feedforward_ ? other.feedforward_->clone() : nullptr),
      feedback_(other.feedback_),
      linear_(other.linear_),
      path_(other.path_),
      shifted_(other.shifted_),
      drive_min_(other.drive_min_),
      drive_max_(other.drive_max_),
      at_bound_(other.at_bound_),
      y_ref_prev_(other.y_ref_prev_),
      have_prev_(other.have_prev_) {}

CompensatorOutput Compensator::step(double y_ref, double y_measured,
                                    std::span<const double> ff_targets) noexcept {
  CompensatorOutput out;
  if (!feedback_) {
    out.u_ff = inverse_ ? inverse_drive(*inverse_, ff_targets) : linear_drive(ff_targets.front());
    out.u = out.u_ff;
    return out;
  }
  const bool fresh = have_prev_ && std::isfinite(y_measured) && std::isfinite(y_ref_prev_);
  out.v = fresh ? feedback_->step(y_ref_prev_ - y_measured) : feedback_->output();
  y_ref_prev_ = y_ref;
  have_prev_ = true;
  const std::size_t n = std::min(ff_targets.size(), shifted_.size());
  for (std::size_t j = 0; j < n; ++j) shifted_[j] = ff_targets[j] + out.v;
  const std::span<const double> targets(shifted_.data(), n);
  if (path_ == FeedbackPath::kInverse) {
    out.u_ff = inverse_drive(*feedforward_, ff_targets.first(n));
    out.u = inverse_drive(*inverse_, targets);
  } else {
    out.u_ff = inverse_ ? inverse_drive(*inverse_, ff_targets) : linear_drive(ff_targets.front());
    out.u = out.u_ff + out.v / linear_.gain;
  }
  out.u_fb = out.u - out.u_ff;
  // The drive at a bound of its range, or a later stage clamping it: v's integral holds.
  at_bound_ = out.u >= drive_max_ ? 1 : out.u <= drive_min_ ? -1 : 0;
  feedback_->set_saturation(at_bound_);
  out.feedback_saturated = feedback_->saturated();
  return out;
}

void Compensator::notify_saturation(int direction) noexcept {
  if (feedback_) feedback_->set_saturation(direction != 0 ? direction : at_bound_);
}

void Compensator::reset(double u0) noexcept {
  if (inverse_) inverse_->reset(u0);
  if (feedforward_) feedforward_->reset(u0);
  if (feedback_) feedback_->reset();  // added to the target: it starts at 0
  at_bound_ = 0;
  have_prev_ = false;
}

}  // namespace hystbench::compensation
