// Relay and play thresholds that widen with the input's rate (ThresholdsRateLaw): the widening,
// the rate filter and the cap searched by the fit's error, for the rate-dependent PI and the
// Preisach plane alike.
#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "details/identifier.hpp"
#include "details/validate.hpp"

namespace hystbench::compensation::details::identification {

namespace {

// The plane's hundreds of cells: its search fits on every kPlaneSearchStride-th row.
constexpr std::size_t kPlaneSearchStride = 4;
// The thresholds law: how far the thresholds widen at the record's largest smooth rate, as
// fractions of the input span (a grid, then a golden-section search on the logarithm between
// the best point's neighbours).
constexpr double kWideningFractions[] = {0.005, 0.01, 0.02, 0.04, 0.08, 0.16};
constexpr int kWideningRefinements = 5;
// Its rate filters, in fit samples: the weight laws' but the longest (its search has the
// widening as one more dimension).
constexpr double kWideningFilterSamples[] = {0.0, 2.0, 5.0};

// Golden section on log(fraction) between the grid neighbours of `fraction` (the grid's ratio
// 2), kWideningRefinements points of f(fraction) -> fit error in all.
template <class F>
void golden_section_on_log(double fraction, F f) {
  const double step = 2.0;
  double lo = std::log(fraction / step), hi = std::log(fraction * step);
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = f(std::exp(x1)), f2 = f(std::exp(x2));
  for (int i = 2; i < kWideningRefinements; ++i) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1;
      x1 = hi - g * (hi - lo);
      f1 = f(std::exp(x1));
    } else {
      lo = x1, x1 = x2, f1 = f2;
      x2 = lo + g * (hi - lo);
      f2 = f(std::exp(x2));
    }
  }
}

}  // namespace

Candidate Identifier::thresholds_law_over(ModelStructure s) {
  s.rate_law = RateLaw::kThresholds;
  // The plane's hundreds of cells: its search fits on every kPlaneSearchStride-th row, the
  // point found then on every row.
  const std::size_t stride = s.kind == ModelKind::kPreisach ? kPlaneSearchStride : 1;
  const double span = r_.u_hi - r_.u_lo;
  if (!(span > 0.0) || !(s.max_rate > 0.0)) return {};
  Candidate best;
  double best_fraction = 0.0, best_filter_s = 0.0, best_cap = 0.0;
  const double smooth_rate = s.max_rate;
  // The record's largest rate through each filter tried, the cap of an uncapped law.
  std::map<double, double> uncapped;
  for (const double samples : kWideningFilterSamples) {
    const std::vector<double> rates = details::sample_rates(r_.ud, r_.dt, samples * r_.dt);
    uncapped[samples * r_.dt] =
        std::max(smooth_rate, *std::max_element(rates.begin(), rates.end()));
  }
  // cap 0: not capped inside the record (an input step's rate holds the switching back until
  // it has decayed, the law's own response to a step); else the rate levels off there.
  struct Point {
    double fraction, filter_s, cap;
  };
  auto law_at = [&](const Point& p) {
    ModelStructure at = s;
    at.rate_filter_s = p.filter_s;
    at.max_rate = p.cap > 0.0 ? p.cap : uncapped.at(p.filter_s);
    at.record_max_rate = std::max(smooth_rate, at.max_rate);
    at.threshold_rate_s = p.fraction * span / smooth_rate;
    return at;
  };
  const std::string method = "constrained-lsq-rate-thresholds";
  auto keep = [&](Candidate c, const Point& p) {
    const double rmse = c.fit.rmse;
    if (!best.model || rmse < best.fit.rmse) {
      best = std::move(c);
      best_fraction = p.fraction;
      best_filter_s = p.filter_s;
      best_cap = p.cap;
    }
    return rmse;
  };
  // Points that do not depend on each other are fitted together (evaluate_each), then kept in
  // their order, as one after another.
  auto try_each = [&](const std::vector<Point>& points) {
    std::vector<ModelStructure> laws;
    laws.reserve(points.size());
    for (const Point& p : points) laws.push_back(law_at(p));
    std::vector<Candidate> fits = evaluate_each(laws, method, stride);
    for (std::size_t i = 0; i < points.size(); ++i) keep(std::move(fits[i]), points[i]);
  };
  auto try_at = [&](double fraction, double filter_s, double cap) {
    const Point p{fraction, filter_s, cap};
    return keep(evaluate(law_at(p), method, stride), p);
  };
  stage_progress(0.0, "thresholds rate law, its widening under each rate filter");
  std::vector<Point> grid;
  for (const double samples : kWideningFilterSamples) {
    for (const double fraction : kWideningFractions)
      grid.push_back({fraction, samples * r_.dt, 0.0});
  }
  try_each(grid);
  // Golden section on log(fraction) between the grid neighbours of the best, at its filter;
  // then where the widening levels off (the weight laws' caps) at the fraction found, and when
  // a cap wins, the section again at that cap.
  const double filter_s = best_filter_s;
  auto refine = [&](double cap) {
    golden_section_on_log(best_fraction, [&](double f) { return try_at(f, filter_s, cap); });
  };
  refine(0.0);
  const double fraction = best_fraction;
  std::vector<Point> caps;
  for (const double cap : kRateCapFractions)
    caps.push_back({fraction, filter_s, cap * smooth_rate});
  try_each(caps);
  if (best_cap > 0.0) refine(best_cap);
  if (stride > 1 && best.model) best = evaluate(best.structure, best.method);
  return best;
}

}  // namespace hystbench::compensation::details::identification
