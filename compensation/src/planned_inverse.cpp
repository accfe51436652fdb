#include "hystbench/compensation/planned_inverse.hpp"

#include <algorithm>
#include <cmath>

#include "details/validate.hpp"

namespace hystbench::compensation {

PlannedInverse::PlannedInverse(std::vector<double> targets, DrivePlan plan)
    : targets_(std::move(targets)), plan_(std::move(plan)) {
  details::require(!plan_.u.empty(), "planned inverse: the plan is empty");
  details::require(targets_.size() == plan_.u.size() && plan_.gain.size() == plan_.u.size(),
                   "planned inverse: targets, drive and gain differ in length");
}

double PlannedInverse::step(double y_ref) noexcept {
  const std::size_t k = std::min(next_, plan_.u.size() - 1);
  if (next_ < plan_.u.size()) ++next_;
  const double correction = (y_ref - targets_[k]) / plan_.gain[k];
  return plan_.u[k] + (std::isfinite(correction) ? correction : 0.0);
}

void PlannedInverse::reset(double /*u0*/) noexcept { next_ = 0; }

std::unique_ptr<InverseModel> PlannedInverse::clone() const {
  return std::make_unique<PlannedInverse>(*this);
}

}  // namespace hystbench::compensation
