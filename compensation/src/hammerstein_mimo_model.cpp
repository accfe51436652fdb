#include "hystbench/compensation/hammerstein_mimo_model.hpp"

#include <stdexcept>
#include <string>

namespace hystbench::compensation {

HammersteinMimoModel::HammersteinMimoModel(std::vector<std::optional<PiParameters>> operators,
                                           MimoLinearModel dynamics)
    : operators_(std::move(operators)), dynamics_(std::move(dynamics)) {
  if (operators_.size() != dynamics_.inputs()) {
    throw std::invalid_argument("Hammerstein model: " + std::to_string(operators_.size()) +
                                " input operators for dynamics of " +
                                std::to_string(dynamics_.inputs()) + " inputs");
  }
  for (const auto& op : operators_) {
    if (op) PiModel check(*op);  // throws naming the bad field
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
    PiModel op(*operators_[j]);
    const auto row = static_cast<Eigen::Index>(j);
    op.reset(u(row, 0));
    for (Eigen::Index t = 0; t < u.cols(); ++t) v(row, t) = op.step(u(row, t));
  }
  return v;
}

Eigen::MatrixXd HammersteinMimoModel::simulate(const Eigen::MatrixXd& u) const {
  return dynamics_.simulate(operator_outputs(u));
}

}  // namespace hystbench::compensation
