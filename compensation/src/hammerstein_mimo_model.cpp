#include "hystbench/compensation/hammerstein_mimo_model.hpp"

#include <memory>
#include <stdexcept>
#include <string>

namespace hystbench::compensation {

ActuatorModel classical_pi_operator(PiParameters p) {
  return ActuatorModel(std::make_unique<PiModel>(std::move(p)));
}

HammersteinMimoModel::HammersteinMimoModel(std::vector<std::optional<ActuatorModel>> operators,
                                           MimoLinearModel dynamics, double dt_s)
    : operators_(std::move(operators)), dynamics_(std::move(dynamics)), dt_s_(dt_s) {
  if (operators_.size() != dynamics_.inputs()) {
    throw std::invalid_argument("Hammerstein model: " + std::to_string(operators_.size()) +
                                " input operators for dynamics of " +
                                std::to_string(dynamics_.inputs()) + " inputs");
  }
  if (!(dt_s_ > 0.0)) throw std::invalid_argument("Hammerstein model: a sample period > 0");
  for (const auto& op : operators_) {
    if (op && !op->valid()) {
      throw std::invalid_argument("Hammerstein model: an operator without a hysteresis model");
    }
  }
}

bool HammersteinMimoModel::has_hysteresis() const noexcept {
  for (const auto& op : operators_) {
    if (op) return true;
  }
  return false;
}

Eigen::MatrixXd HammersteinMimoModel::operator_outputs(const Eigen::MatrixXd& u) const {
  if (static_cast<std::size_t>(u.rows()) != inputs()) {
    throw std::invalid_argument("Hammerstein model: " + std::to_string(u.rows()) +
                                " input rows for a model of " + std::to_string(inputs()));
  }
  Eigen::MatrixXd v = u;
  for (std::size_t j = 0; j < operators_.size(); ++j) {
    if (!operators_[j] || u.cols() == 0) continue;
    ActuatorModel op = *operators_[j];
    const auto row = static_cast<Eigen::Index>(j);
    const Eigen::VectorXd in = u.row(row).transpose();
    const std::vector<double> out =
        op.simulate(std::span<const double>(in.data(), static_cast<std::size_t>(in.size())), dt_s_);
    for (Eigen::Index t = 0; t < u.cols(); ++t) v(row, t) = out[static_cast<std::size_t>(t)];
  }
  return v;
}

Eigen::MatrixXd HammersteinMimoModel::simulate(const Eigen::MatrixXd& u) const {
  return dynamics_.simulate(operator_outputs(u));
}

}  // namespace hystbench::compensation
