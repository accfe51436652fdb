#pragma once
// Forward-difference Jacobian for Eigen's Levenberg-Marquardt functors (internals): column i is
// (f(p + step e_i) - f(p)) / step. Allocates two residual vectors.
#include <Eigen/Core>

namespace hystbench::compensation::details {

template <class Functor>
void forward_difference_jacobian(const Functor& f, const Eigen::VectorXd& p, Eigen::MatrixXd& jac,
                                 double step) {
  Eigen::VectorXd f0(f.values()), f1(f.values());
  f(p, f0);
  Eigen::VectorXd q = p;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    q[i] = p[i] + step;
    f(q, f1);
    jac.col(i) = (f1 - f0) / step;
    q[i] = p[i];
  }
}

}  // namespace hystbench::compensation::details
