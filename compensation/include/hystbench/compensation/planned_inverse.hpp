#pragma once
// The feedforward of a run whose targets are known before it starts: plays a DrivePlan sample
// by sample. A target that differs from the planned one (the run's tare, a clipped reference)
// is met to first order through the plan's gain: u = u_plan + (y_ref - target_plan) / gain.
// After the plan's last sample it holds that sample (with the same correction).
// step() is real-time safe: it indexes the plan.
#include <memory>
#include <vector>

#include "hystbench/compensation/drive_planner.hpp"
#include "hystbench/compensation/inverse_model.hpp"

namespace hystbench::compensation {

class PlannedInverse final : public InverseModel {
 public:
  /// `targets` are the static targets the plan was made for (same length as plan.u); throws
  /// std::invalid_argument on an empty plan or mismatched lengths.
  PlannedInverse(std::vector<double> targets, DrivePlan plan);
  double step(double y_ref) noexcept override;
  /// Back to the plan's first sample (the plan itself starts from the state it was made for).
  void reset(double u0) noexcept override;
  std::unique_ptr<InverseModel> clone() const override;

  const DrivePlan& plan() const noexcept { return plan_; }

 private:
  std::vector<double> targets_;
  DrivePlan plan_;
  std::size_t next_ = 0;
};

}  // namespace hystbench::compensation
