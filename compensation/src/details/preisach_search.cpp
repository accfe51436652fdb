#include "details/preisach_search.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "details/constrained_lsq.hpp"
#include "details/preisach_smoothness.hpp"
#include "details/validate.hpp"

namespace hystbench::compensation::details {

namespace {

// The base with m output dead zones per side over the scored output's range, about its middle.
ModelStructure with_output_map(ModelStructure s, std::span<const double> y, std::size_t begin,
                               std::size_t end, std::size_t m) {
  s.dead_zone_thresholds = {0.0};
  s.center = 0.0;
  if (m == 0) return s;
  const auto [lo, hi] = std::minmax_element(y.begin() + static_cast<std::ptrdiff_t>(begin),
                                            y.begin() + static_cast<std::ptrdiff_t>(end));
  require(*hi > *lo, "preisach fit: the output does not move");
  s.center = 0.5 * (*lo + *hi);
  s.dead_zone_thresholds = uniform_dead_zone_thresholds(m, s.center - *lo, *hi - s.center);
  return s;
}

double rms_over(const Design& design, const Eigen::VectorXd& x, std::span<const double> u,
                std::span<const double> y, std::size_t from, std::size_t to) {
  ActuatorModel model = design.build(x);
  std::vector<double> yhat = model.simulate(u.first(to), design.structure().dt);
  if (design.structure().drift) add_drift(design.structure(), x[design.drift_column()], yhat);
  double sum = 0.0;
  for (std::size_t k = from; k < to; ++k) sum += (yhat[k] - y[k]) * (yhat[k] - y[k]);
  return std::sqrt(sum / static_cast<double>(to - from));
}

// One output map: its smoothness weight chosen on [split, end), then fitted on [begin, end).
PreisachSearch search_one_map(const ModelStructure& s, std::span<const double> u,
                              std::span<const double> y, std::size_t begin, std::size_t split,
                              std::size_t end, std::span<const double> smoothness) {
  Design design(s);
  // One pass: the first part's equations and the rest's.
  NormalEquations first(design.unknowns()), rest(design.unknowns());
  design.reset(u[0]);
  for (std::size_t k = 0; k < end; ++k) {
    if (k < begin) {
      design.skip(u[k]);
      continue;
    }
    NormalEquations& ne = k < split ? first : rest;
    ne.push(design.row(u[k], y[k], ne.row()));
  }
  const Eigen::VectorXd lower = design.lower_bounds(), upper = design.upper_bounds();
  const Eigen::MatrixXd& g_first = first.gram();
  const auto cells = static_cast<Eigen::Index>(PreisachModel::cell_count(s.preisach_cells));
  const double first_scale = g_first.diagonal().head(cells).mean();
  auto solve = [&](const Eigen::MatrixXd& g, const Eigen::VectorXd& b, double weight) {
    // The penalty as the first part's columns set it, for the whole record's fit too.
    Eigen::MatrixXd penalised = g;
    add_preisach_smoothness(penalised, s.preisach_cells, 0,
                            weight * first_scale / g.diagonal().head(cells).mean());
    return solve_bounded_lsq(penalised, b, lower, upper).x;
  };
  PreisachSearch out;
  out.structure = s;
  out.heldout_rms = std::numeric_limits<double>::infinity();
  for (const double weight : smoothness) {
    const double rms = rms_over(design, solve(g_first, first.rhs(), weight), u, y, split, end);
    out.tried_rms.push_back(rms);
    if (rms < out.heldout_rms) {
      out.heldout_rms = rms;
      out.structure.smoothness = weight;
    }
  }
  out.x = solve(g_first + rest.gram(), first.rhs() + rest.rhs(), out.structure.smoothness);
  return out;
}

}  // namespace

PreisachSearch search_preisach(const ModelStructure& base, std::span<const double> u,
                               std::span<const double> y, std::size_t begin, std::size_t split,
                               std::size_t end, std::span<const double> smoothness,
                               std::span<const std::size_t> output_zones) {
  require(begin < split && split < end && end <= u.size() && u.size() == y.size(),
          "preisach fit: the record's parts are out of order");
  PreisachSearch best;
  for (const std::size_t m : output_zones) {
    PreisachSearch one = search_one_map(with_output_map(base, y, begin, end, m), u, y, begin, split,
                                        end, smoothness);
    if (best.tried_rms.empty() || one.heldout_rms < best.heldout_rms) best = std::move(one);
  }
  return best;
}

}  // namespace hystbench::compensation::details
