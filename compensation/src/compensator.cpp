#include "hystbench/compensation/compensator.hpp"

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
                         std::optional<PidController> pid, LinearMap linear)
    : kind_(kind), inverse_(std::move(inverse)), pid_(std::move(pid)), linear_(linear) {
  details::require(!needs_model(kind_) || inverse_ != nullptr,
                   std::string("compensator '") + std::string(to_string(kind_)) +
                       "' needs a model (identify or load one first)");
  details::require(
      !uses_feedback(kind_) || pid_.has_value(),
      std::string("compensator '") + std::string(to_string(kind_)) + "' needs PID gains");
  details::require(std::isfinite(linear_.gain) && linear_.gain > 0.0,
                   "linear map gain must be > 0");
}

Compensator::Compensator(const Compensator& other)
    : kind_(other.kind_),
      inverse_(other.inverse_ ? other.inverse_->clone() : nullptr),
      pid_(other.pid_),
      linear_(other.linear_),
      y_ref_prev_(other.y_ref_prev_),
      have_prev_(other.have_prev_) {}

CompensatorOutput Compensator::step(double y_ref, double y_measured,
                                    std::span<const double> ff_targets) noexcept {
  CompensatorOutput out;
  switch (kind_) {
    case CompensatorKind::kNone:
    case CompensatorKind::kPid:
      out.u_ff = (ff_targets.front() - linear_.offset) / linear_.gain;
      break;
    case CompensatorKind::kInverse:
    case CompensatorKind::kInverseMultiplicative:
    case CompensatorKind::kInversePid:
      out.u_ff = ff_targets.size() > 1 ? inverse_->step_previewed(ff_targets)
                                       : inverse_->step(ff_targets.front());
      break;
  }
  if (pid_ && uses_feedback(kind_)) {
    out.u_fb = (have_prev_ && std::isfinite(y_measured)) ? pid_->step(y_ref_prev_ - y_measured)
                                                         : pid_->output();
  }
  y_ref_prev_ = y_ref;
  have_prev_ = true;
  out.feedback_saturated = pid_ && pid_->saturated();
  out.u = out.u_ff + out.u_fb;
  return out;
}

void Compensator::notify_saturation(int direction) noexcept {
  if (pid_) pid_->set_saturation(direction);
}

void Compensator::reset(double u0) noexcept {
  if (inverse_) inverse_->reset(u0);
  if (pid_) pid_->reset(0.0);  // added to a feedforward: it starts at 0
  have_prev_ = false;
}

}  // namespace hystbench::compensation
