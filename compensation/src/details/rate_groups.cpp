#include "details/rate_groups.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace hystbench::compensation::details {

namespace {

struct Segment {
  std::size_t begin = 0, end = 0;
  double rate = 0.0;
};

constexpr std::size_t kMinSegmentSamples = 5;
constexpr std::size_t kMaxGroups = 5;

// Half-cycles between reversals of u on [begin, end), each with its mean |du/dt|.
std::vector<Segment> half_cycles(std::span<const double> u, std::span<const double> rate,
                                 std::size_t begin, std::size_t end) {
  std::vector<Segment> out;
  auto close = [&](std::size_t b, std::size_t e) {
    if (e - b < kMinSegmentSamples) return;
    double sum = 0.0;
    for (std::size_t k = b; k < e; ++k) sum += rate[k];
    out.push_back({b, e, sum / static_cast<double>(e - b)});
  };
  int direction = 0;
  std::size_t start = begin;
  for (std::size_t k = std::max<std::size_t>(begin, 1); k < end; ++k) {
    const double du = u[k] - u[k - 1];
    const int s = du > 0.0 ? 1 : (du < 0.0 ? -1 : 0);
    if (s == 0) continue;
    if (direction != 0 && s != direction) {
      close(start, k);
      start = k;
    }
    direction = s;
  }
  close(start, end);
  return out;
}

// Weighted LS line W(rho) = A (1 - rho) + B rho through (rho_g, W_g), with A, B >= eps.
// W(rho) = A + D rho with A >= eps and D >= 0 (the weights grow with rate, as the design's).
std::pair<double, double> rate_line(const std::vector<double>& rho, const std::vector<double>& w,
                                    const std::vector<double>& weight, double eps) {
  Eigen::Matrix2d G = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (std::size_t g = 0; g < rho.size(); ++g) {
    const Eigen::Vector2d a(1.0, rho[g]);
    G.noalias() += weight[g] * a * a.transpose();
    b.noalias() += weight[g] * w[g] * a;
  }
  const Eigen::Vector2d lo(eps, 0.0);
  const Eigen::Vector2d hi = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  const Eigen::VectorXd x = solve_bounded_lsq(G, b, lo, hi).x;
  return {x[0], x[1]};
}

}  // namespace

double half_cycle_rate_spread(std::span<const double> u, double dt, std::size_t begin,
                              std::size_t end) {
  const std::vector<double> rate = sample_rates(u, dt);
  std::vector<Segment> segments = half_cycles(u, rate, begin, end);
  if (segments.size() < 4) return 1.0;
  std::vector<double> r;
  r.reserve(segments.size());
  for (const Segment& s : segments) r.push_back(s.rate);
  std::sort(r.begin(), r.end());
  const double lo = r[r.size() / 10];
  const double hi = r[r.size() - 1 - r.size() / 10];
  return lo > 0.0 ? hi / lo : std::numeric_limits<double>::infinity();
}

std::optional<Eigen::VectorXd> fit_rate_groups(const ModelStructure& structure,
                                               const Eigen::VectorXd& dead_zone_cumulative,
                                               std::span<const double> u, std::span<const double> y,
                                               std::size_t begin, std::size_t end) {
  if (structure.kind != ModelKind::kRateDependentPi || !structure.creep_time_constants.empty()) {
    throw std::invalid_argument("fit_rate_groups needs a rate-dependent structure without creep");
  }
  Design design(structure);
  const Eigen::Index n = design.plays();
  const Eigen::Index dz = design.dead_zone_column();
  const Eigen::Index ndz = design.dead_zone_unknowns();
  if (dead_zone_cumulative.size() != ndz) {
    throw std::invalid_argument("fit_rate_groups: wrong number of dead-zone weights");
  }

  std::vector<double> rate = sample_rates(u, structure.dt, structure.rate_filter_s);
  for (double& v : rate) v = std::min(v, structure.max_rate);  // as the model caps it
  std::vector<Segment> segments = half_cycles(u, rate, begin, end);
  if (segments.size() < 4) return std::nullopt;  // two groups of at least two half-cycles
  std::sort(segments.begin(), segments.end(),
            [](const Segment& a, const Segment& b) { return a.rate < b.rate; });
  const std::size_t groups = std::min(kMaxGroups, segments.size() / 2);
  std::vector<int> group_of(end, -1);
  std::vector<double> group_rate(groups, 0.0), group_rows(groups, 0.0);
  for (std::size_t s = 0; s < segments.size(); ++s) {
    const std::size_t g = s * groups / segments.size();
    for (std::size_t k = segments[s].begin; k < segments[s].end; ++k) {
      group_of[k] = static_cast<int>(g);
      group_rate[g] += rate[k];
      group_rows[g] += 1.0;
    }
  }
  for (std::size_t g = 0; g < groups; ++g) group_rate[g] /= group_rows[g];
  if (!(group_rate.back() > group_rate.front())) return std::nullopt;

  // Per-group fits of the cumulative play weights, dead zones held: one pass over the record.
  std::vector<NormalEquations> per_group(groups, NormalEquations(n + 1));
  Eigen::VectorXd a(design.unknowns());
  design.reset(u[0]);
  for (std::size_t k = 0; k < end; ++k) {
    const double target = design.row(u[k], y[k], a.data());
    if (k < begin || group_of[k] < 0) continue;
    NormalEquations& ne = per_group[static_cast<std::size_t>(group_of[k])];
    double* r = ne.row();
    for (Eigen::Index i = 0; i < n; ++i) r[i] = a[i];  // q_i: the weight's own column
    r[n] = 1.0;
    ne.push(target - a.segment(dz, ndz).dot(dead_zone_cumulative));
  }
  Eigen::VectorXd lo = Eigen::VectorXd::Constant(n + 1, structure.min_play_slope);
  lo[n] = -std::numeric_limits<double>::infinity();
  const Eigen::VectorXd hi =
      Eigen::VectorXd::Constant(n + 1, std::numeric_limits<double>::infinity());
  std::vector<Eigen::VectorXd> W;
  W.reserve(per_group.size());
  for (auto& ne : per_group) W.push_back(solve_bounded_lsq(ne.gram(), ne.rhs(), lo, hi).x);

  // Cumulative weights linear in rate, growing with it, invertible on all of [0, max_rate].
  Eigen::VectorXd x = Eigen::VectorXd::Zero(design.unknowns());
  std::vector<double> rho(groups), wi(groups);
  for (std::size_t g = 0; g < groups; ++g) rho[g] = group_rate[g] / structure.max_rate;
  for (Eigen::Index i = 0; i < n; ++i) {
    for (std::size_t g = 0; g < groups; ++g) wi[g] = W[g][i];
    const auto [A, D] = rate_line(rho, wi, group_rows, structure.min_play_slope);
    x[i] = A;
    x[n + i] = D;
  }
  x.segment(dz, ndz) = dead_zone_cumulative;

  // The offset that goes with these weights: the mean remaining error over the fitted rows.
  double sum = 0.0;
  design.reset(u[0]);
  for (std::size_t k = 0; k < end; ++k) {
    const double target = design.row(u[k], y[k], a.data());
    if (k >= begin) sum += target - a.dot(x);  // x[offset] is still 0
  }
  x[design.offset_column()] = sum / static_cast<double>(end - begin);
  return x;
}

}  // namespace hystbench::compensation::details
