#pragma once
// A Hammerstein model with several inputs and outputs: a hysteresis operator per input (a model
// of one input of any PI family, creep included; or none: the input as it is), then a MIMO
// linear dynamic block (MimoLinearModel). Units: the inputs' and outputs' as given; an
// operator's output is in its input's unit. Pure maths; simulate() allocates its result.
#include <Eigen/Dense>
#include <optional>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/mimo_linear_model.hpp"
#include "hystbench/compensation/pi_model.hpp"

namespace hystbench::compensation {

/// A classical PI model of one input as an operator (what the identification fits).
ActuatorModel classical_pi_operator(PiParameters p);

class HammersteinMimoModel {
 public:
  HammersteinMimoModel() = default;
  /// One operator slot per input of `dynamics` (nullopt: none); dt_s > 0 is the sample period
  /// the operators run at [s]. Throws std::invalid_argument on a count mismatch or an operator
  /// without a hysteresis model.
  HammersteinMimoModel(std::vector<std::optional<ActuatorModel>> operators,
                       MimoLinearModel dynamics, double dt_s);

  std::size_t inputs() const noexcept { return dynamics_.inputs(); }
  std::size_t outputs() const noexcept { return dynamics_.outputs(); }
  const std::vector<std::optional<ActuatorModel>>& operators() const noexcept { return operators_; }
  const MimoLinearModel& dynamics() const noexcept { return dynamics_; }
  double sample_period_s() const noexcept { return dt_s_; }
  bool has_hysteresis() const noexcept;

  /// The operators' outputs (m x N) for input u (m x N), each operator starting at rest at the
  /// input's first value.
  Eigen::MatrixXd operator_outputs(const Eigen::MatrixXd& u) const;
  /// Output (p x N) for input u (m x N), from rest.
  Eigen::MatrixXd simulate(const Eigen::MatrixXd& u) const;

 private:
  std::vector<std::optional<ActuatorModel>> operators_;
  MimoLinearModel dynamics_;
  double dt_s_ = 1.0;
};

}  // namespace hystbench::compensation
