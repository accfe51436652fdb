#include "details/preisach_smoothness.hpp"

#include "hystbench/compensation/preisach_model.hpp"

namespace hystbench::compensation::details {

void add_preisach_smoothness(Eigen::MatrixXd& g, std::size_t n, Eigen::Index first, double weight) {
  if (weight == 0.0 || n == 0) return;
  const auto cells = static_cast<Eigen::Index>(PreisachModel::cell_count(n));
  const double w = weight * g.diagonal().segment(first, cells).mean();
  auto at = [first](std::size_t p, std::size_t q) {
    return first + static_cast<Eigen::Index>(PreisachModel::cell_index(p, q));
  };
  auto pair = [&g, w](Eigen::Index a, Eigen::Index b) {
    g(a, a) += w;
    g(b, b) += w;
    g(a, b) -= w;
    g(b, a) -= w;
  };
  for (std::size_t p = 0; p < n; ++p) {
    for (std::size_t q = 0; q <= p; ++q) {
      if (p + 1 < n) pair(at(p, q), at(p + 1, q));
      if (q + 1 <= p) pair(at(p, q), at(p, q + 1));
    }
  }
}

}  // namespace hystbench::compensation::details
