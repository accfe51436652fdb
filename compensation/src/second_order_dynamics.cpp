#include "hystbench/compensation/second_order_dynamics.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <unsupported/Eigen/MatrixFunctions>

#include "details/validate.hpp"

namespace hystbench::compensation {

SecondOrderDynamics::SecondOrderDynamics(DynamicsParameters p, double dt_s) : p_(p) {
  details::require(std::isfinite(p_.natural_frequency_hz) && p_.natural_frequency_hz > 0.0,
                   "dynamics.natural_frequency_hz must be > 0");
  details::require(std::isfinite(p_.damping_ratio) && p_.damping_ratio > 0.0,
                   "dynamics.damping_ratio must be > 0");
  details::require(std::isfinite(dt_s) && dt_s > 0.0, "sample period must be > 0");
  const double wn = 2.0 * std::numbers::pi * p_.natural_frequency_hz;
  // Augmented exponential gives Phi and the zero-order-hold input matrix in one step.
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  m(0, 1) = 1.0;
  m(1, 0) = -wn * wn;
  m(1, 1) = -2.0 * p_.damping_ratio * wn;
  m(1, 2) = wn * wn;
  const Eigen::Matrix3d e = (m * dt_s).exp();
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) phi_[i][j] = e(i, j);
    gam_[i] = e(i, 2);
  }
}

void SecondOrderDynamics::reset(double x0) noexcept {
  s_[0] = x0;
  s_[1] = 0.0;
}

}  // namespace hystbench::compensation
